//! Quadrature, closure / equirect / cube-map projection.

use super::*;
use crate::sh::*;
use glam::Vec3;
use std::f64::consts::PI;

#[test]
fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
    let (x, w) = gauss_legendre(5).unwrap();
    close(w.iter().sum(), 2.0, 1e-14);
    // ∫ x^8 = 2/9 (degree 8 ≤ 9); x^10 is not integrated exactly by 5 nodes.
    close(x.iter().zip(&w).map(|(x, w)| w * x.powi(8)).sum(), 2.0 / 9.0, 1e-14);
    assert!((x.iter().zip(&w).map(|(x, w)| w * x.powi(10)).sum::<f64>() - 2.0 / 11.0).abs() > 1e-4);
    assert!(x.windows(2).all(|p| p[0] < p[1]), "ascending");
    let (x1, w1) = gauss_legendre(1).unwrap();
    assert_eq!((x1[0], w1[0]), (0.0, 2.0));
    assert!(gauss_legendre(0).is_err());
}

#[test]
fn zone_rules_sum_to_the_zone_solid_angle() {
    close(
        Quadrature::sphere(7, 13).unwrap().weights().iter().sum(),
        4.0 * PI,
        1e-12,
    );
    let hemi = Quadrature::zone(0.0, 1.0, 6, 9).unwrap();
    close(hemi.weights().iter().sum(), 2.0 * PI, 1e-12);
    // ∫_{upper hemisphere} z² dω = 2π/3, exact on the zone rule.
    close(hemi.integrate(|d| d.z * d.z), 2.0 * PI / 3.0, 1e-12);
    assert!(Quadrature::zone(0.5, 0.2, 4, 4).is_err());
    assert!(Quadrature::zone(f64::NAN, 1.0, 4, 4).is_err());
    assert!(Quadrature::sphere(4, 0).is_err());
}

#[test]
fn seed000_5_1_constant_function_projects_to_2_sqrt_pi() {
    let c = project_scalar(|_| 1.0, 8).unwrap();
    close(c[0] as f64, 3.5449077, 1e-6);
    close(CONSTANT_ONE_C00, 2.0 * PI.sqrt(), 1e-15);
    assert!(c[1..].iter().all(|v| v.abs() < 1e-6));
}

#[test]
fn closure_projection_recovers_a_band_limited_function() {
    let mut rng = Rng::new(21);
    let f = rng.coeffs(8);
    // f64 rule exact for degree 14: to rounding.
    let c = exact_rule(14).project_scalar(|d| eval_f64(&f, d).unwrap(), 8).unwrap();
    assert!(max_diff(&c, &f) < 1e-12);
    // The f32 RGB front end with its default rule.
    let rgb = project(
        |d| Vec3::splat(eval_f64(&f, d.as_dvec3()).unwrap() as f32) * Vec3::new(1.0, -2.0, 0.5),
        8,
    )
    .unwrap();
    let r: Vec<f64> = rgb.iter().map(|v| v.y as f64 / -2.0).collect();
    assert!(max_diff(&r, &f) < 2e-5);
    // Linearity (the Ca3D-Engine thesis §5.1 test 6): proj(2f + 1) = 2 proj(f) + proj(1).
    let lin = exact_rule(14)
        .project_scalar(|d| 2.0 * eval_f64(&f, d).unwrap() + 1.0, 8)
        .unwrap();
    for (i, v) in lin.iter().enumerate() {
        close(*v, 2.0 * f[i] + if i == 0 { CONSTANT_ONE_C00 } else { 0.0 }, 1e-12);
    }
}

#[test]
fn equirect_texels_follow_penumbra_mapping_and_exact_solid_angles() {
    let (w, h) = (64, 32);
    let total: f64 = (0..h).map(|y| w as f64 * equirect_texel_solid_angle(y, w, h)).sum();
    close(total, 4.0 * PI, 1e-12);
    // scene::Environment::equirect_dir: u = 0.5 is −z, u = 0.75 is +x, v = 0 is +y.
    let d = equirect_texel_dir_world(w / 2, h / 2, w, h); // just below/right of the centre
    assert!(d.z < -0.99, "{d}");
    let d = equirect_texel_dir_world(3 * w / 4, h / 2, w, h);
    assert!(d.x > 0.99, "{d}");
    assert!(equirect_texel_dir_world(0, 0, w, h).y > 0.99);
    // Row y = 0 spans θ ∈ [0, π/h]: Ω = (2π/w)(1 − cos(π/h)).
    close(
        equirect_texel_solid_angle(0, w, h),
        2.0 * PI / w as f64 * (1.0 - (PI / h as f64).cos()),
        1e-15,
    );
}

