//! Per-pass GPU timings summarised over frames: shared by `profile`, `chart` and the methods'
//! report hooks (e.g. the height-field thesis's Table 6.6).

use serde::Serialize;

use crate::backend::PassTiming;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PassStats {
    pub name: String,
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(|a, b| a.total_cmp(b));
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// Per-pass samples gathered frame by frame: each pass's name is kept once and its times as
/// plain numbers, 8 bytes a pass a frame (keeping each frame's `PassTiming`s, names and all, cost
/// about 1 KB a frame on bsp_rooms: `penumbra profile --frames 4000` grew by 4 MB).
#[derive(Clone, Debug, Default)]
pub struct TimingSummary {
    names: Vec<String>,
    samples: Vec<Vec<f64>>,
    frames: usize,
}

impl TimingSummary {
    pub fn add(&mut self, frame: &[PassTiming]) {
        for t in frame {
            let k = match self.names.iter().position(|n| *n == t.name) {
                Some(k) => k,
                None => {
                    self.names.push(t.name.clone());
                    self.samples.push(Vec::new());
                    self.names.len() - 1
                }
            };
            self.samples[k].push(t.ms);
        }
        self.frames += 1;
    }

    /// Frames added.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Median, min and max per scope name, in first-seen order.
    pub fn stats(&self) -> Vec<PassStats> {
        self.names
            .iter()
            .zip(&self.samples)
            .map(|(name, v)| {
                let min = v.iter().copied().fold(f64::INFINITY, f64::min);
                let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                PassStats {
                    name: name.clone(),
                    median_ms: median(&mut v.clone()),
                    min_ms: min,
                    max_ms: max,
                }
            })
            .collect()
    }
}

/// Median, min and max per scope name, keeping first-seen order.
pub fn summarise(frames: &[Vec<PassTiming>]) -> Vec<PassStats> {
    let mut summary = TimingSummary::default();
    for f in frames {
        summary.add(f);
    }
    summary.stats()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_statistics() {
        let f = |v: &[(&str, f64)]| {
            v.iter()
                .map(|(n, ms)| PassTiming {
                    name: n.to_string(),
                    ms: *ms,
                })
                .collect::<Vec<_>>()
        };
        let frames = vec![
            f(&[("a", 1.0), ("b", 5.0)]),
            f(&[("a", 3.0), ("b", 4.0)]),
            f(&[("a", 2.0), ("b", 9.0)]),
            f(&[("a", 10.0)]),
        ];
        let mut summary = TimingSummary::default();
        for frame in &frames {
            summary.add(frame);
        }
        assert_eq!(summary.frames(), 4);
        let s = summary.stats();
        assert_eq!(s, summarise(&frames));
        assert_eq!(
            s[0],
            PassStats {
                name: "a".into(),
                median_ms: 2.5,
                min_ms: 1.0,
                max_ms: 10.0
            }
        );
        assert_eq!(
            s[1],
            PassStats {
                name: "b".into(),
                median_ms: 5.0,
                min_ms: 4.0,
                max_ms: 9.0
            }
        );
    }
}
