//! Known-answer tests: every expected value is worked out by hand (in the comments) or from
//! the published formulas evaluated independently in f64 here.

use super::*;
use crate::util::image_io::HdrImage;

fn image(w: u32, h: u32, mut f: impl FnMut(u32, u32) -> [f32; 3]) -> HdrImage {
    let mut img = HdrImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let [r, g, b] = f(x, y);
            img.pixels[(y * w + x) as usize] = [r, g, b, 1.0];
        }
    }
    img
}

fn constant(w: u32, h: u32, v: f32) -> HdrImage {
    image(w, h, |_, _| [v; 3])
}

/// Deterministic noise in [lo, hi) per channel (xorshift64*), so failures reproduce.
fn noise(w: u32, h: u32, seed: u64, lo: f32, hi: f32) -> HdrImage {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        (s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    };
    image(w, h, |_, _| [0, 1, 2].map(|_| lo + (hi - lo) * next()))
}

fn opts() -> CompareOptions {
    CompareOptions::default()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn default_viewing_conditions_give_67_ppd() {
    // 0.7 m · (3840 px / 0.7 m) · π/180 = 3840·π/180 = 67.0206.
    assert!((default_pixels_per_degree() - 67.0206).abs() < 1e-3);
    assert_eq!(CompareOptions::default().exposure, 1.0);
}

#[test]
fn identical_images_give_exactly_zero() {
    let img = noise(32, 24, 1, 0.0, 4.0);
    let m = compare(&img, &img, &opts()).unwrap();
    assert_eq!(
        m,
        Metrics {
            rmse: 0.0,
            rel_mse: 0.0,
            mean_bias: 0.0,
            p99_abs_error: 0.0,
            max_abs_error: 0.0,
            flip_mean: 0.0,
            mean_ratio: 1.0,
            scaled_rel_rmse: 0.0,
            pixels: 768
        }
    );
}

#[test]
fn constant_offset_of_a_tenth() {
    // Reference: checkerboard of 0.2 and 1.0 (32 pixels each); test = reference + 0.1.
    let r = image(8, 8, |x, y| [if (x + y) % 2 == 0 { 0.2 } else { 1.0 }; 3]);
    let t = image(8, 8, |x, y| [if (x + y) % 2 == 0 { 0.2 + 0.1 } else { 1.0 + 0.1 }; 3]);
    let m = compare(&t, &r, &opts()).unwrap();
    let tol = 1e-6; // f32 inputs: 0.2 + 0.1 is 0.1 up to ~1e-8
    assert!(close(m.rmse, 0.1, tol), "{}", m.rmse);
    assert!(close(m.mean_bias, 0.1, tol));
    assert!(close(m.max_abs_error, 0.1, tol));
    assert!(close(m.p99_abs_error, 0.1, tol));
    // relMSE = ½·(0.01/(0.04 + 0.01) + 0.01/(1 + 0.01)) = ½·(0.2 + 0.00990099…) = 0.1049505
    let rel = 0.5 * (0.01 / (0.2f64 * 0.2 + 0.01) + 0.01 / (1.0 + 0.01));
    assert!(close(rel, 0.104_950_495, 1e-9));
    assert!(close(m.rel_mse, rel, tol), "{}", m.rel_mse);
    assert_eq!(m.pixels, 64);
}

#[test]
fn single_outlier_moves_max_but_not_p99() {
    // 100 grey pixels; one has +1 on red only: its error is (1 + 0 + 0)/3.
    let r = constant(10, 10, 0.5);
    let mut t = r.clone();
    t.pixels[4 * 10 + 3][0] += 1.0;
    let m = compare(&t, &r, &opts()).unwrap();
    assert!(close(m.max_abs_error, 1.0 / 3.0, 1e-7));
    // Nearest rank k = ⌈0.99·100⌉ = 99: the 99th smallest of 99 zeros and one 1/3.
    assert_eq!(m.p99_abs_error, 0.0);
    // Σ(t−r)² = 1 over 300 samples.
    assert!(close(m.rmse, (1.0f64 / 300.0).sqrt(), 1e-9));
    assert!(close(m.mean_bias, 1.0 / 300.0, 1e-9));
    assert!(close(m.rel_mse, 1.0 / (0.25 + 0.01) / 300.0, 1e-9));
}

#[test]
fn two_outliers_p99_is_the_smaller() {
    // Errors 0.25 and 0.5 on all channels (exact in binary) at two of 100 pixels.
    let r = constant(10, 10, 0.5);
    let mut t = r.clone();
    t.pixels[17] = [0.75, 0.75, 0.75, 1.0];
    t.pixels[62] = [1.0, 1.0, 1.0, 1.0];
    let m = compare(&t, &r, &opts()).unwrap();
    assert_eq!(m.p99_abs_error, 0.25);
    assert_eq!(m.max_abs_error, 0.5);
    // Σ(t−r)² = 3·0.0625 + 3·0.25 = 0.9375 over 300 samples.
    assert!(close(m.rmse, (0.9375f64 / 300.0).sqrt(), 1e-12));
    // Below 100 pixels the rank is N itself: p99 = max.
    let r = constant(5, 5, 0.5);
    let mut t = r.clone();
    t.pixels[7][2] = 0.8;
    let m = compare(&t, &r, &opts()).unwrap();
    assert_eq!(m.p99_abs_error, m.max_abs_error);
    assert!(close(m.max_abs_error, 0.1, 1e-7));
}

#[test]
fn nearest_rank_definition() {
    let mut v: Vec<f64> = (1..=200).rev().map(f64::from).collect();
    // k = ⌈0.99·200⌉ = 198.
    assert_eq!(stats::nearest_rank_percentile(&mut v, 99), 198.0);
    let mut v: Vec<f64> = (1..=1000).map(f64::from).collect();
    assert_eq!(stats::nearest_rank_percentile(&mut v, 99), 990.0);
    assert_eq!(stats::nearest_rank_percentile(&mut [7.0], 99), 7.0);
    assert_eq!(stats::nearest_rank_percentile(&mut [], 99), 0.0);
}

#[test]
fn darker_test_has_negative_bias() {
    let r = noise(16, 16, 2, 0.5, 1.5);
    let t = image(16, 16, |x, y| {
        let p = r.get(x, y);
        [p[0] - 0.25, p[1] - 0.25, p[2] - 0.25]
    });
    let m = compare(&t, &r, &opts()).unwrap();
    assert!(close(m.mean_bias, -0.25, 1e-6), "{}", m.mean_bias);
    assert!(close(m.rmse, 0.25, 1e-6));
    assert!(m.flip_mean > 0.0);
}

// --- FLIP ---------------------------------------------------------------------------------

/// Hunt-adjusted L*a*b* of a linear RGB colour, from the textbook formulas in f64.
fn hunt_lab_f64(rgb: [f64; 3]) -> [f64; 3] {
    let m = [
        [10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0],
        [2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0],
        [1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0],
    ];
    let white = [0, 1, 2].map(|i| m[i][0] + m[i][1] + m[i][2]);
    let xyz = [0, 1, 2].map(|i| (m[i][0] * rgb[0] + m[i][1] * rgb[1] + m[i][2] * rgb[2]) / white[i]);
    let d = 6.0 / 29.0;
    let f = |t: f64| {
        if t > d * d * d {
            t.cbrt()
        } else {
            t / (3.0 * d * d) + 4.0 / 29.0
        }
    };
    let [fx, fy, fz] = xyz.map(f);
    let l = 116.0 * fy - 16.0;
    [l, 0.01 * l * 500.0 * (fx - fy), 0.01 * l * 200.0 * (fy - fz)]
}

fn hyab_f64(p: [f64; 3], q: [f64; 3]) -> f64 {
    (p[0] - q[0]).abs() + ((p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// Colour-only FLIP of two constant images (no features, CSF leaves constants alone).
fn closed_form_flip(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (qc, pc, pt) = (0.7, 0.4, 0.95);
    let cmax = hyab_f64(hunt_lab_f64([0.0, 1.0, 0.0]), hunt_lab_f64([0.0, 0.0, 1.0])).powf(qc);
    let e = hyab_f64(hunt_lab_f64(a), hunt_lab_f64(b)).powf(qc);
    if e < pc * cmax {
        pt / (pc * cmax) * e
    } else {
        pt + (e - pc * cmax) / (cmax - pc * cmax) * (1.0 - pt)
    }
}

#[test]
fn flip_black_vs_white_is_the_closed_form() {
    // Radiance 100 saturates the ACES fit to exactly 1, so this is display black vs white:
    // HyAB = |0 − 100| + 0 = 100, 100^0.7 = 25.12 > p_c·c_max, so the upper branch applies.
    let expected = closed_form_flip([0.0; 3], [1.0; 3]);
    // NVIDIA's flip-evaluator 1.7 gives 0.967388 for this pair.
    assert!(close(expected, 0.967_388, 1e-5), "{expected}");
    let black = constant(24, 16, 0.0);
    let white = constant(24, 16, 100.0);
    let m = compare(&black, &white, &opts()).unwrap();
    assert!(close(m.flip_mean, expected, 1e-4), "{} vs {expected}", m.flip_mean);
    // Constant images: every pixel, including the borders, carries the same value.
    let map = flip_error_map(&black, &white, &opts()).unwrap();
    assert!(map.values.iter().all(|v| (f64::from(*v) - expected).abs() < 1e-4));
    // And the value does not depend on the viewing distance.
    let far = CompareOptions {
        pixels_per_degree: 20.0,
        ..opts()
    };
    assert!(close(compare(&black, &white, &far).unwrap().flip_mean, expected, 1e-4));
}

#[test]
fn flip_of_grey_offsets_matches_closed_form_and_grows() {
    let r = constant(16, 16, 0.5);
    let mut last = 0.0;
    for k in [0.05f32, 0.1, 0.2] {
        let m = compare(&constant(16, 16, 0.5 + k), &r, &opts()).unwrap();
        let (a, b) = (f64::from(image_io_aces(0.5 + k)), f64::from(image_io_aces(0.5)));
        let expected = closed_form_flip([a; 3], [b; 3]);
        assert!(
            close(m.flip_mean, expected, 1e-4),
            "k = {k}: {} vs {expected}",
            m.flip_mean
        );
        assert!(m.flip_mean > last, "k = {k}: {} not above {last}", m.flip_mean);
        last = m.flip_mean;
    }
}

fn image_io_aces(x: f32) -> f32 {
    crate::util::image_io::aces_fit(x)
}

#[test]
fn flip_exposure_is_applied_before_the_tone_curve() {
    // At exposure 0 both images display as black: FLIP sees nothing, RMSE still does.
    let r = constant(8, 8, 0.5);
    let t = constant(8, 8, 0.9);
    let m = compare(
        &t,
        &r,
        &CompareOptions {
            exposure: 0.0,
            ..opts()
        },
    )
    .unwrap();
    assert_eq!(m.flip_mean, 0.0);
    assert!(close(m.rmse, 0.4, 1e-6));
    // Exposure 2 on 0.25 vs 0.45 is the same display pair as exposure 1 on 0.5 vs 0.9.
    let a = compare(
        &constant(8, 8, 0.45),
        &constant(8, 8, 0.25),
        &CompareOptions {
            exposure: 2.0,
            ..opts()
        },
    )
    .unwrap();
    let b = compare(&t, &r, &opts()).unwrap();
    assert!(close(a.flip_mean, b.flip_mean, 1e-6));
}

#[test]
fn flip_on_noise() {
    let r = noise(48, 40, 3, 0.0, 2.0);
    let same = flip_error_map(&r, &r.clone(), &opts()).unwrap();
    assert!(same.values.iter().all(|v| *v == 0.0));

    let t = image(48, 40, |x, y| {
        let (p, n) = (
            r.get(x, y),
            noise(1, 1, u64::from(y * 48 + x) + 100, -0.3, 0.3).pixels[0],
        );
        [p[0] + n[0], p[1] + n[1], p[2] + n[2]]
    });
    let map = flip_error_map(&t, &r, &opts()).unwrap();
    assert_eq!(map.values.len(), 48 * 40);
    assert!(
        map.values.iter().all(|v| *v > 0.0 && *v <= 1.0),
        "{:?}",
        map.values.iter().fold((1f32, 0f32), |a, v| (a.0.min(*v), a.1.max(*v)))
    );
    let m = compare(&t, &r, &opts()).unwrap();
    assert!(close(m.flip_mean, map.mean(), 1e-12));
    // A larger perturbation of the same pattern is more visible.
    let t2 = image(48, 40, |x, y| {
        let (p, q) = (r.get(x, y), t.get(x, y));
        [0, 1, 2].map(|c| p[c] + 3.0 * (q[c] - p[c]))
    });
    assert!(compare(&t2, &r, &opts()).unwrap().flip_mean > m.flip_mean);
}

#[test]
fn flip_of_a_thin_line_is_local_and_blurred() {
    // A one-pixel dark line across a mid-grey image. At 67 ppd the CSF spreads it out, so the
    // error on the line is below that of a large uniform patch of the same colours, and it
    // falls off with distance. The feature term only scales a colour error (ΔE = ΔE_c^(1−ΔE_f)),
    // so the reach is that of the achromatic CSF (σ ≈ 1 pixel): a few pixels, then exactly 0.
    let r = constant(32, 32, 0.5);
    let t = image(32, 32, |_, y| [if y == 16 { 0.3 } else { 0.5 }; 3]);
    let map = flip_error_map(&t, &r, &opts()).unwrap();
    let at = |y: usize| f64::from(map.values[y * 32 + 5]);
    let patch = closed_form_flip([f64::from(image_io_aces(0.3)); 3], [f64::from(image_io_aces(0.5)); 3]);
    assert!(at(16) > 0.0 && at(16) < patch, "{} vs patch {patch}", at(16));
    assert!(at(16) > at(14) && at(14) > at(12) && at(12) > 0.0);
    assert!(
        close(at(13), at(19), 1e-6) && close(at(14), at(18), 1e-6),
        "symmetric about the line"
    );
    assert_eq!(at(2), 0.0);
    assert_eq!(at(30), 0.0);
}

#[test]
fn flip_matches_nvidia_reference_implementation() {
    // Expected values from NVIDIA's own FLIP (PyPI flip-evaluator 1.7, LDR mode, linear input
    // `inputsRGB=False`, fed aces_fit of the same images in float32): a block pattern with
    // hashed noise, a multiplicative ±15 % perturbation and a brighter 8×20 rectangle. Over the
    // whole map the per-pixel difference to that tool was ≤ 1.1e-5 (f32 rounding).
    fn h(x: u32, y: u32, c: u32, seed: u32) -> f32 {
        let v = x.wrapping_mul(73_856_093)
            ^ y.wrapping_mul(19_349_663)
            ^ c.wrapping_mul(83_492_791)
            ^ seed.wrapping_mul(2_654_435_761);
        (v % 1024) as f32 / 1024.0
    }
    let r = image(64, 48, |x, y| {
        [0, 1, 2].map(|c| 0.3 + 0.8 * (((x / 8 + y / 8 + c) % 3) as f32 / 2.0) + 0.3 * h(x, y, c, 1))
    });
    let t = image(64, 48, |x, y| {
        let p = r.get(x, y);
        [0, 1, 2].map(|c| {
            let v = p[c as usize] * (1.0 + 0.3 * (h(x, y, c, 2) - 0.5));
            if (20..28).contains(&x) && (10..30).contains(&y) {
                v + 0.4
            } else {
                v
            }
        })
    });
    // (ppd, mean, pixel (0, 0), pixel (25, 20), pixel (63, 47)) from the reference tool.
    for (ppd, mean, p0, p1, p2) in [
        (
            default_pixels_per_degree(),
            0.073_484_41,
            0.148_825_27,
            0.394_243_4,
            0.116_180_7,
        ),
        (30.0, 0.118_434_28, 0.139_552_24, 0.428_181_5, 0.122_176_7),
    ] {
        let map = flip_error_map(
            &t,
            &r,
            &CompareOptions {
                pixels_per_degree: ppd,
                ..opts()
            },
        )
        .unwrap();
        assert!(
            close(map.mean(), mean, 2e-6),
            "ppd {ppd}: mean {} vs {mean}",
            map.mean()
        );
        for (i, want) in [(0, p0), (20 * 64 + 25, p1), (47 * 64 + 63, p2)] {
            let got = f64::from(map.values[i]);
            assert!(close(got, want, 2e-5), "ppd {ppd}, pixel {i}: {got} vs {want}");
        }
    }
}

#[test]
fn flip_of_green_vs_blue_is_one() {
    // c_max is defined by this pair (the largest HyAB distance between in-gamut colours), so
    // the normalised error is exactly the top of the scale, whichever image is the reference.
    let g = image(8, 8, |_, _| [0.0, 100.0, 0.0]);
    let b = image(8, 8, |_, _| [0.0, 0.0, 100.0]);
    assert!(close(compare(&g, &b, &opts()).unwrap().flip_mean, 1.0, 1e-6));
    assert!(close(compare(&b, &g, &opts()).unwrap().flip_mean, 1.0, 1e-6));
}

#[test]
fn huge_radiance_saturates_instead_of_poisoning_flip() {
    // 1e30 is finite, but naive ACES of it is inf/inf; on display it is plain white, like 100.
    let r = constant(8, 8, 100.0);
    let mut t = r.clone();
    t.pixels[9] = [1.0e30, 3.0e38, 1.0e20, 1.0];
    let m = compare(&t, &r, &opts()).unwrap();
    assert_eq!(m.flip_mean, 0.0);
    assert!(m.max_abs_error.is_finite() && m.max_abs_error > 1e37);
}

// --- errors, output ----------------------------------------------------------------------

#[test]
fn size_mismatch_message() {
    let e = compare(&constant(64, 48, 0.0), &constant(32, 32, 0.0), &opts()).unwrap_err();
    assert_eq!(e.to_string(), "test image 64x48 and reference 32x32 differ in size");
    assert!(diff_image(&constant(64, 48, 0.0), &constant(32, 32, 0.0), &opts()).is_err());
}

#[test]
fn non_finite_messages_name_the_image_and_pixel() {
    let good = constant(8, 10, 0.5);
    let mut bad = good.clone();
    bad.pixels[7 * 8 + 3][1] = f32::NAN;
    let e = compare(&good, &bad, &opts()).unwrap_err();
    assert_eq!(e.to_string(), "reference has a non-finite value at pixel (3, 7)");
    let mut inf = good.clone();
    inf.pixels[8 + 5][2] = f32::INFINITY;
    let e = compare(&inf, &good, &opts()).unwrap_err();
    assert_eq!(e.to_string(), "test image has a non-finite value at pixel (5, 1)");
    // Alpha is not compared, so it is not checked.
    let mut alpha = good.clone();
    alpha.pixels[0][3] = f32::NAN;
    assert!(compare(&alpha, &good, &opts()).is_ok());
}

#[test]
fn malformed_inputs_and_options_are_errors() {
    let good = constant(4, 4, 0.5);
    let mut short = good.clone();
    short.pixels.pop();
    assert_eq!(
        compare(&good, &short, &opts()).unwrap_err().to_string(),
        "reference holds 15 pixels but its size 4x4 needs 16"
    );
    let empty = HdrImage::new(0, 3);
    assert!(matches!(
        compare(&empty, &empty, &opts()),
        Err(MetricsError::Empty { .. })
    ));
    for bad in [
        CompareOptions {
            exposure: f32::NAN,
            ..opts()
        },
        CompareOptions {
            exposure: -1.0,
            ..opts()
        },
        CompareOptions {
            pixels_per_degree: 0.0,
            ..opts()
        },
    ] {
        assert!(matches!(
            compare(&good, &good, &bad),
            Err(MetricsError::InvalidOption(_))
        ));
    }
}

#[test]
fn diff_image_uses_magma() {
    assert_eq!(magma(0.0), [0, 0, 4]);
    assert_eq!(magma(1.0), [252, 253, 191]);
    assert_eq!(magma(128.0 / 255.0), [183, 55, 121]);
    assert_eq!(magma(f32::NAN), magma(0.0));
    // Perceptually ordered: luma rises monotonically along the map.
    let luma = |c: [u8; 3]| 0.2126 * f32::from(c[0]) + 0.7152 * f32::from(c[1]) + 0.0722 * f32::from(c[2]);
    let steps: Vec<f32> = (0..=100).map(|i| luma(magma(i as f32 / 100.0))).collect();
    assert!(steps.windows(2).all(|w| w[1] >= w[0]));

    let r = constant(6, 4, 0.0);
    let d = diff_image(&r, &r, &opts()).unwrap();
    assert_eq!(d.dimensions(), (6, 4));
    assert!(d.pixels().all(|p| p.0 == [0, 0, 4, 255]));
    let (m, map) = compare_with_map(&constant(6, 4, 100.0), &r, &opts()).unwrap();
    let d = colorize(&map);
    assert_eq!(d.get_pixel(2, 2).0[..3], magma(m.flip_mean as f32));
}

#[test]
fn table_and_json() {
    let m = Metrics {
        rmse: 0.1,
        rel_mse: 0.105,
        mean_bias: -0.02,
        p99_abs_error: 0.3,
        max_abs_error: 2.5e-6,
        flip_mean: 0.25,
        mean_ratio: 0.9,
        scaled_rel_rmse: 0.04,
        pixels: 64,
    };
    let t = m.table();
    assert_eq!(t.lines().count(), 9);
    assert!(t.contains("mean ratio      0.900000"));
    assert!(t.contains("scaled rel RMSE 0.040000"));
    assert!(t
        .lines()
        .next()
        .is_some_and(|l| l.starts_with("pixels") && l.ends_with("64")));
    assert!(t.contains("RMSE            0.100000"));
    assert!(t.contains("mean bias       -0.020000"));
    assert!(t.contains("max abs error   2.5000e-6"));
    assert!(t.contains("FLIP mean       0.250000"));
    let json = serde_json::to_string(&m).unwrap();
    assert!(json.contains("\"flip_mean\":0.25") && json.contains("\"pixels\":64"));
}

/// An image from per-pixel grey values, one row.
fn grey_row(values: &[f32]) -> HdrImage {
    image(values.len() as u32, 1, |x, _| [values[x as usize]; 3])
}

#[test]
fn mean_ratio_and_scaled_error_separate_the_level_from_the_shape() {
    // A scaled copy: the ratio is the factor and nothing is left once scaled back.
    let r = grey_row(&[0.0, 1.0, 2.0, 5.0]);
    let m = compare(&grey_row(&[0.0, 3.0, 6.0, 15.0]), &r, &opts()).unwrap();
    assert!((m.mean_ratio - 3.0).abs() < 1e-12 && m.scaled_rel_rmse < 1e-9, "{m:?}");
    // t = (1, 1) against r = (0, 2): same mean, ratio 1; s = Σtr/Σt² = 1, residual (1, 1),
    // RMSE 1 over a mean of 1. Against the brute-force minimum over s on a fine grid.
    let (t, r) = (grey_row(&[1.0, 1.0]), grey_row(&[0.0, 2.0]));
    let m = compare(&t, &r, &opts()).unwrap();
    assert!((m.mean_ratio - 1.0).abs() < 1e-12, "{m:?}");
    assert!((m.scaled_rel_rmse - 1.0).abs() < 1e-12, "{m:?}");
    let brute = (0..=4000)
        .map(|i| i as f64 / 1000.0)
        .map(|s| ((s * 1.0 - 0.0f64).powi(2) + (s * 1.0 - 2.0f64).powi(2)) / 2.0)
        .fold(f64::INFINITY, f64::min)
        .sqrt();
    assert!((m.scaled_rel_rmse - brute / 1.0).abs() < 1e-6);
    // A black reference: equal black images agree, anything else is infinitely off.
    let black = grey_row(&[0.0, 0.0]);
    let m = compare(&black, &black, &opts()).unwrap();
    assert_eq!((m.mean_ratio, m.scaled_rel_rmse), (1.0, 0.0));
    let m = compare(&grey_row(&[0.5, 0.0]), &black, &opts()).unwrap();
    assert!(m.mean_ratio.is_infinite() && m.scaled_rel_rmse.is_infinite());
}
