//! `penumbra profile`: per-pass GPU time from timestamp queries, over many frames.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::backend::{Gpu, PassTiming};
use crate::capture::{load_scene, CaptureOptions};
use crate::error::{Error, Result};
use crate::renderer::Renderer;

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PassStats {
    pub name: String,
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct ProfileReport {
    pub device: String,
    pub driver: String,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    /// Passes in frame order; "frame" is the whole frame.
    pub passes: Vec<PassStats>,
    pub culled: Vec<String>,
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

pub fn run(opts: &CaptureOptions, frames: usize) -> Result<ProfileReport> {
    let scene = load_scene(opts.scene.as_deref())?;
    let gpu = Gpu::new(&opts.gpu)?;
    if gpu.caps().timestamp_valid_bits == 0 {
        return Err(Error::Backend(crate::backend::BackendError::Unsupported(format!("{}: timestamps on the graphics queue (timestampValidBits = 0)", gpu.caps().name))));
    }
    let mut renderer = Renderer::new(gpu, scene, opts.method.as_deref(), opts.size, 1)?;
    let camera = renderer.scene.camera.clone();
    // One frame to warm caches and learn which passes were culled.
    let culled = renderer.render(&camera, crate::renderer::FrameOutput::None)?.report.culled;
    renderer.gpu.submit_and_wait(renderer.last_frame())?;
    let timings = renderer.profile(&camera, frames.max(1))?;
    let caps = renderer.gpu.caps();
    Ok(ProfileReport {
        device: caps.name.clone(),
        driver: format!("{} {}", caps.driver_name, caps.driver_info),
        width: opts.size.0,
        height: opts.size.1,
        frames: timings.len(),
        passes: summarise(&timings),
        culled,
    })
}

impl ProfileReport {
    pub fn table(&self) -> String {
        let mut s = format!("{} ({}), {}x{}, {} frames\n{:<28} {:>10} {:>10} {:>10}\n", self.device, self.driver, self.width, self.height, self.frames, "pass", "median ms", "min ms", "max ms");
        for p in &self.passes {
            s += &format!("{:<28} {:>10.3} {:>10.3} {:>10.3}\n", p.name, p.median_ms, p.min_ms, p.max_ms);
        }
        if !self.culled.is_empty() {
            s += &format!("culled (outputs unused): {}\n", self.culled.join(", "));
        }
        // The height-field methods also print their passes as seed 001's Table 6.6.
        if let Some(t) = crate::heightfield::measure::table_6_6(&self.passes) {
            s += &t;
        }
        s
    }
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
