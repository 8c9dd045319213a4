//! Per-pass GPU timings summarised over frames: shared by `profile`, `chart` and the methods'
//! report hooks (e.g. seed 001's Table 6.6).

use std::collections::BTreeMap;

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

/// Median, min and max per scope name, keeping first-seen order.
pub fn summarise(frames: &[Vec<PassTiming>]) -> Vec<PassStats> {
    let mut order: Vec<String> = Vec::new();
    let mut samples: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for f in frames {
        for t in f {
            if !samples.contains_key(&t.name) {
                order.push(t.name.clone());
            }
            samples.entry(t.name.clone()).or_default().push(t.ms);
        }
    }
    order
        .into_iter()
        .map(|name| {
            let mut v = samples.remove(&name).unwrap_or_default();
            let min = v.iter().copied().fold(f64::INFINITY, f64::min);
            let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            PassStats { name, median_ms: median(&mut v), min_ms: min, max_ms: max }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_statistics() {
        let f = |v: &[(&str, f64)]| v.iter().map(|(n, ms)| PassTiming { name: n.to_string(), ms: *ms }).collect::<Vec<_>>();
        let frames = vec![f(&[("a", 1.0), ("b", 5.0)]), f(&[("a", 3.0), ("b", 4.0)]), f(&[("a", 2.0), ("b", 9.0)]), f(&[("a", 10.0)])];
        let s = summarise(&frames);
        assert_eq!(s[0], PassStats { name: "a".into(), median_ms: 2.5, min_ms: 1.0, max_ms: 10.0 });
        assert_eq!(s[1], PassStats { name: "b".into(), median_ms: 5.0, min_ms: 4.0, max_ms: 9.0 });
    }
}
