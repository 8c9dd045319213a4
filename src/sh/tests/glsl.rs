//! `glsl/common/sh.glsl` against the CPU: its constants, the float formulas it uses for texel
//! solid angles, and (where `glslc` is installed) that it compiles with warnings as errors.

use super::*;
use crate::sh::*;
use std::collections::HashMap;
use std::f64::consts::PI;

const SOURCE: &str = include_str!("../../../glsl/common/sh.glsl");

/// Every `const float NAME = v;` and `const float NAME[n] = float[n](v, …);` of the header.
fn constants() -> HashMap<String, Vec<f64>> {
    let mut out = HashMap::new();
    let mut text = SOURCE.to_string();
    // Join continuation lines of array initialisers.
    text = text.replace(",\n", ", ");
    for line in text.lines() {
        let line = line.trim();
        let Some(rest) = line
            .strip_prefix("const float ")
            .or_else(|| line.strip_prefix("const int "))
        else {
            continue;
        };
        let Some((name, value)) = rest.split_once('=') else {
            continue;
        };
        let name = name.trim().split('[').next().unwrap_or_default().to_string();
        let value = value.split(';').next().unwrap_or_default();
        let value = value
            .rsplit_once('(')
            .map(|(_, v)| v.trim_end().trim_end_matches(')'))
            .unwrap_or(value);
        let nums: Vec<f64> = value
            .split(',')
            .map(|v| v.trim().parse().unwrap_or_else(|_| panic!("{name}: {v}")))
            .collect();
        out.insert(name, nums);
    }
    out
}

#[test]
fn glsl_constants_match_the_cpu_values() {
    let c = constants();
    let one = |n: &str| c.get(n).unwrap_or_else(|| panic!("{n} missing"))[0];
    close(one("SH_PI"), PI, 1e-15);
    assert_eq!(one("SH_MAX_BANDS") as usize, GLSL_MAX_BANDS);
    assert_eq!(one("SH_MAX_COEFFS") as usize, GLSL_MAX_BANDS * GLSL_MAX_BANDS);
    close(one("SH_Y00"), Y00, 1e-16);
    // Cartesian constants against the recurrence: y at chosen directions / polynomial there.
    let y = |d: DVec3| {
        let mut v = vec![0.0; 16];
        eval_basis_f64(d, 4, &mut v).unwrap();
        v
    };
    let s = std::f64::consts::FRAC_1_SQRT_2;
    close(one("SH_C1"), y(DVec3::Z)[2], 1e-15);
    close(one("SH_C2_XY"), y(DVec3::new(s, s, 0.0))[4] / 0.5, 1e-14);
    close(one("SH_C2_ZZ"), y(DVec3::Z)[6] / 2.0, 1e-15);
    close(one("SH_C2_XXYY"), y(DVec3::X)[8], 1e-15);
    close(one("SH_C3_3"), -y(DVec3::X)[15], 1e-14);
    let d = DVec3::ONE.normalize();
    close(one("SH_C3_XYZ"), y(d)[10] / (d.x * d.y * d.z), 1e-13);
    close(one("SH_C3_1"), y(DVec3::X)[13], 1e-14);
    close(one("SH_C3_0"), y(DVec3::Z)[12] / 2.0, 1e-15);
    close(one("SH_C3_2"), y(DVec3::new(s, 0.0, s))[14] / (s * 0.5), 1e-13);
    // Per-band tables.
    let k: Vec<f64> = (0..8).map(|l| (4.0 * PI / (2 * l + 1) as f64).sqrt()).collect();
    assert!(max_diff(&c["SH_ZH_ROT_K"], &k) < 1e-15);
    assert!(max_diff(&c["SH_CLAMPED_COS_ZH"], &clamped_cosine_zh(8).unwrap()) < 1e-15);
    assert!(max_diff(&c["SH_LAMBERT_A"], &lambert_kernel(8).unwrap()) < 1e-15);
    // Cap factors: sh_cap_zh4 at cos α = 0.3 equals cap_zh (s² = 0.91).
    let ck = &c["SH_CAP_K"];
    let (cc, s2) = (0.3, 0.91);
    let glsl = [
        ck[0] * (1.0 - cc),
        ck[1] * s2,
        ck[2] * cc * s2,
        ck[3] * s2 * (5.0 * cc * cc - 1.0),
    ];
    assert!(max_diff(&glsl, &cap_zh(0.3f64.acos(), 4).unwrap()) < 1e-15);
}

/// The GLSL cube-texel solid angle (two Van Oosterom–Strackee triangles with exact triple
/// products), in f32 as the GPU computes it.
fn glsl_cube_texel_solid_angle(x: usize, y: usize, size: usize) -> f32 {
    let n = size as f32;
    let (x0, x1) = (2.0 * x as f32 / n - 1.0, 2.0 * (x + 1) as f32 / n - 1.0);
    let (y0, y1) = (2.0 * y as f32 / n - 1.0, 2.0 * (y + 1) as f32 / n - 1.0);
    let p = |a: f32, b: f32| glam::Vec3::new(a, b, 1.0);
    let tri = |a: glam::Vec3, b: glam::Vec3, c: glam::Vec3, triple: f32| {
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        2.0 * triple.atan2(la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la)
    };
    let h = 2.0 / n;
    tri(p(x0, y0), p(x1, y0), p(x1, y1), h * h) + tri(p(x0, y0), p(x1, y1), p(x0, y1), h * h)
}

