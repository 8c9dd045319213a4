//! The triple-product tensor, products and product matrices.

use super::*;
use crate::sh::*;
use glam::Vec3;
use std::f64::consts::PI;

#[test]
fn gamma_matches_brute_force_quadrature_for_4_bands() {
    let t = TripleProductTensor::new(4).unwrap();
    let q = exact_rule(9);
    let mut y = vec![0.0; 16];
    let mut brute = vec![0.0; 16 * 16 * 16];
    for (d, w) in q.dirs().iter().zip(q.weights()) {
        eval_basis_f64(*d, 4, &mut y).unwrap();
        for i in 0..16 {
            for j in 0..16 {
                for k in 0..16 {
                    brute[(i * 16 + j) * 16 + k] += w * y[i] * y[j] * y[k];
                }
            }
        }
    }
    let mut nonzero = 0;
    for i in 0..16 {
        for j in 0..16 {
            for k in 0..16 {
                let b = brute[(i * 16 + j) * 16 + k];
                close(t.get(i, j, k), if b.abs() > 1e-7 { b } else { 0.0 }, 1e-13);
                nonzero += usize::from(b.abs() > 1e-7);
            }
        }
    }
    assert_eq!(nonzero, t.len());
    // Γ_000 = Y00, Γ_0jk = Y00 δ_jk, and e.g. Γ_{(1,0)(1,0)(2,0)} = 1/√(5π).
    close(t.get(0, 0, 0), Y00, 1e-15);
    close(t.get(2, 2, 6), 1.0 / (5.0 * PI).sqrt(), 1e-14);
    assert_eq!(t.get(1, 2, 3), 0.0);
}

#[test]
fn seed001_a2_gamma_is_symmetric_and_the_constant_function_is_the_identity() {
    let t = TripleProductTensor::new(8).unwrap();
    for &([i, j, k], v) in t.unique_entries().iter().step_by(7) {
        let (i, j, k) = (i as usize, j as usize, k as usize);
        for (a, b, c) in [(i, j, k), (j, i, k), (k, j, i), (i, k, j), (j, k, i), (k, i, j)] {
            assert_eq!(t.get(a, b, c), v);
        }
    }
    let mut rng = Rng::new(51);
    let f = rng.coeffs(8);
    // The constant function 1 has coefficients [2√π, 0, …]: f • 1 = f (< 1e−12).
    let mut one = vec![0.0; 64];
    one[0] = CONSTANT_ONE_C00;
    assert!(max_diff(&t.product(&f, &one, 8).unwrap(), &f) < 1e-12);
    // [1, 0, …] is the constant Y00 = 1/(2√π): f • y00 = f / (2√π).
    let mut e0 = vec![0.0; 64];
    e0[0] = 1.0;
    let scaled: Vec<f64> = f.iter().map(|v| v * Y00).collect();
    assert!(max_diff(&t.product(&e0, &f, 8).unwrap(), &scaled) < 1e-13);
}

#[test]
fn product_equals_projection_of_the_pointwise_product() {
    let mut rng = Rng::new(52);
    let (a, b) = (rng.coeffs(4), rng.coeffs(4));
    // a·b is band-limited to 7 bands: the 7-band product is exact, its first 16 are the truncation.
    let full = product(&a, &b, 7).unwrap();
    let brute = exact_rule(18)
        .project_scalar(|d| eval_f64(&a, d).unwrap() * eval_f64(&b, d).unwrap(), 7)
        .unwrap();
    assert!(max_diff(&full, &brute) < 1e-12, "{}", max_diff(&full, &brute));
    let truncated = product(&a, &b, 4).unwrap();
    assert!(max_diff(&truncated, &full[..16]) < 1e-15);
    // Different operand band counts, pointwise check of the exact product.
    let c = rng.coeffs(3);
    let p = product(&a, &c, 6).unwrap();
    let d = rng.dir();
    close(
        eval_f64(&p, d).unwrap(),
        eval_f64(&a, d).unwrap() * eval_f64(&c, d).unwrap(),
        1e-12,
    );
    // RGB • scalar.
    let rgb: Vec<Vec3> = a.iter().map(|v| Vec3::new(*v as f32, 0.0, -*v as f32)).collect();
    let prgb = product(&rgb, &c, 4).unwrap();
    let ps = product(&a, &c, 4).unwrap();
    for (x, y) in prgb.iter().zip(&ps) {
        close(x.x as f64, *y, 1e-5);
        close(x.z as f64, -*y, 1e-5);
    }
}

