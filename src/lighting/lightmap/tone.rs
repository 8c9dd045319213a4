//! CaLight's tone reproduction (the Ca3D-Engine thesis §3.3.5, digest §1.2 step F): Ward Larson, Rushmeier and
//! Piatko's histogram adjustment \[LRP97\] applied to the light-map's world luminances instead of
//! screen pixels, then a linear rescale to 8 bits. The faithful mode's light-maps are these display
//! values, not radiometric ones.

use glam::DVec3;

/// Histogram bins over log luminance.
const BINS: usize = 300;
/// Darkest luminance considered (log of it is the histogram's floor).
const MIN_LUMINANCE: f64 = 1e-4;
/// The display's maximum luminance (its minimum is 1): the dynamic range `ln 80`.
const DISPLAY_MAX: f64 = 80.0;
/// The ceiling iteration stops once it trims less than this fraction of the total.
const TOLERANCE: f64 = 0.025;

fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Maps each value to 8-bit RGB by histogram adjustment; chroma is kept (RGB scaled by the
/// display/world luminance ratio), black stays black.
pub fn reproduce(values: &[DVec3]) -> Vec<[u8; 3]> {
    let lum: Vec<f64> = values.iter().map(|&v| luminance(v)).collect();
    values
        .iter()
        .zip(display_scale(&lum))
        .map(|(&v, scale)| [v.x, v.y, v.z].map(|c| (c * 255.0 * scale).round().clamp(0.0, 255.0) as u8))
        .collect()
}

/// Per world luminance, the factor that takes it to its display value in [0, 1] (0 for black):
/// what [`reproduce`] scales RGB by, and CaSHL scales a transfer vector by (the Ca3D-Engine thesis §5.4.4).
pub fn display_scale(lum: &[f64]) -> Vec<f64> {
    let max = lum.iter().copied().fold(0.0f64, f64::max);
    if max <= MIN_LUMINANCE {
        return vec![0.0; lum.len()];
    }
    let (lo, hi) = (MIN_LUMINANCE.ln(), max.ln());
    let width = ((hi - lo) / BINS as f64).max(1e-12);
    let bin = |l: f64| (((l.max(MIN_LUMINANCE).ln() - lo) / width) as usize).min(BINS - 1);
    let mut hist = vec![0.0f64; BINS];
    for &l in lum.iter().filter(|&&l| l > MIN_LUMINANCE) {
        hist[bin(l)] += 1.0;
    }
    // \[LRP97\]'s ceiling: no bin may hold more than Total·Δb / ln(display range), so that contrast
    // is never exaggerated beyond what the display's range needs; trimming lowers the total, so
    // it repeats until it trims less than the tolerance.
    let original = hist.clone();
    let count: f64 = original.iter().sum();
    loop {
        let total: f64 = hist.iter().sum();
        // A sparse histogram (fewer values than bins) would be trimmed away entirely: keep the
        // plain cumulative histogram then, as \[LRP97\] falls back when the ceiling cannot hold.
        if total < TOLERANCE * count {
            hist = original;
            break;
        }
        let ceiling = total * width / DISPLAY_MAX.ln();
        let trimmed: f64 = hist
            .iter_mut()
            .map(|h| {
                let t = (*h - ceiling).max(0.0);
                *h -= t;
                t
            })
            .sum();
        if trimmed < TOLERANCE * total {
            break;
        }
    }
    let total: f64 = hist.iter().sum::<f64>().max(1e-300);
    let mut cdf = vec![0.0f64; BINS];
    let mut acc = 0.0;
    for (c, h) in cdf.iter_mut().zip(&hist) {
        acc += h;
        *c = acc / total;
    }
    lum.iter()
        .map(|&l| {
            if l <= MIN_LUMINANCE {
                return 0.0;
            }
            let display = DISPLAY_MAX.powf(cdf[bin(l)]);
            // The display range [1, 80] rescaled to [0, 1].
            (display - 1.0) / (DISPLAY_MAX - 1.0) / l
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_bounded_and_black_stays_black() {
        // A wide range of grey luminances, shuffled: the order of the outputs is the order of the
        // inputs, and everything fits 8 bits with the brightest at the top.
        let mut values: Vec<DVec3> = (0..2000).map(|i| DVec3::splat(1e-3 * 1.005f64.powi(i))).collect();
        values.reverse();
        values.push(DVec3::ZERO);
        let out = reproduce(&values);
        assert_eq!(out.last(), Some(&[0, 0, 0]));
        let grey: Vec<u8> = out[..2000].iter().map(|c| c[1]).collect();
        assert!(grey.windows(2).all(|w| w[0] >= w[1]), "not monotonic");
        assert_eq!(grey[0], 255);
        assert!(grey[1999] < 10, "{}", grey[1999]);
        // A spike (most patches at one value) over a spread of others: the ceiling keeps the
        // spike from taking the whole output range, so the spread keeps many levels (measured:
        // 134; plain histogram equalization, the ceiling removed, leaves it 57).
        let mut spiky = vec![DVec3::splat(0.5); 5000];
        spiky.extend((0..3000).map(|i| DVec3::splat(1e-3 * 1.0026f64.powi(i))));
        let out = reproduce(&spiky);
        let distinct: std::collections::BTreeSet<u8> = out[5000..].iter().map(|c| c[0]).collect();
        assert!(distinct.len() > 100, "{} levels", distinct.len());
        // Chroma survives: a red patch stays red.
        let c = reproduce(&[DVec3::new(0.8, 0.1, 0.05), DVec3::splat(0.2)])[0];
        assert!(c[0] > c[1] && c[1] >= c[2], "{c:?}");
    }
}
