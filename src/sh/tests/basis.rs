//! Basis constants, orthonormality, frames and reconstruction.

use super::*;
use crate::sh::*;
use glam::Vec3;

/// The textbook definition (the height-field thesis Eq. 3.9–3.12 and 3.19–3.20, the Ca3D-Engine thesis §5.1.1): unnormalised
/// P_l^m with the Condon–Shortley phase by the classic recurrence, factorial K_l^m, trig in φ.
/// An implementation independent of the normalised recurrence in `basis.rs`.
fn textbook(l: usize, m: i32, theta: f64, phi: f64) -> f64 {
    let am = m.unsigned_abs() as usize;
    let x = theta.cos();
    let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
    let dfact = |n: i64| (1..=n).rev().step_by(2).map(|k| k as f64).product::<f64>();
    let mut pmm = if am % 2 == 1 { -1.0 } else { 1.0 } * dfact(2 * am as i64 - 1) * (1.0 - x * x).powf(am as f64 / 2.0);
    let p = if l == am {
        pmm
    } else {
        let mut pmm1 = x * (2 * am + 1) as f64 * pmm;
        for ll in am + 2..=l {
            let next = (x * (2 * ll - 1) as f64 * pmm1 - (ll + am - 1) as f64 * pmm) / (ll - am) as f64;
            pmm = pmm1;
            pmm1 = next;
        }
        pmm1
    };
    let k = ((2 * l + 1) as f64 * fact(l - am) / (4.0 * std::f64::consts::PI * fact(l + am))).sqrt();
    match m {
        0 => k * p,
        m if m > 0 => std::f64::consts::SQRT_2 * k * (m as f64 * phi).cos() * p,
        _ => std::f64::consts::SQRT_2 * k * (am as f64 * phi).sin() * p,
    }
}

fn eval_all(d: DVec3, bands: usize) -> Vec<f64> {
    let mut y = vec![0.0; bands * bands];
    eval_basis_f64(d, bands, &mut y).unwrap();
    y
}

#[test]
fn seed000_5_1_y00_and_band1_constants_with_condon_shortley_signs() {
    let d = DVec3::new(0.3, -0.5, 0.7).normalize();
    let y = eval_all(d, 2);
    close(y[0], 0.282095, 1e-6);
    close(Y00, 1.0 / (2.0 * std::f64::consts::PI.sqrt()), 1e-15);
    // y_1^{-1} = −0.488603·y, y_1^0 = +0.488603·z, y_1^1 = −0.488603·x (the Ca3D-Engine thesis §5.1 test 1).
    close(y[1], -0.488603 * d.y, 1e-6);
    close(y[2], 0.488603 * d.z, 1e-6);
    close(y[3], -0.488603 * d.x, 1e-6);
}

#[test]
fn seed000_5_1_scale_factors_and_recurrence_match_textbook_definition() {
    // the Ca3D-Engine thesis §5.1 test 1: K_l^0 and √2·K_l^m for l ≤ 3, as the factor in front of P_l^m·trig.
    let table: [&[f64]; 4] = [
        &[0.282095],
        &[0.488603, 0.488603],
        &[0.630783, 0.364183, 0.182091],
        &[0.746353, 0.304697, 0.096354, 0.039336],
    ];
    let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
    for (l, row) in table.iter().enumerate() {
        for (m, expected) in row.iter().enumerate() {
            let k = ((2 * l + 1) as f64 * fact(l - m) / (4.0 * std::f64::consts::PI * fact(l + m))).sqrt();
            close(if m == 0 { k } else { std::f64::consts::SQRT_2 * k }, *expected, 1e-6);
        }
    }
    // The normalised recurrence equals the textbook formula for all 16 bands (l = 15 has
    // (2l−1)!! ≈ 6e15 and K ≈ 1e−16 in the textbook route: relative agreement 1e−9).
    let mut rng = Rng::new(7);
    for _ in 0..20 {
        let d = rng.dir();
        let (theta, phi) = (d.z.acos(), d.y.atan2(d.x));
        let y = eval_all(d, MAX_BANDS);
        for (i, yi) in y.iter().enumerate() {
            let (l, m) = band_of(i);
            let t = textbook(l, m, theta, phi);
            assert!((yi - t).abs() <= 1e-9 * (1.0 + t.abs()), "l={l} m={m}: {yi} vs {t}");
        }
    }
}

