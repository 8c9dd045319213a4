//! Hanning / Lanczos windows and the clamped-cosine negative-lobe check.

use super::*;
use crate::sh::*;
use std::f64::consts::PI;

fn windowed_cosine(bands: usize, window: &[f64]) -> Vec<f64> {
    clamped_cosine_zh(bands)
        .unwrap()
        .iter()
        .zip(window)
        .map(|(z, w)| z * w)
        .collect()
}

#[test]
fn window_formulas() {
    // Hanning (1 + cos(πl/w))/2 and Lanczos sin(πl/w)/(πl/w), w = 4.
    let h = hanning(4, 4.0).unwrap();
    assert!(
        max_diff(
            &h,
            &[
                1.0,
                0.5 * (1.0 + (PI / 4.0).cos()),
                0.5,
                0.5 * (1.0 + (3.0 * PI / 4.0).cos())
            ]
        ) < 1e-15
    );
    close(h[1], 0.853553, 1e-6);
    let l = lanczos(4, 4.0).unwrap();
    assert!(max_diff(&l, &[1.0, 0.900316, std::f64::consts::FRAC_2_PI, 0.300105]) < 1e-6);
    // Zero from l = w on.
    assert_eq!(hanning(6, 3.0).unwrap()[3..], [0.0, 0.0, 0.0]);
    assert_eq!(lanczos(6, 3.0).unwrap()[3..], [0.0, 0.0, 0.0]);
    assert!(hanning(4, 0.0).is_err());
    assert!(lanczos(4, f64::NAN).is_err());
    assert!(hanning(0, 1.0).is_err());
}

#[test]
fn seed000_5_2_d_unwindowed_clamped_cosine_minima() {
    // −0.25 (2 bands), −0.040 (4), −0.0155 (8).
    for (bands, min) in [(2, -0.25), (4, -0.0396), (8, -0.0155)] {
        close(zonal_minimum(&clamped_cosine_zh(bands).unwrap(), 20001).1, min, 1e-4);
    }
}

#[test]
fn windowed_clamped_cosine_negative_lobe_bound() {
    // The table in window.rs: (bands, Hanning min, Lanczos min) at w = bands.
    for (bands, hann, lanc) in [
        (3, -0.0469, -0.0343),
        (4, -0.0224, -0.0192),
        (6, -0.0119, -0.0107),
        (8, -0.0081, -0.0072),
    ] {
        let h = windowed_cosine(bands, &hanning(bands, bands as f64).unwrap());
        let l = windowed_cosine(bands, &lanczos(bands, bands as f64).unwrap());
        let (mh, ml) = (zonal_minimum(&h, 20001).1, zonal_minimum(&l, 20001).1);
        close(mh, hann, 1e-4);
        close(ml, lanc, 1e-4);
        if bands >= 4 {
            // The documented bound: above −0.0225 and at most 0.57× the unwindowed lobe.
            let raw = zonal_minimum(&clamped_cosine_zh(bands).unwrap(), 20001).1;
            assert!(mh > -0.0225 && ml > -0.0225);
            assert!(mh / raw < 0.57 && ml / raw < 0.57, "{mh} {ml} {raw}");
        }
    }
    // Non-negative only at w ≤ 2: (1 + cos θ)/4.
    let h = windowed_cosine(4, &hanning(4, 2.0).unwrap());
    assert!(zonal_minimum(&h, 20001).1 > -1e-15);
    close(eval_zonal(&h, 1.0), 0.5, 1e-15);
    assert!(zonal_minimum(&windowed_cosine(4, &hanning(4, 2.05).unwrap()), 20001).1 < -1e-4);
    // Peak at 4 bands: 0.833 Hanning, 0.899 Lanczos (vs 1.0625 unwindowed).
    close(
        eval_zonal(&windowed_cosine(4, &hanning(4, 4.0).unwrap()), 1.0),
        0.8330,
        1e-4,
    );
    close(
        eval_zonal(&windowed_cosine(4, &lanczos(4, 4.0).unwrap()), 1.0),
        0.8991,
        1e-4,
    );
}

#[test]
fn windowing_keeps_band0_and_commutes_with_rotation() {
    let mut rng = Rng::new(61);
    let f = rng.coeffs(6);
    let w = hanning(6, 6.0).unwrap();
    let mut a = f.clone();
    apply_window(&mut a, &w).unwrap();
    assert_eq!(a[0], f[0]);
    close(a[30], f[30] * w[5], 1e-15);
    let r = rng.rotation();
    let rot = ShRotation::new(r, 6).unwrap();
    let mut b = rot.rotate(&f).unwrap();
    apply_window(&mut b, &w).unwrap();
    assert!(max_diff(&b, &rot.rotate(&a).unwrap()) < 1e-12);
    assert!(apply_window(&mut a, &w[..3]).is_err());
}
