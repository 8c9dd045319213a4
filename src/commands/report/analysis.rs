//! What the report derives from a chart's data: the best configuration within a time budget, the
//! failure cases, and which configurations differ only in faithful against corrected mode.

use crate::commands::chart::Chart;

/// The most accurate configuration (least relative MSE) whose frame time is within `budget_ms`.
pub fn best_within(chart: &Chart, budget_ms: f64) -> Option<usize> {
    chart
        .rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.frame_ms <= budget_ms && r.lighting_metrics().rel_mse.is_finite())
        .min_by(|(_, a), (_, b)| a.lighting_metrics().rel_mse.total_cmp(&b.lighting_metrics().rel_mse))
        .map(|(i, _)| i)
}

/// Relative MSE at or above which an image's error carries as much energy as its light.
pub const FAR_OFF_REL_MSE: f64 = 1.0;
/// Mean radiance ratios outside [1/F, F] are far off: the image is over twice too bright or dark.
pub const FAR_OFF_MEAN_RATIO: f64 = 2.0;

/// A failure case the data shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// `refused`, `non-finite`, `far off`, `no timing` or `incomplete`.
    pub kind: &'static str,
    pub config: String,
    pub detail: String,
}

/// Every failure case of the chart: swept points the method refused, images with NaN or
/// infinity, images far off the reference (relative MSE at least `FAR_OFF_REL_MSE` (1), or a mean
/// off by more than `FAR_OFF_MEAN_RATIO` (2)×), frames without GPU time, and frames where the
/// method says it left something out.
pub fn failures(chart: &Chart) -> Vec<Failure> {
    let split = |kind: &'static str, text: &String| {
        let (config, detail) = text.split_once(": ").unwrap_or((text.as_str(), ""));
        Failure {
            kind,
            config: config.to_string(),
            detail: detail.to_string(),
        }
    };
    let mut out: Vec<Failure> = chart.skipped.iter().map(|s| split("refused", s)).collect();
    out.extend(chart.non_finite.iter().map(|s| split("non-finite", s)));
    for r in &chart.rows {
        let m = r.lighting_metrics();
        let failure = |kind, detail| Failure {
            kind,
            config: r.config.clone(),
            detail,
        };
        // NaN counts as far off.
        if m.rel_mse.is_nan() || m.rel_mse >= FAR_OFF_REL_MSE {
            out.push(failure(
                "far off",
                format!("relative MSE {:.3} against the reference", m.rel_mse),
            ));
        } else if !(1.0 / FAR_OFF_MEAN_RATIO..=FAR_OFF_MEAN_RATIO).contains(&m.mean_ratio) {
            out.push(failure(
                "far off",
                format!("mean radiance {:.3}\u{d7} the reference's", m.mean_ratio),
            ));
        }
        if !r.frame_ms.is_finite() {
            out.push(failure("no timing", "the device gave no GPU time".into()));
        }
        out.extend(r.warnings.iter().map(|w| failure("incomplete", w.clone())));
    }
    out
}

/// Pairs (faithful row, other row) of one method whose configuration names differ only in the
/// word `faithful` against another mode's word (e.g. `corrected` or `physical`).
pub fn faithful_pairs(chart: &Chart) -> Vec<(usize, usize)> {
    let words = |s: &str| s.split(' ').map(str::to_string).collect::<Vec<_>>();
    let mut out = Vec::new();
    for (i, a) in chart.rows.iter().enumerate() {
        let wa = words(&a.config);
        let Some(at) = wa.iter().position(|w| w == "faithful") else {
            continue;
        };
        let partner = chart.rows.iter().enumerate().find(|(j, b)| {
            let wb = words(&b.config);
            *j != i
                && b.method == a.method
                && wb.len() == wa.len()
                && wb[at] != "faithful"
                && wa.iter().zip(&wb).enumerate().all(|(k, (x, y))| k == at || x == y)
        });
        if let Some((j, _)) = partner {
            out.push((i, j));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::chart::ChartRow;
    use crate::metrics::Metrics;

    fn row(config: &str, ms: f64, rel_mse: f64, mean_ratio: f64) -> ChartRow {
        let m = Metrics {
            rmse: 0.1,
            rel_mse,
            mean_bias: 0.0,
            p99_abs_error: 0.1,
            max_abs_error: 0.1,
            flip_mean: 0.1,
            mean_ratio,
            scaled_rel_rmse: 0.1,
            pixels: 4,
        };
        ChartRow {
            method: config.split(' ').next().unwrap().into(),
            config: config.into(),
            frame_ms: ms,
            frames_timed: 3,
            passes: Vec::new(),
            metrics: m.clone(),
            supersampled: None,
            reference_noise: m,
            warnings: Vec::new(),
            reference: "direct".into(),
            bake_ms: 0.0,
            bake_bytes: 0,
        }
    }

    fn chart(rows: Vec<ChartRow>) -> Chart {
        Chart {
            scene: "s".into(),
            device: "d".into(),
            size: (4, 1),
            supersample: 1,
            rows,
            skipped: vec!["lpv grid=64: over the memory limit".into()],
            non_finite: vec!["vls n=9: a non-finite value (NaN or infinity) at pixel (1, 0)".into()],
            frame: 0,
            camera: None,
        }
    }

    #[test]
    fn the_best_within_a_budget_is_the_most_accurate_that_fits() {
        let c = chart(vec![
            row("a fast", 2.0, 0.3, 1.0),
            row("a mid", 9.0, 0.05, 1.0),
            row("a slow", 40.0, 0.001, 1.0),
        ]);
        assert_eq!(best_within(&c, 10.0), Some(1));
        assert_eq!(best_within(&c, 100.0), Some(2));
        assert_eq!(best_within(&c, 1.0), None);
    }

    #[test]
    fn failures_come_from_the_data() {
        let c = chart(vec![
            row("a good", 1.0, 0.01, 1.0),
            row("a noisy", 1.0, 2.0, 1.0),
            row("a dark", 1.0, 0.5, 0.3),
        ]);
        let f = failures(&c);
        let kinds: Vec<(&str, &str)> = f.iter().map(|f| (f.kind, f.config.as_str())).collect();
        assert_eq!(
            kinds,
            vec![
                ("refused", "lpv grid=64"),
                ("non-finite", "vls n=9"),
                ("far off", "a noisy"),
                ("far off", "a dark")
            ]
        );
    }

    #[test]
    fn faithful_pairs_differ_in_the_mode_word_only() {
        let c = chart(vec![
            row("r corrected patch=1", 1.0, 0.1, 1.0),
            row("r faithful patch=1", 1.0, 0.1, 1.0),
            row("r faithful patch=2", 1.0, 0.1, 1.0),
            row("s physical pscs", 1.0, 0.1, 1.0),
            row("s faithful pscs", 1.0, 0.1, 1.0),
        ]);
        assert_eq!(faithful_pairs(&c), vec![(1, 0), (4, 3)]);
    }
}