#[test]
fn seed002_appendix_a_cartesian_polynomials_l_le_3() {
    // Staniszewski 2005 appendix A (unsigned) with the Condon–Shortley signs of the Ca3D-Engine thesis §5.1 test 1:
    // odd-m functions carry −1.
    let mut rng = Rng::new(3);
    for _ in 0..50 {
        let d = rng.dir();
        let (x, y, z) = (d.x, d.y, d.z);
        let expected = [
            0.282095,
            -0.488603 * y,
            0.488603 * z,
            -0.488603 * x,
            1.092548 * x * y,
            -1.092548 * y * z,
            0.315392 * (3.0 * z * z - 1.0),
            -1.092548 * x * z,
            0.546274 * (x * x - y * y),
            -0.590044 * y * (3.0 * x * x - y * y),
            2.890611 * x * y * z,
            -0.457046 * y * (5.0 * z * z - 1.0),
            0.373176 * z * (5.0 * z * z - 3.0),
            -0.457046 * x * (5.0 * z * z - 1.0),
            1.445306 * z * (x * x - y * y),
            -0.590044 * x * (x * x - 3.0 * y * y),
        ];
        // The printed constants have 6 decimals: agreement to 4e−6 after multiplication.
        assert!(max_diff(&eval_all(d, 4), &expected) < 4e-6);
    }
}

#[test]
fn seed001_a1_orthonormality_gram_matrix() {
    // f64, 16 bands, exact rule for degree 30: |G − I| < 1e−12 (the height-field thesis §7 A1).
    let q = exact_rule(30);
    let n = MAX_BANDS * MAX_BANDS;
    let mut g = vec![0.0; n * n];
    let mut y = vec![0.0; n];
    for (d, w) in q.dirs().iter().zip(q.weights()) {
        eval_basis_f64(*d, MAX_BANDS, &mut y).unwrap();
        for i in 0..n {
            for j in i..n {
                g[i * n + j] += w * y[i] * y[j];
            }
        }
    }
    let err = (0..n)
        .flat_map(|i| (i..n).map(move |j| (i, j)))
        .map(|(i, j)| (g[i * n + j] - if i == j { 1.0 } else { 0.0 }).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-12, "f64 Gram error {err:e}");

    // The f32 path (what the GPU and `eval_basis` give), 8 bands: 1e−5.
    let q = exact_rule(14);
    let n = 64;
    let mut g = vec![0.0f64; n * n];
    let mut y = vec![0.0f32; n];
    for (d, w) in q.dirs().iter().zip(q.weights()) {
        eval_basis(d.as_vec3(), 8, &mut y).unwrap();
        for i in 0..n {
            for j in 0..n {
                g[i * n + j] += w * y[i] as f64 * y[j] as f64;
            }
        }
    }
    let err = (0..n * n)
        .map(|k| (g[k] - if k / n == k % n { 1.0 } else { 0.0 }).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-5, "f32 Gram error {err:e}");
}

#[test]
fn directions_are_normalised_and_degenerate_ones_are_plus_z() {
    let a = basis(Vec3::new(0.0, 3.0, 4.0), 5).unwrap();
    let b = basis(Vec3::new(0.0, 0.6, 0.8), 5).unwrap();
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6));
    let z = basis(Vec3::Z, 5).unwrap();
    for bad in [Vec3::ZERO, Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 0.0)] {
        assert_eq!(basis(bad, 5).unwrap(), z);
    }
    // At the pole only m = 0 survives: y_l0(+z) = √((2l+1)/4π).
    for l in 0..5 {
        close(
            z[l * (l + 1)] as f64,
            ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI)).sqrt(),
            1e-6,
        );
    }
    assert_eq!(z.iter().filter(|v| **v != 0.0).count(), 5);
}

