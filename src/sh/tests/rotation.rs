//! z-rotation, ZH rotation and general rotation against brute-force reprojection.

use super::*;
use crate::sh::*;
use glam::{DMat3, Vec3};
use std::f64::consts::PI;

fn band_energy(c: &[f64], l: usize) -> f64 {
    c[l * l..(l + 1) * (l + 1)].iter().map(|v| v * v).sum()
}

#[test]
fn z_rotation_matches_brute_force_reprojection() {
    let mut rng = Rng::new(31);
    let f = rng.coeffs(6);
    let alpha = 0.7;
    let mut g = f.clone();
    rotate_z(&mut g, alpha).unwrap();
    let expected = reproject_rotated(&f, DMat3::from_rotation_z(alpha), 6);
    assert!(max_diff(&g, &expected) < 1e-12, "{}", max_diff(&g, &expected));
    // A lobe at +x rotated by +90° points at +y (counter-clockwise seen from +z).
    let mut lobe = zh_rotate(&clamped_cosine_zh(3).unwrap(), Vec3::X).unwrap();
    rotate_z(&mut lobe, PI / 2.0).unwrap();
    close(
        eval_f64(&lobe, DVec3::Y).unwrap(),
        eval_zonal(&clamped_cosine_zh(3).unwrap(), 1.0),
        1e-12,
    );
}

#[test]
fn seed001_a4_z_rotations_compose_and_a_full_turn_is_identity() {
    let mut rng = Rng::new(32);
    let f = rng.coeffs(8);
    let (mut ab, mut sum) = (f.clone(), f.clone());
    rotate_z(&mut ab, 0.4).unwrap();
    rotate_z(&mut ab, 1.1).unwrap();
    rotate_z(&mut sum, 1.5).unwrap();
    assert!(max_diff(&ab, &sum) < 1e-13);
    let mut full = f.clone();
    rotate_z(&mut full, 2.0 * PI).unwrap();
    assert!(max_diff(&full, &f) < 1e-13);
    // the height-field thesis §1.6 formula on one pair: c'_{1,1} = c_11 cos α − c_{1,−1} sin α.
    let mut c = vec![0.0, 0.25, 0.0, 1.0];
    rotate_z(&mut c, 0.3).unwrap();
    close(c[3], 0.3f64.cos() - 0.25 * 0.3f64.sin(), 1e-15);
    close(c[1], 0.3f64.sin() + 0.25 * 0.3f64.cos(), 1e-15);
    assert!(rotate_z(&mut c, f64::NAN).is_err());
    assert!(rotate_z(&mut [0.0f32; 3], 1.0).is_err());
}

#[test]
fn general_rotation_matches_brute_force_reprojection() {
    let mut rng = Rng::new(33);
    for _ in 0..3 {
        let r = rng.rotation();
        let f = rng.coeffs(8);
        let g = ShRotation::new(r, 8).unwrap().rotate(&f).unwrap();
        let expected = reproject_rotated(&f, r.as_dmat3(), 8);
        // r is f32; re-orthonormalised in f64, it differs from r.as_dmat3() by ~1e−7.
        assert!(max_diff(&g, &expected) < 1e-5, "{}", max_diff(&g, &expected));
    }
    // With an exactly representable rotation (90° about x: y → z) the agreement is to rounding.
    let r = Mat3::from_cols(Vec3::X, Vec3::Z, Vec3::NEG_Y);
    let f = rng.coeffs(8);
    let g = ShRotation::new(r, 8).unwrap().rotate(&f).unwrap();
    assert!(max_diff(&g, &reproject_rotated(&f, r.as_dmat3(), 8)) < 1e-12);
}

#[test]
fn general_rotation_preserves_band_energy_and_inverse_undoes_it() {
    let mut rng = Rng::new(34);
    let r = rng.rotation();
    let f = rng.coeffs(MAX_BANDS);
    let rot = ShRotation::new(r, MAX_BANDS).unwrap();
    let g = rot.rotate(&f).unwrap();
    for l in 0..MAX_BANDS {
        close(
            band_energy(&g, l),
            band_energy(&f, l),
            1e-10 * band_energy(&f, l).max(1.0),
        );
    }
    let back = ShRotation::new(r.transpose(), MAX_BANDS).unwrap().rotate(&g).unwrap();
    assert!(max_diff(&back, &f) < 1e-6, "{}", max_diff(&back, &f)); // f32 input matrix
                                                                    // Blocks are orthogonal to rounding at band 15.
    let b = rot.band_matrix(15).unwrap();
    let w = 31;
    for i in 0..w {
        for j in 0..w {
            let d: f64 = (0..w).map(|k| b[k * w + i] * b[k * w + j]).sum();
            close(d, if i == j { 1.0 } else { 0.0 }, 1e-12);
        }
    }
    // Composition: rot(R2)·rot(R1) = rot(R2 R1).
    let r2 = rng.rotation();
    let two = ShRotation::new(r2, 6)
        .unwrap()
        .rotate(&ShRotation::new(r, 6).unwrap().rotate(&f[..36]).unwrap())
        .unwrap();
    let one = ShRotation::new(r2 * r, 6).unwrap().rotate(&f[..36]).unwrap();
    assert!(max_diff(&two, &one) < 1e-5);
}

