//! Clamped cosine, caps, hemisphere, convolution / irradiance.

use super::*;
use crate::sh::*;
use glam::Vec3;
use std::f64::consts::PI;

#[test]
fn seed000_5_1_clamped_cosine_zh_l0_to_l7() {
    let z = clamped_cosine_zh(8).unwrap();
    let expected = [0.886227, 1.023327, 0.495416, 0.0, -0.110778, 0.0, 0.049927, 0.0];
    assert!(max_diff(&z, &expected) < 1e-6, "{z:?}");
    // Closed forms √π/2, √(π/3), √(5π)/8, −√π/16, √(13π)/128.
    close(z[0], PI.sqrt() / 2.0, 1e-15);
    close(z[1], (PI / 3.0).sqrt(), 1e-15);
    close(z[2], (5.0 * PI).sqrt() / 8.0, 1e-15);
    close(z[4], -PI.sqrt() / 16.0, 1e-15);
    close(z[6], (13.0 * PI).sqrt() / 128.0, 1e-15);
    // Numerical integration, two independent ways, 16 bands: the zonal GL projection of x on
    // [0, 1] and the sphere-zone rule projecting max(z, 0) (both exact: polynomials on [0, 1]).
    let zz = clamped_cosine_zh(16).unwrap();
    assert!(max_diff(&zz, &project_zonal(|x| x, 16, 0.0, 1.0, 16).unwrap()) < 1e-13);
    let full = Quadrature::zone(0.0, 1.0, 16, 33)
        .unwrap()
        .project_scalar(|d| d.z, 16)
        .unwrap();
    let m0: Vec<f64> = (0..16).map(|l| full[l * (l + 1)]).collect();
    assert!(max_diff(&zz, &m0) < 1e-13);
    assert!(full
        .iter()
        .enumerate()
        .filter(|(i, _)| band_of(*i).1 != 0)
        .all(|(_, v)| v.abs() < 1e-13));
}

#[test]
fn seed002_5_lambert_kernel_is_pi_2pi3_pi4_0_minus_pi24() {
    let a = lambert_kernel(8).unwrap();
    let expected = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0, 0.0, PI / 64.0, 0.0];
    assert!(max_diff(&a, &expected) < 1e-14, "{a:?}");
}

#[test]
fn seed001_a5_truncated_clamped_cosine_is_1_0625_at_the_normal_and_0_09375_at_90_degrees() {
    let z = clamped_cosine_zh(4).unwrap();
    close(eval_zonal(&z, 1.0), 1.0625, 1e-14);
    close(eval_zonal(&z, 0.0), 0.09375, 1e-14);
    // the height-field thesis §3.2 item 2: −0.039 at 120°, 0.0625 at 180°.
    close(eval_zonal(&z, -0.5), -0.0390625, 1e-14);
    close(eval_zonal(&z, -1.0), 0.0625, 1e-14);
}

#[test]
fn seed000_5_2_d_directional_light_golden_values() {
    // (1/π) Σ_l c_l y_l0(cos) for cos = 1, 0.5, 0, −0.5, −1 at n = 2, 4, 6, 8 bands.
    let table: [(usize, [f64; 5]); 4] = [
        (2, [0.2387, 0.1592, 0.0796, 0.0000, -0.0796]),
        (4, [0.3382, 0.1467, 0.0298, -0.0124, 0.0199]),
        (6, [0.3084, 0.1553, 0.0187, -0.0038, -0.0099]),
        (8, [0.3245, 0.1606, 0.0136, 0.0014, 0.0062]),
    ];
    for (bands, row) in table {
        let z = clamped_cosine_zh(bands).unwrap();
        for (c, expected) in [1.0, 0.5, 0.0, -0.5, -1.0].iter().zip(row) {
            close(eval_zonal(&z, *c) / PI, expected, 5e-5);
        }
    }
    // n = 3 equals n = 4 (the l = 3 coefficient is 0).
    close(
        eval_zonal(&clamped_cosine_zh(3).unwrap(), 0.5),
        eval_zonal(&clamped_cosine_zh(4).unwrap(), 0.5),
        1e-15,
    );
}