#[test]
fn bad_band_counts_and_lengths_are_errors() {
    let mut out = [0.0f32; 16];
    assert_eq!(eval_basis(Vec3::Z, 0, &mut out), Err(ShError::Bands(0)));
    assert_eq!(eval_basis(Vec3::Z, 17, &mut out), Err(ShError::Bands(17)));
    assert!(matches!(
        eval_basis(Vec3::Z, 5, &mut out),
        Err(ShError::Length {
            expected: 25,
            got: 16,
            ..
        })
    ));
    assert!(eval(&[1.0f32; 5], Vec3::Z).is_err());
    assert!(dot(&[1.0f32; 4], &[1.0f32; 3]).is_err());
    assert_eq!(bands_of_len(257), Err(ShError::NotBands(257)));
    assert_eq!(bands_of_len(289), Err(ShError::NotBands(289))); // 17 bands: too many
    assert_eq!(bands_of_len(256), Ok(16));
}

#[test]
fn index_and_band_of_round_trip() {
    assert_eq!(index(3, -2), 10);
    assert_eq!(index(2, 0), 6);
    assert_eq!(index(1, 5), 3); // m clamped to l
    for i in 0..MAX_BANDS * MAX_BANDS {
        let (l, m) = band_of(i);
        assert!(m.unsigned_abs() as usize <= l);
        assert_eq!(index(l, m), i);
    }
}

#[test]
fn world_frame_maps_y_up_to_sh_z_by_a_proper_rotation() {
    assert_eq!(world_to_sh(Vec3::Y), Vec3::Z);
    assert_eq!(world_to_sh(Vec3::X), Vec3::X);
    assert_eq!(world_to_sh(Vec3::NEG_Z), Vec3::Y);
    assert_eq!(WORLD_TO_SH.determinant(), 1.0);
    assert_eq!(WORLD_TO_SH * SH_TO_WORLD, Mat3::IDENTITY);
    let mut rng = Rng::new(11);
    for _ in 0..10 {
        let d = rng.dir().as_vec3();
        assert!((WORLD_TO_SH * d - world_to_sh(d)).length() < 1e-7);
        assert!((sh_to_world(world_to_sh(d)) - d).length() < 1e-7);
        assert!((SH_TO_WORLD * d - sh_to_world(d)).length() < 1e-7);
    }
}

#[test]
fn reconstruction_and_dot_are_the_function_and_its_integral() {
    let mut rng = Rng::new(5);
    let (a, b) = (rng.coeffs(5), rng.coeffs(3));
    let d = rng.dir();
    // eval = Σ c_i y_i(d), generic path (f32/Vec3) agrees with f64.
    let direct: f64 = a.iter().zip(eval_all(d, 5)).map(|(c, y)| c * y).sum();
    close(eval_f64(&a, d).unwrap(), direct, 1e-12);
    let a32: Vec<f32> = a.iter().map(|v| *v as f32).collect();
    close(eval(&a32, d.as_vec3()).unwrap() as f64, direct, 1e-5);
    let rgb: Vec<Vec3> = a.iter().map(|v| Vec3::new(*v as f32, 2.0 * *v as f32, 0.0)).collect();
    close(eval(&rgb, d.as_vec3()).unwrap().y as f64, 2.0 * direct, 2e-5);
    // dot = ∫ f g dω, with different band counts (the missing bands are zero).
    let integral = exact_rule(10).integrate(|w| eval_f64(&a, w).unwrap() * eval_f64(&b, w).unwrap());
    close(dot(&a, &b).unwrap(), integral, 1e-12);
    close(dot(&b, &a).unwrap(), integral, 1e-12);
}
