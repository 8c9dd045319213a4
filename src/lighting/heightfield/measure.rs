//! Measurements of the height-field methods: the seed's Table 6.6 layout from pass timings, the
//! pyramid's speed-up over brute force at equal error from chart rows, and the temporal
//! stability of the shading under a moving field.

use crate::backend::GpuDesc;
use crate::error::Result;
use crate::scene::{MethodDecl, Scene};
use crate::util::timing::PassStats;

use super::standalone::Standalone;

/// Per-pass medians grouped as the seed's Table 6.6 (pyramid, environment, each local light)
/// plus the rest of the frame; `None` when the passes are not a height-field method's.
pub fn table_6_6(passes: &[PassStats]) -> Option<String> {
    let sum = |pred: &dyn Fn(&str) -> bool| {
        passes
            .iter()
            .filter(|p| pred(&p.name))
            .map(|p| p.median_ms)
            .sum::<f64>()
    };
    let has = |prefix: &str| passes.iter().any(|p| p.name.starts_with(prefix));
    if !has("hf ") {
        return None;
    }
    let pyramid = sum(&|n| n.starts_with("hf pyramid") || n == "hf bounds");
    let env = sum(&|n| n == "hf environment" || n.starts_with("hf environment SH"));
    let lights: Vec<(String, f64)> = passes
        .iter()
        .filter(|p| p.name.starts_with("hf light "))
        .map(|p| (p.name.clone(), p.median_ms))
        .collect();
    let height = sum(&|n| n == "hf height update");
    let rest = sum(&|n| n == "hf accumulate" || n == "hf raster" || n == "hf emitters");
    let pyramid_label = if has("hf bounds") { "Bounds" } else { "Pyramid" };
    let mut s = String::from(
        "the height-field thesis's Table 6.6 layout (ms, medians; pyramid = level 0 + decimations + reconstruction):\n",
    );
    s += &format!("| Height update | {pyramid_label} | Env. Light |");
    for (i, _) in lights.iter().enumerate() {
        s += &format!(" L-Light {} |", i + 1);
    }
    s += " Accumulate + raster |\n|---|---|---|";
    for _ in &lights {
        s += "---|";
    }
    s += "---|\n";
    s += &format!("| {height:.3} | {pyramid:.3} | {env:.3} |");
    for (_, ms) in &lights {
        s += &format!(" {ms:.3} |");
    }
    s += &format!(" {rest:.3} |\n");
    Some(s)
}

/// One measured configuration: its method, label, GPU milliseconds and error.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub method: String,
    pub config: String,
    pub ms: f64,
    pub error: f64,
}

/// The brute force's cost at error `e`, interpolated log–log along its Pareto front (cheapest
/// configuration for each error level). `None` when `e` is outside the range it reached.
pub fn brute_cost_at(brute: &[Point], e: f64) -> Option<f64> {
    let mut front: Vec<&Point> = Vec::new();
    let mut sorted: Vec<&Point> = brute.iter().collect();
    sorted.sort_by(|a, b| a.ms.total_cmp(&b.ms));
    let mut best = f64::INFINITY;
    for p in sorted {
        if p.error < best {
            best = p.error;
            front.push(p);
        }
    }
    // front: time increasing, error decreasing.
    for w in front.windows(2) {
        let (a, b) = (w[0], w[1]);
        if e <= a.error && e >= b.error {
            if (a.error - b.error).abs() < 1e-300 {
                return Some(a.ms.min(b.ms));
            }
            let t = (e.ln() - a.error.ln()) / (b.error.ln() - a.error.ln());
            return Some((a.ms.ln() + t * (b.ms.ln() - a.ms.ln())).exp());
        }
    }
    match front.as_slice() {
        [only] if (only.error - e).abs() <= 1e-12 * e.abs() => Some(only.ms),
        _ => None,
    }
}

/// Mean and 99th percentile of |Δ| between consecutive frames (luminance of the shading, per
/// texel) over `frames` frames `dt` seconds apart, from time 0; plus the same for the second
/// difference |s(t+1) − 2 s(t) + s(t−1)|, which is zero for a change that is linear in time and
/// so isolates flicker from the motion itself.
#[derive(Clone, Debug, PartialEq)]
pub struct Stability {
    pub mean: f64,
    pub p99: f64,
    pub mean_second: f64,
    pub p99_second: f64,
}

fn luminance(p: &[f32; 4]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

fn mean_p99(mut v: Vec<f64>) -> (f64, f64) {
    if v.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    v.sort_by(|a, b| a.total_cmp(b));
    let k = ((v.len() as f64 * 0.99).ceil() as usize).clamp(1, v.len()) - 1;
    (mean, v[k])
}

pub fn temporal_stability(
    gpu: &GpuDesc,
    scene: &Scene,
    decl: &MethodDecl,
    frames: usize,
    dt: f32,
) -> Result<Stability> {
    let mut h = Standalone::new(crate::backend::Gpu::new(gpu)?, scene, decl)?;
    let mut prev: Option<Vec<f64>> = None;
    let mut prev_delta: Option<Vec<f64>> = None;
    let (mut first, mut second) = (Vec::new(), Vec::new());
    for f in 0..frames.max(3) {
        let s: Vec<f64> = h.shading(f as f32 * dt)?.iter().map(luminance).collect();
        if let Some(p) = &prev {
            let delta: Vec<f64> = s.iter().zip(p).map(|(a, b)| a - b).collect();
            first.extend(delta.iter().map(|d| d.abs()));
            if let Some(pd) = &prev_delta {
                second.extend(delta.iter().zip(pd).map(|(a, b)| (a - b).abs()));
            }
            prev_delta = Some(delta);
        }
        prev = Some(s);
    }
    let (mean, p99) = mean_p99(first);
    let (mean_second, p99_second) = mean_p99(second);
    Ok(Stability {
        mean,
        p99,
        mean_second,
        p99_second,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(ms: f64, error: f64) -> Point {
        Point {
            method: "b".into(),
            config: format!("{ms}"),
            ms,
            error,
        }
    }

    #[test]
    fn brute_cost_interpolates_along_the_front() {
        let brute = vec![pt(1.0, 0.1), pt(10.0, 0.01), pt(5.0, 0.2)];
        assert!((brute_cost_at(&brute, 0.1).unwrap() - 1.0).abs() < 1e-9);
        // Half-way in log error between 0.1 and 0.01: √10 ms.
        assert!((brute_cost_at(&brute, 0.1f64.powf(1.5)).unwrap() - 10f64.sqrt()).abs() < 1e-9);
        assert_eq!(brute_cost_at(&brute, 0.001), None);
    }

    #[test]
    fn table_groups_passes() {
        let p = |n: &str, ms: f64| PassStats {
            name: n.into(),
            median_ms: ms,
            min_ms: ms,
            max_ms: ms,
        };
        let passes = vec![
            p("frame", 10.0),
            p("hf height update", 0.5),
            p("hf pyramid level 0", 0.1),
            p("hf pyramid decimate 1", 0.2),
            p("hf pyramid reconstruct", 0.7),
            p("hf environment SH", 0.1),
            p("hf environment", 3.0),
            p("hf light 1", 4.0),
            p("hf accumulate", 0.2),
            p("hf raster", 1.0),
        ];
        let t = table_6_6(&passes).unwrap();
        assert!(t.contains("| 0.500 | 1.000 | 3.100 | 4.000 | 1.200 |"), "{t}");
        assert!(table_6_6(&[p("forward", 1.0)]).is_none());
    }
}