/// A random 8-band function sampled per texel into RGB (r = f, g = 2f, b = 0).
fn sample(f: &[f64], dirs: impl Iterator<Item = Vec3>) -> Vec<[f32; 3]> {
    dirs.map(|d| {
        let v = eval_f64(f, world_to_sh(d).as_dvec3()).unwrap() as f32;
        [v, 2.0 * v, 0.0]
    })
    .collect()
}

#[test]
fn equirect_round_trip_recovers_coefficients_to_1e3() {
    let mut rng = Rng::new(8);
    let f = rng.coeffs(8);
    let (w, h) = (256, 128);
    let px = sample(&f, (0..w * h).map(|i| equirect_texel_dir_world(i % w, i / w, w, h)));
    let c = project_equirect(&px, w, h, 8).unwrap();
    let r: Vec<f64> = c.iter().map(|v| v.x as f64).collect();
    let g: Vec<f64> = c.iter().map(|v| v.y as f64 / 2.0).collect();
    assert!(max_diff(&r, &f) < 1e-3, "{}", max_diff(&r, &f));
    assert!(max_diff(&g, &f) < 1e-3);
    assert!(c.iter().all(|v| v.z == 0.0));
    assert!(project_equirect(&px, w, h + 1, 8).is_err());
    assert!(project_equirect(&[], 0, 0, 8).is_err());
}

#[test]
fn cube_texels_follow_the_vulkan_face_table_and_sum_to_4pi() {
    let n = 16;
    let face: f64 = (0..n * n).map(|i| cube_texel_solid_angle(i % n, i / n, n)).sum();
    close(face, 4.0 * PI / 6.0, 1e-12);
    // One texel covering a whole face: 4π/6 exactly.
    close(cube_texel_solid_angle(0, 0, 1), 4.0 * PI / 6.0, 1e-12);
    // Face centres are the axes in layer order +X, −X, +Y, −Y, +Z, −Z.
    let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    for (f, a) in axes.iter().enumerate() {
        assert_eq!(cube_texel_dir_world(f, 0, 0, 1), *a);
    }
    // Texel (0, 0) (s = t = 0) of +X is toward +y, +z; of +Y toward −x, −z; of +Z toward −x, +y.
    let c = cube_texel_dir_world(0, 0, 0, n);
    assert!(c.y > 0.9 && c.z > 0.9);
    let c = cube_texel_dir_world(2, 0, 0, n);
    assert!(c.x < -0.9 && c.z < -0.9);
    let c = cube_texel_dir_world(4, 0, 0, n);
    assert!(c.x < -0.9 && c.y > 0.9);
    // Small texel: Ω ≈ area·cos/r² = (2/n)²/r³ at its centre.
    let d = cube_texel_dir_world(0, 3, 11, 256).as_dvec3();
    close(
        cube_texel_solid_angle(3, 11, 256),
        (2.0 / 256.0f64).powi(2) / d.length().powi(3),
        1e-9,
    );
}

#[test]
fn cubemap_round_trip_recovers_coefficients_to_1e3() {
    let mut rng = Rng::new(9);
    let f = rng.coeffs(8);
    let n = 64;
    let px = sample(
        &f,
        (0..6 * n * n).map(|i| cube_texel_dir_world(i / (n * n), i % n, (i % (n * n)) / n, n)),
    );
    let c = project_cubemap(&px, n, 8).unwrap();
    let r: Vec<f64> = c.iter().map(|v| v.x as f64).collect();
    assert!(max_diff(&r, &f) < 1e-3, "{}", max_diff(&r, &f));
    assert!(project_cubemap(&px[1..], n, 8).is_err());
    assert!(project_cubemap(&px, n, 0).is_err());
}