#[test]
fn product_matrix_is_integral_of_a_yj_yk_and_applies_like_product() {
    let mut rng = Rng::new(53);
    let (a, b) = (rng.coeffs(4), rng.coeffs(4));
    let m = product_matrix(&a, 4).unwrap();
    assert_eq!(m.dim(), 16);
    assert!(max_diff(&m.apply(&b).unwrap(), &product(&a, &b, 4).unwrap()) < 1e-14);
    // M_kj = ∫ a y_j y_k: symmetric, and entry (2, 6) by quadrature.
    let s = m.as_slice();
    for k in 0..16 {
        for j in 0..16 {
            close(s[k * 16 + j], s[j * 16 + k], 1e-15);
        }
    }
    let mut y = vec![0.0; 16];
    let m26 = exact_rule(9).integrate(|d| {
        eval_basis_f64(d, 4, &mut y).unwrap();
        eval_f64(&a, d).unwrap() * y[2] * y[6]
    });
    close(s[2 * 16 + 6], m26, 1e-13);
    assert!(m.apply(&b[..9]).is_err());
}

#[test]
fn seed001_1_7_transfer_can_be_reordered() {
    // L·(V•C) = V·(L•C) = C·(L•V) under the truncated 16×16→16 product (Γ symmetric).
    let mut rng = Rng::new(54);
    let (l, v, c) = (rng.coeffs(4), rng.coeffs(4), rng.coeffs(4));
    let a = dot(&l, &product(&v, &c, 4).unwrap()).unwrap();
    let b = dot(&v, &product(&l, &c, 4).unwrap()).unwrap();
    let d = dot(&c, &product(&l, &v, 4).unwrap()).unwrap();
    close(a, b, 1e-13);
    close(a, d, 1e-13);
}

#[test]
fn seed001_d1_overhead_sphere_light_sh_over_exact() {
    // Flat receiver: V = hemisphere, C = clamped cosine, L = unit-radiance cap of half-angle θ,
    // all about +z, 4 bands, truncated product; exact irradiance π sin²θ.
    let v = zh_rotate(&hemisphere_zh(4).unwrap(), Vec3::Z).unwrap();
    let c = zh_rotate(&clamped_cosine_zh(4).unwrap(), Vec3::Z).unwrap();
    let t = product(&v, &c, 4).unwrap();
    for (deg, ratio) in [
        (1.0f64, 1.053),
        (10.0, 1.051),
        (30.0, 1.031),
        (45.0, 1.008),
        (60.0, 0.985),
        (80.0, 0.978),
    ] {
        let th = deg.to_radians();
        let l = zh_rotate(&cap_zh(th, 4).unwrap(), Vec3::Z).unwrap();
        close(dot(&l, &t).unwrap() / (PI * th.sin().powi(2)), ratio, 6e-4);
    }
    // Without the product the cap·cosine dot is exact up to truncation: at θ → 0 it tends to the
    // truncated clamped cosine at the normal, 1.0625 (the height-field thesis §7 A5).
    let l = zh_rotate(&cap_zh(1e-3, 4).unwrap(), Vec3::Z).unwrap();
    close(dot(&l, &c).unwrap() / (PI * 1e-3f64.sin().powi(2)), 1.0625, 1e-6);
}

#[test]
fn tensor_sizes_and_16_band_build() {
    assert_eq!(TripleProductTensor::shared(4).unwrap().unique_entries().len(), 77);
    let t = TripleProductTensor::shared(16).unwrap();
    assert!(std::ptr::eq(t, TripleProductTensor::shared(16).unwrap()));
    // Constant identity at 16 bands.
    let mut rng = Rng::new(55);
    let f = rng.coeffs(16);
    let mut one = vec![0.0; 256];
    one[0] = CONSTANT_ONE_C00;
    assert!(max_diff(&t.product(&one, &f, 16).unwrap(), &f) < 1e-12);
    assert!(TripleProductTensor::new(0).is_err());
    assert!(TripleProductTensor::shared(4).unwrap().product(&f, &f, 4).is_err()); // 16 bands > 4
    assert!(product(&[0.0f32; 5], &[0.0f32; 4], 2).is_err());
}

#[test]
fn gpu_product_term_list_applies_like_the_tensor() {
    // The packed list sh_product (glsl/common/sh.glsl) loops over, applied here in f64 with the
    // shader's decoding: the same product as the tensor (the values are f32, hence 1e-6).
    let mut rng = Rng::new(29);
    for bands in [1usize, 4, 8] {
        let terms = product_terms(bands).unwrap();
        assert_eq!(terms.len(), TripleProductTensor::shared(bands).unwrap().len());
        let (a, b) = (rng.coeffs(bands), rng.coeffs(bands));
        let mut c = vec![0.0; bands * bands];
        for [packed, bits] in &terms {
            let (i, j, k) = (
                (packed & 0xff) as usize,
                ((packed >> 8) & 0xff) as usize,
                (packed >> 16) as usize,
            );
            c[k] += f32::from_bits(*bits) as f64 * a[i] * b[j];
        }
        assert!(max_diff(&c, &product(&a, &b, bands).unwrap()) < 1e-6 * bands as f64);
    }
    // The GLSL arrays hold 8 bands.
    assert!(matches!(product_terms(0), Err(ShError::Range { .. })));
    assert!(matches!(product_terms(9), Err(ShError::Range { .. })));
}