#[test]
fn seed001_a6_cap_zh_table() {
    let table: [(f64, [f64; 4]); 5] = [
        (0.1, [0.008855, 0.015299, 0.019652, 0.023078]),
        (0.5, [0.216979, 0.352816, 0.399724, 0.384093]),
        (1.0, [0.814793, 1.086886, 0.758132, 0.190776]),
        (PI / 2.0, [1.772454, 1.534990, 0.0, -0.586184]),
        (2.0, [2.510055, 1.269163, -0.681849, -0.064999]),
    ];
    for (theta, row) in table {
        assert!(max_diff(&cap_zh(theta, 4).unwrap(), &row) < 1e-6, "θ = {theta}");
        // The height-field thesis Appendix A.1 forms (digest §1.8).
        let (c, s) = (theta.cos(), theta.sin());
        let appendix = [
            PI.sqrt() * (1.0 - c),
            (3.0 * PI).sqrt() / 2.0 * s * s,
            (5.0 * PI).sqrt() / 2.0 * c * s * s,
            (7.0 * PI).sqrt() / 8.0 * s * s * (5.0 * c * c - 1.0),
        ];
        assert!(max_diff(&cap_zh(theta, 4).unwrap(), &appendix) < 1e-14);
    }
}

#[test]
fn cap_closed_form_matches_numerical_integration_to_16_bands() {
    for alpha in [0.05, 0.4, 1.3, 2.2, 3.0] {
        let closed = cap_zh(alpha, 16).unwrap();
        // Exact zone rule over the cap (indicator = 1 there).
        let zone = Quadrature::zone(alpha.cos(), 1.0, 12, 33)
            .unwrap()
            .project_scalar(|_| 1.0, 16)
            .unwrap();
        let m0: Vec<f64> = (0..16).map(|l| zone[l * (l + 1)]).collect();
        assert!(max_diff(&closed, &m0) < 1e-13, "α = {alpha}");
        // And a crude independent check: midpoint rule in θ with the indicator on the whole sphere.
        let n = 20000;
        let mut crude = [0.0f64; 4];
        for i in 0..n {
            let t = PI * (i as f64 + 0.5) / n as f64;
            if t < alpha {
                let p = legendre(3, t.cos());
                for (l, c) in crude.iter_mut().enumerate() {
                    *c += 2.0 * PI * ((2 * l + 1) as f64 / (4.0 * PI)).sqrt() * p[l] * t.sin() * PI / n as f64;
                }
            }
        }
        assert!(max_diff(&closed[..4], &crude) < 1e-3, "α = {alpha}");
    }
}

#[test]
fn cap_of_90_degrees_is_the_hemisphere_and_c00_gives_the_solid_angle() {
    let hemi = hemisphere_zh(8).unwrap();
    assert_eq!(cap_zh(PI / 2.0, 8).unwrap(), hemi);
    // the Ca3D-Engine thesis §5.1 test 5.
    let expected = [1.772454, 1.534990, 0.0, -0.586184, 0.0, 0.367410, 0.0, -0.268152];
    assert!(max_diff(&hemi, &expected) < 1e-6, "{hemi:?}");
    for alpha in [0.0, 0.3, 1.0, PI / 2.0, 2.5, PI] {
        // ∫ cap = z_0 ∫ y00 = z_0·4π·Y00: the solid angle 2π(1 − cos α).
        close(
            cap_zh(alpha, 4).unwrap()[0] * 4.0 * PI * Y00,
            2.0 * PI * (1.0 - alpha.cos()),
            1e-13,
        );
    }
    // Whole sphere: only band 0, 2√π (the height-field thesis §7 A6 limit); beyond π clamps.
    let all = cap_zh(PI, 6).unwrap();
    close(all[0], CONSTANT_ONE_C00, 1e-14);
    assert!(all[1..].iter().all(|v| v.abs() < 1e-14));
    assert_eq!(cap_zh(4.0, 6).unwrap(), all);
    assert_eq!(cap_zh(-1.0, 3).unwrap(), vec![0.0; 3]);
    assert!(cap_zh(f64::NAN, 3).is_err());
}

