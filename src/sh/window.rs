//! Windowing (per-band scale factors) against ringing of truncated SH expansions, after Sloan,
//! "Stupid Spherical Harmonics (SH) Tricks" (GDC 2008), with the window width `w` in bands
//! (Sloan suggests w = the number of bands used, so the last band keeps a little weight):
//!
//! * Hanning: `h_l = (1 + cos(π l / w)) / 2` for l < w, else 0.
//! * Lanczos σ-factors: `σ_l = sinc(l / w) = sin(π l / w) / (π l / w)` for l < w (σ_0 = 1),
//!   else 0.
//!
//! Windowing is a convolution with a zonal kernel, so it commutes with rotation and keeps the
//! integral (band 0). The price is blur: the clamped cosine's peak drops below 1.
//!
//! Negative-lobe bound of the windowed clamped cosine `max(cos θ, 0)` (the cos-lobe check; the
//! `window` tests assert every number here). Minimum of the reconstruction over the sphere
//! (the true function is ≥ 0, peak 1):
//!
//! | bands | unwindowed | Hanning w = bands | Lanczos w = bands |
//! |---|---|---|---|
//! | 3 | −0.0396 | −0.0469 | −0.0343 |
//! | 4 | −0.0396 | −0.0224 | −0.0192 |
//! | 6 | −0.0313 | −0.0119 | −0.0107 |
//! | 8 | −0.0155 | −0.0081 | −0.0072 |
//!
//! So for 4..=8 bands a window of width w = bands keeps the negative lobe above **−0.0225**
//! and at most 0.57× the unwindowed lobe, at the cost of the peak (0.833 Hanning / 0.899
//! Lanczos at 4 bands instead of 1.0625). No Hanning width above 2 removes the lobe entirely:
//! a non-negative reconstruction needs w ≤ 2, which leaves only (1 + cos θ)/4. The unwindowed
//! minima −0.25 (2 bands), −0.0396 (4), −0.0155 (8) are the Ca3D-Engine thesis §5.2 D's. Note that at 3
//! bands Hanning makes the lobe *worse*: windowing is not a cure-all, measure it.

use super::{bands_of, check_bands, Coeff, ShError, ShResult};
use std::f64::consts::PI;

fn check_width(width: f64) -> ShResult<()> {
    if !width.is_finite() {
        return Err(ShError::NonFinite("window width"));
    }
    if width <= 0.0 {
        return Err(ShError::Range {
            what: "window width",
            range: "> 0",
            got: width,
        });
    }
    Ok(())
}

/// Hanning window of width `width` (> 0, in bands) for `bands` bands.
pub fn hanning(bands: usize, width: f64) -> ShResult<Vec<f64>> {
    check_bands(bands)?;
    check_width(width)?;
    Ok((0..bands)
        .map(|l| {
            if (l as f64) < width {
                0.5 * (1.0 + (PI * l as f64 / width).cos())
            } else {
                0.0
            }
        })
        .collect())
}

/// Lanczos σ-factor window of width `width` (> 0, in bands) for `bands` bands.
pub fn lanczos(bands: usize, width: f64) -> ShResult<Vec<f64>> {
    check_bands(bands)?;
    check_width(width)?;
    Ok((0..bands)
        .map(|l| {
            if l == 0 {
                1.0
            } else if (l as f64) < width {
                let x = PI * l as f64 / width;
                x.sin() / x
            } else {
                0.0
            }
        })
        .collect())
}

/// Scales band l of `coeffs` by `window[l]` (the window needs at least as many bands).
pub fn apply_window<C: Coeff>(coeffs: &mut [C], window: &[f64]) -> ShResult<()> {
    let bands = bands_of("windowed coefficients", coeffs)?;
    if window.len() < bands {
        return Err(ShError::Length {
            what: "window bands",
            expected: bands,
            got: window.len(),
        });
    }
    for (l, w) in window.iter().enumerate().take(bands) {
        for c in &mut coeffs[l * l..(l + 1) * (l + 1)] {
            *c = c.scale(*w);
        }
    }
    Ok(())
}

/// Minimum of the zonal function `zh` over the sphere, scanned at `samples` (≥ 2, clamped)
/// equally spaced angles θ ∈ [0, π] from its axis: returns `(θ at the minimum, minimum)`.
/// Used to bound the negative lobes of windowed kernels.
pub fn zonal_minimum(zh: &[f64], samples: usize) -> (f64, f64) {
    let n = samples.max(2);
    (0..n)
        .map(|i| {
            let t = PI * i as f64 / (n - 1) as f64;
            (t, super::eval_zonal(zh, t.cos()))
        })
        .fold((0.0, f64::INFINITY), |best, x| if x.1 < best.1 { x } else { best })
}