#[test]
fn z_rotation_equals_general_rotation_about_z() {
    let mut rng = Rng::new(35);
    let f = rng.coeffs(8);
    let mut z = f.clone();
    rotate_z(&mut z, 2.3).unwrap();
    let g = ShRotation::new(Mat3::from_rotation_z(2.3), 8)
        .unwrap()
        .rotate(&f)
        .unwrap();
    assert!(max_diff(&z, &g) < 1e-6, "{}", max_diff(&z, &g));
}

#[test]
fn seed001_a3_zh_rotation_equals_general_rotation_of_the_zonal_function() {
    let mut rng = Rng::new(36);
    let zh = cap_zh(0.8, 8).unwrap();
    // To +z: identity (the m = 0 slots hold z_l, all else 0).
    let up = zh_rotate(&zh, Vec3::Z).unwrap();
    for (i, v) in up.iter().enumerate() {
        let (l, m) = band_of(i);
        close(*v, if m == 0 { zh[l] } else { 0.0 }, 1e-14);
    }
    for _ in 0..3 {
        let axis = rng.dir().as_vec3();
        let fast = zh_rotate(&zh, axis).unwrap();
        // Band norms: ‖c_l‖ = |z_l| (the height-field thesis §7 A3).
        for (l, z) in zh.iter().enumerate() {
            close(band_energy(&fast, l).sqrt(), z.abs(), 1e-6);
        }
        let r = rotation_z_to(axis);
        assert!((r * Vec3::Z - axis).length() < 1e-6);
        let slow = ShRotation::new(r, 8).unwrap().rotate(&up).unwrap();
        assert!(max_diff(&fast, &slow) < 1e-5, "{}", max_diff(&fast, &slow));
        // And the rotated function peaks where it should: the cap's value at its axis.
        close(eval_f64(&fast, axis.as_dvec3()).unwrap(), eval_zonal(&zh, 1.0), 1e-5);
    }
    // −z uses the 180° fallback of `rotation_z_to`.
    assert!((rotation_z_to(Vec3::NEG_Z) * Vec3::Z - Vec3::NEG_Z).length() < 1e-7);
    assert!(zh_rotate::<f64>(&[], Vec3::Z).is_err());
}

#[test]
fn world_rotations_move_world_lobes_where_expected() {
    // A lobe toward world +x, rotated by 90° about world +y (x → −z), points at world −z.
    let zh = clamped_cosine_zh(4).unwrap();
    let lobe = zh_rotate(&zh, world_to_sh(Vec3::X)).unwrap();
    let rw = Mat3::from_rotation_y(PI as f32 / 2.0);
    let rotated = ShRotation::from_world(rw, 4).unwrap().rotate(&lobe).unwrap();
    let expected = zh_rotate(&zh, world_to_sh(rw * Vec3::X)).unwrap();
    assert!(max_diff(&rotated, &expected) < 1e-6);
    close(
        eval_f64(&rotated, world_to_sh(Vec3::NEG_Z).as_dvec3()).unwrap(),
        eval_zonal(&zh, 1.0),
        1e-6,
    );
}

#[test]
fn non_rotations_are_rejected() {
    assert!(matches!(
        ShRotation::new(Mat3::from_diagonal(Vec3::splat(2.0)), 4),
        Err(ShError::NotRotation { .. })
    ));
    assert!(matches!(
        ShRotation::new(Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0)), 4),
        Err(ShError::NotRotation { .. })
    ));
    assert!(matches!(
        ShRotation::new(Mat3::from_diagonal(Vec3::new(f32::NAN, 1.0, 1.0)), 4),
        Err(ShError::NonFinite(_))
    ));
    let rot = ShRotation::new(Mat3::IDENTITY, 3).unwrap();
    assert!(rot.rotate(&[0.0f32; 16]).is_err()); // more bands than the rotation has
    assert!(rot.apply(&[0.0f32; 4], &mut [0.0f32; 9]).is_err());
    assert_eq!(rot.rotate(&[1.0f32, 2.0, 3.0, 4.0]).unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
}