#[test]
fn seed002_5_uniform_sky_gives_pi_and_aligned_cosine_light_gives_127pi_over_192() {
    // Test 2: unit radiance (L00 = 2√π) against the unoccluded transfer (clamped cosine).
    let t = zh_rotate(&clamped_cosine_zh(4).unwrap(), Vec3::new(0.3, -0.2, 0.9)).unwrap();
    let mut l = vec![0.0; 16];
    l[0] = CONSTANT_ONE_C00;
    close(dot(&t, &l).unwrap(), PI, 1e-13);
    // Test 3: light = max(0, ω·d), n = d: Σ z_l² = 127π/192 = 2.07803 at l ≤ 3.
    close(dot(&t, &t).unwrap(), 127.0 * PI / 192.0, 1e-13);
    close(127.0 * PI / 192.0, 2.07803, 1e-5);
}

#[test]
fn seed002_5_disk_occluder_transfer_t00_t10() {
    // Test 4: opaque disk of angular radius α about the normal: visible = α < θ < π/2, so
    // T_l = 2π N_l ∫_0^{cos α} x P_l(x) dx; T00 = 0.886227 cos²α, T10 = 1.023327 cos³α.
    for (deg, t00, t10) in [
        (30.0f64, 0.66467, 0.66467),
        (45.0, 0.44311, 0.36180),
        (60.0, 0.22156, 0.12792),
    ] {
        let a = deg.to_radians();
        let t = project_zonal(|x| x, 2, 0.0, a.cos(), 8).unwrap();
        close(t[0], t00, 1e-5);
        close(t[1], t10, 1e-5);
    }
}

#[test]
fn irradiance_convolution_matches_the_cosine_integral_of_the_radiance() {
    let mut rng = Rng::new(41);
    let radiance = rng.coeffs(5);
    let e = irradiance(&radiance).unwrap();
    let hemi = Quadrature::zone(0.0, 1.0, 8, 17).unwrap();
    for _ in 0..4 {
        let n = rng.dir();
        let r = rotation_z_to(n.as_vec3()).as_dmat3();
        // E(n) = ∫_{n·ω>0} L(ω) (n·ω) dω, exactly (polynomial integrand on the hemisphere).
        let exact = hemi.integrate(|w| eval_f64(&radiance, r * w).unwrap() * w.z);
        close(eval_f64(&e, n).unwrap(), exact, 1e-6); // f32 rotation matrix
    }
    // convolve = per band √(4π/(2l+1)) k_l; a kernel shorter than the coefficients is an error.
    let mut c = vec![1.0f32; 9];
    assert!(convolve(&mut c, &[1.0, 1.0]).is_err());
    convolve(&mut c, &clamped_cosine_zh(3).unwrap()).unwrap();
    close(c[0] as f64, PI, 1e-6);
    close(c[5] as f64, PI / 4.0, 1e-6);
}

#[test]
fn seed000_5_1_zonal_dot_is_sum_of_products_times_legendre() {
    // ⟨f, g⟩ = Σ f_l g_l P_l(u·v) for zonal f about u and g about v (test 7).
    let mut rng = Rng::new(42);
    let (u, v) = (rng.dir(), rng.dir());
    let f = cap_zh(0.7, 8).unwrap();
    let g = clamped_cosine_zh(8).unwrap();
    let lhs = dot(
        &zh_rotate(&f, u.as_vec3()).unwrap(),
        &zh_rotate(&g, v.as_vec3()).unwrap(),
    )
    .unwrap();
    let p = legendre(7, u.dot(v));
    let rhs: f64 = (0..8).map(|l| f[l] * g[l] * p[l]).sum();
    close(lhs, rhs, 1e-6);
}