#[test]
fn glsl_texel_solid_angle_formulas_are_exact_in_float() {
    for size in [1usize, 2, 7, 64, 1024] {
        let mut worst = 0.0f64;
        for (x, y) in [(0, 0), (size / 2, size / 3), (size - 1, 0), (size - 1, size - 1)] {
            let exact = cube_texel_solid_angle(x, y, size);
            worst = worst.max((glsl_cube_texel_solid_angle(x, y, size) as f64 - exact).abs() / exact);
        }
        assert!(worst < 2e-6, "size {size}: relative error {worst:e}");
    }
    // The four-term atan formula in f32 loses ~1% at 1024² (why the GLSL does not use it).
    let a = |u: f32, v: f32| (u * v).atan2((u * u + v * v + 1.0).sqrt());
    let (n, x, y) = (1024.0f32, 1000.0f32, 1000.0f32);
    let (x0, x1, y0, y1) = (
        2.0 * x / n - 1.0,
        2.0 * (x + 1.0) / n - 1.0,
        2.0 * y / n - 1.0,
        2.0 * (y + 1.0) / n - 1.0,
    );
    let naive = (a(x0, y0) - a(x0, y1) - a(x1, y0) + a(x1, y1)) as f64;
    let exact = cube_texel_solid_angle(1000, 1000, 1024);
    assert!((naive - exact).abs() / exact > 1e-3);
    // Equirect: the product form 2 sin(θc) sin(Δ/2) in f32 against the f64 difference of cosines.
    for (y, h) in [(0usize, 2048usize), (1023, 2048), (5, 16)] {
        let dt = std::f32::consts::PI / h as f32;
        let glsl = 2.0 * std::f32::consts::PI / 4096.0 * 2.0 * ((y as f32 + 0.5) * dt).sin() * (0.5 * dt).sin();
        let exact = equirect_texel_solid_angle(y, 4096, h);
        assert!((glsl as f64 - exact).abs() / exact < 1e-6);
    }
}

/// `sh_eval_bands` of the GLSL, line by line in f32 (its loop merges the l = m, m + 1 and
/// recurrence cases differently from `basis.rs`, so the structure itself is checked).
fn glsl_eval_bands(dir: glam::Vec3, bands: usize) -> Vec<f32> {
    let mut y = vec![0.0f32; 64];
    let d = dir.normalize();
    let nb = bands.clamp(1, 8);
    let mut pmm = 0.282_094_8_f32;
    let mut cs = (1.0f32, 0.0f32);
    for m in 0..nb {
        if m > 0 {
            pmm *= -((2 * m + 1) as f32 / (2 * m) as f32).sqrt();
            cs = (d.x * cs.0 - d.y * cs.1, d.x * cs.1 + d.y * cs.0);
        }
        let (mut p_prev, mut p) = (0.0f32, pmm);
        for l in m..nb {
            if l == m + 1 {
                p_prev = p;
                p = ((2 * m + 3) as f32).sqrt() * d.z * p_prev;
            } else if l > m + 1 {
                let (lf, mf) = (l as f32, m as f32);
                let a = ((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf)).sqrt();
                let b = (((lf - 1.0) * (lf - 1.0) - mf * mf) / (4.0 * (lf - 1.0) * (lf - 1.0) - 1.0)).sqrt();
                let next = a * (d.z * p - b * p_prev);
                p_prev = p;
                p = next;
            }
            let centre = l * (l + 1);
            if m == 0 {
                y[centre] = p;
            } else {
                y[centre + m] = std::f32::consts::SQRT_2 * p * cs.0;
                y[centre - m] = std::f32::consts::SQRT_2 * p * cs.1;
            }
        }
    }
    y
}

#[test]
fn glsl_eval_bands_loop_structure_matches_cpu() {
    let mut rng = Rng::new(71);
    for _ in 0..20 {
        let d = rng.dir();
        let g = glsl_eval_bands(d.as_vec3(), 8);
        let mut c = vec![0.0; 64];
        eval_basis_f64(d, 8, &mut c).unwrap();
        let g: Vec<f64> = g.iter().map(|v| *v as f64).collect();
        assert!(max_diff(&g, &c) < 1e-5, "{}", max_diff(&g, &c)); // f32 rounding: ~2e-6
    }
    // Fewer bands leave the rest zero, as the GLSL's initial clear does.
    let g = glsl_eval_bands(glam::Vec3::X, 3);
    assert!(g[9..].iter().all(|v| *v == 0.0));
}
