//! Radiance statistics on linear RGB (alpha ignored).
//!
//! With t and r the test and reference values of one channel of one pixel, N pixels and the
//! sums running over all pixels and the three channels R, G, B:
//!
//! * RMSE         = sqrt( Σ (t − r)² / 3N )
//! * relative MSE = Σ (t − r)² / (r² + 0.01) / 3N. The 0.01 keeps near-black reference values
//!   from dominating (it is the square of 0.1, so an error of 0.1 on black counts as 1).
//! * mean bias    = Σ (t − r) / 3N; negative when the test image is darker than the reference.
//! * per-pixel error e = (|t_R − r_R| + |t_G − r_G| + |t_B − r_B|) / 3, the mean absolute
//!   error of the pixel over RGB.
//! * max = the largest e.
//! * mean ratio   = Σ t / Σ r: the global bias as a factor (1 when both are black, infinite
//!   when only the reference is).
//! * scaled relative RMSE = sqrt( Σ (s·t − r)² / 3N ) / (Σ r / 3N) with the best-fit scale
//!   s = Σ t·r / Σ t²: the error left once the test image is scaled to match, which separates
//!   a method's shape from its overall level (0 when the test is the reference times any
//!   factor; 0 when both are black, infinite when only the reference is).
//! * p99 by nearest rank: with the N values of e sorted ascending as e₁ ≤ … ≤ e_N, p99 = e_k
//!   for k = ⌈0.99·N⌉ (1-based), computed in integers as k = (99·N + 99) / 100. So p99 is
//!   always one of the observed errors; for N < 100 it is the maximum, for N = 100 the second
//!   largest (so a single outlier among 100 pixels moves max but not p99).
//!
//! Sums are accumulated in f64 so that multi-megapixel images do not lose the small errors.

/// The radiance part of [`super::Metrics`].
#[derive(Clone, Debug, PartialEq)]
pub struct RadianceStats {
    pub rmse: f64,
    pub rel_mse: f64,
    pub mean_bias: f64,
    pub p99_abs_error: f64,
    pub max_abs_error: f64,
    pub mean_ratio: f64,
    pub scaled_rel_rmse: f64,
}

/// Offset in the relative-MSE denominator r² + `REL_MSE_EPSILON`.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// Statistics of `test` against `reference`, pixel by pixel. The slices must have the same,
/// non-zero length (checked by `compare`); an empty input gives all zeros.
pub fn radiance_stats(test: &[[f32; 4]], reference: &[[f32; 4]]) -> RadianceStats {
    let n = test.len().min(reference.len());
    if n == 0 {
        return RadianceStats {
            rmse: 0.0,
            rel_mse: 0.0,
            mean_bias: 0.0,
            p99_abs_error: 0.0,
            max_abs_error: 0.0,
            mean_ratio: 1.0,
            scaled_rel_rmse: 0.0,
        };
    }
    let mut sum_sq = 0.0f64;
    let mut sum_rel = 0.0f64;
    let mut sum_diff = 0.0f64;
    let (mut sum_t, mut sum_r, mut sum_tt, mut sum_tr, mut sum_rr) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut per_pixel = Vec::with_capacity(n);
    for (t, r) in test.iter().zip(reference) {
        let mut abs_sum = 0.0f64;
        for c in 0..3 {
            let (tc, rc) = (f64::from(t[c]), f64::from(r[c]));
            let d = tc - rc;
            sum_sq += d * d;
            sum_rel += d * d / (rc * rc + REL_MSE_EPSILON);
            sum_diff += d;
            sum_t += tc;
            sum_r += rc;
            sum_tt += tc * tc;
            sum_tr += tc * rc;
            sum_rr += rc * rc;
            abs_sum += d.abs();
        }
        per_pixel.push(abs_sum / 3.0);
    }
    let samples = (3 * n) as f64;
    let max_abs_error = per_pixel.iter().copied().fold(0.0f64, f64::max);
    let (mean_ratio, scaled_rel_rmse) = level_and_shape(sum_t, sum_r, sum_tt, sum_tr, sum_rr, samples);
    RadianceStats {
        rmse: (sum_sq / samples).sqrt(),
        rel_mse: sum_rel / samples,
        mean_bias: sum_diff / samples,
        p99_abs_error: nearest_rank_percentile(&mut per_pixel, 99),
        max_abs_error,
        mean_ratio,
        scaled_rel_rmse,
    }
}

/// The mean ratio and the scaled relative RMSE from the sums over pixels and channels.
fn level_and_shape(sum_t: f64, sum_r: f64, sum_tt: f64, sum_tr: f64, sum_rr: f64, samples: f64) -> (f64, f64) {
    if sum_r <= 0.0 {
        let both_black = sum_tt == 0.0 && sum_rr == 0.0;
        return if both_black {
            (1.0, 0.0)
        } else {
            (f64::INFINITY, f64::INFINITY)
        };
    }
    let ratio = sum_t / sum_r;
    // Σ (s·t − r)² at s = Σ t·r / Σ t² is Σ r² − (Σ t·r)² / Σ t²; rounding may take it below 0.
    let residual = if sum_tt > 0.0 {
        (sum_rr - sum_tr * sum_tr / sum_tt).max(0.0)
    } else {
        sum_rr
    };
    (ratio, (residual / samples).sqrt() / (sum_r / samples))
}

/// The nearest-rank `pct`-th percentile (0 < pct ≤ 100): the k-th smallest value for
/// k = ⌈pct·N/100⌉, 1-based. Reorders `values`. Integer arithmetic keeps k exact (0.99·100 in
/// floating point is not 99). Returns 0 for an empty slice.
pub fn nearest_rank_percentile(values: &mut [f64], pct: usize) -> f64 {
    let n = values.len();
    if n == 0 {
        return 0.0;
    }
    let k = (pct * n).div_ceil(100).clamp(1, n);
    let (_, kth, _) = values.select_nth_unstable_by(k - 1, f64::total_cmp);
    *kth
}
