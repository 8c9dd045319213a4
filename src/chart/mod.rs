//! `penumbra chart`: every method the scene enables, at every point of its quality sweep, timed
//! with GPU timestamps and measured against the scene's path-traced reference; a log–log plot of
//! error against time with the Pareto front, and a CSV with every per-pass time and metric.
//!
//! The reference is rendered once per (scene content, size, reference settings) and cached in
//! `.penumbra-cache/`, as is the chart's table, which `capture --max-error` reads.

mod plot;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::backend::{Gpu, GpuDesc};
use crate::bake::{BakeReport, Baker};
use crate::error::{Error, Result};
use crate::image_io::HdrImage;
use crate::lighting::{registry, Configuration, ReferenceKind};
use crate::metrics::{self, CompareOptions, Metrics};
use crate::reference::{Batching, LightPaths, ReferenceRenderer, Settings};
use crate::renderer::{FrameOutput, Renderer};
use crate::scene::Scene;
use crate::timing::summarise;

#[derive(Clone, Debug)]
pub struct ChartOptions {
    pub scene: PathBuf,
    pub size: (u32, u32),
    /// Frames timed per configuration (the median is reported).
    pub frames: usize,
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
    pub png: Option<PathBuf>,
    pub csv: Option<PathBuf>,
    pub cache_dir: PathBuf,
    pub gpu: GpuDesc,
    /// Only these methods or combinations (all of the scene's when empty).
    pub methods: Vec<String>,
}

/// One configuration of one method, measured.
#[derive(Clone, Debug, PartialEq)]
pub struct ChartRow {
    pub method: String,
    /// The sweep point, e.g. `forward` or `lpv grid=32 iterations=8`.
    pub config: String,
    /// Median GPU milliseconds of the whole frame.
    pub frame_ms: f64,
    /// Median GPU milliseconds per pass.
    pub passes: Vec<(String, f64)>,
    pub metrics: Metrics,
    /// The reference it was measured against (e.g. `direct, 256 spp`).
    pub reference: String,
    /// Wall time of the configuration's bakes when it was created (from the cache when
    /// already baked), and their size.
    pub bake_ms: f64,
    pub bake_bytes: u64,
}

pub struct Chart {
    pub scene: String,
    pub device: String,
    pub size: (u32, u32),
    pub rows: Vec<ChartRow>,
    /// Swept points left out, with why (a limit of the method on this scene).
    pub skipped: Vec<String>,
}

/// FNV-1a: a stable content hash for cache keys (std's hasher may change between releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// A key naming everything a cached result depends on: the parsed scene (so comments and
/// formatting don't matter, but every value does), the size, and the extra settings.
pub fn cache_key(scene: &Scene, size: (u32, u32), extra: &str) -> String {
    let mut text = format!("{:?}|{}x{}|{extra}", scene_without_source(scene), size.0, size.1);
    // The reference shader is part of the truth: a changed tracer invalidates old references.
    for (name, spirv) in crate::shaders::ShaderLibrary::embedded_names().zip(crate::shaders::embedded_bytes()) {
        if name.starts_with("reference/") {
            let _ = write!(text, "|{name}:{:016x}", fnv1a(spirv));
        }
    }
    format!("{:016x}", fnv1a(text.as_bytes()))
}

fn scene_without_source(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.source = String::new();
    s
}

fn reference_settings(kind: ReferenceKind, spp: u32) -> (Settings, String) {
    let (paths, bounces, label) = match kind {
        ReferenceKind::Direct => (LightPaths::Direct, 0, "direct"),
        ReferenceKind::Bounces(k) => (LightPaths::All, k, "bounces"),
        ReferenceKind::Indirect(k) => (LightPaths::Indirect, k, "bounces (indirect only)"),
    };
    let label = if kind == ReferenceKind::Direct { format!("{label}, {spp} spp") } else { format!("{bounces} {label}, {spp} spp") };
    (Settings { spp, bounces, paths, seed: 0, batching: Batching::Adaptive, ..Settings::default() }, label)
}

/// The reference for this scene and kind: from the cache, or rendered and cached.
pub fn reference_image(scene: &Scene, size: (u32, u32), kind: ReferenceKind, spp: u32, cache_dir: &Path, gpu: &GpuDesc) -> Result<(HdrImage, String)> {
    let (settings, label) = reference_settings(kind, spp);
    let key = cache_key(scene, size, &format!("{settings:?}"));
    let path = cache_dir.join(format!("reference-{key}.exr"));
    if let Ok(img) = HdrImage::read_exr(&path) {
        if (img.width, img.height) == size {
            return Ok((img, label));
        }
    }
    crate::errln!("chart: rendering the reference ({label}) for {}", scene.source);
    let mut tracer = ReferenceRenderer::new(Gpu::new(gpu)?, scene, size)?;
    let mut progress = crate::progress::Progress::new("reference (spp)");
    let image = tracer.render(&settings, &mut |done, total| progress.update(done as u64, total as u64))?;
    progress.finish();
    std::fs::create_dir_all(cache_dir).map_err(|e| Error::Usage(format!("{}: {e}", cache_dir.display())))?;
    image.mean.write_exr(&path)?;
    Ok((image.mean, label))
}

/// One configuration's image, median frame time (ms), per-pass medians, device name and bakes.
type Measured = (HdrImage, f64, Vec<(String, f64)>, String, Vec<BakeReport>);

/// Renders and times one configuration.
fn measure(scene: &Scene, config: &Configuration, opts: &ChartOptions) -> Result<Measured> {
    let bakes = Baker::new(Some(opts.cache_dir.join("bake")));
    let mut renderer = Renderer::with_configuration(Gpu::new(&opts.gpu)?, scene.clone(), config.clone(), opts.size, 1, bakes)?;
    let device = renderer.gpu.caps().name.clone();
    let camera = renderer.scene.camera.clone();
    let image = renderer.render(&camera, FrameOutput::Readback)?.image.ok_or_else(|| Error::Usage("readback returned no image".into()))?;
    let timings = renderer.profile(&camera, opts.frames.max(1))?;
    let stats = summarise(&timings);
    let frame_ms = stats.iter().find(|s| s.name == "frame").map(|s| s.median_ms).unwrap_or(f64::NAN);
    let passes = stats.into_iter().filter(|s| s.name != "frame").map(|s| (s.name, s.median_ms)).collect();
    Ok((image, frame_ms, passes, device, renderer.bakes.clone()))
}

pub fn run(opts: &ChartOptions) -> Result<Chart> {
    let scene = Scene::from_file(&opts.scene)?;
    let mut rows = Vec::new();
    let mut references: BTreeMap<String, (HdrImage, String)> = BTreeMap::new();
    let mut device = String::new();
    let mut skipped: Vec<String> = Vec::new();
    let all = registry::configurations(&scene)?;
    for name in &opts.methods {
        if !all.iter().any(|c| c.name == *name) {
            let known: Vec<&str> = all.iter().map(|c| c.name.as_str()).collect();
            return Err(Error::Usage(format!("{}: --method {name}: the scene has no such method or combination (it has {})", opts.scene.display(), known.join(", "))));
        }
    }
    for configuration in all.into_iter().filter(|c| opts.methods.is_empty() || opts.methods.contains(&c.name)) {
        let kind = registry::reference_kind(&configuration)?;
        let key = format!("{kind:?}");
        if !references.contains_key(&key) {
            references.insert(key.clone(), reference_image(&scene, opts.size, kind, opts.reference_spp, &opts.cache_dir, &opts.gpu)?);
        }
        let (reference, reference_label) = &references[&key];
        let points = registry::sweep(&configuration)?;
        let mut progress = crate::progress::Progress::new(&format!("chart {}", configuration.name));
        let total = points.len() as u64;
        for (i, (config, point)) in points.into_iter().enumerate() {
            progress.update(i as u64, total);
            let (image, frame_ms, passes, dev, bakes) = match measure(&scene, &point, opts) {
                Ok(m) => m,
                // A swept point beyond one of the method's limits for this scene (a finer
                // segmentation over its memory limit) is left out with its reason; the scene's
                // own configuration must run.
                Err(e @ (Error::Usage(_) | Error::Scene(_))) if i > 0 => {
                    let why = e.to_string();
                    eprintln!("chart: {config} left out: {why}");
                    skipped.push(format!("{config}: {why}"));
                    continue;
                }
                Err(e) => return Err(e),
            };
            device = dev;
            let metrics = metrics::compare(&image, reference, &CompareOptions::default())?;
            let bake_ms = bakes.iter().map(|b| b.ms).sum();
            let bake_bytes = bakes.iter().map(|b| b.bytes).sum();
            rows.push(ChartRow { method: configuration.name.clone(), config, frame_ms, passes, metrics, reference: reference_label.clone(), bake_ms, bake_bytes });
        }
        progress.finish();
    }
    let chart = Chart { scene: opts.scene.display().to_string(), device, size: opts.size, rows, skipped };
    let csv = chart.csv();
    std::fs::create_dir_all(&opts.cache_dir).map_err(|e| Error::Usage(format!("{}: {e}", opts.cache_dir.display())))?;
    let cached = opts.cache_dir.join(format!("chart-{}.csv", cache_key(&scene, opts.size, "chart")));
    crate::image_io::write_file(&cached, csv.as_bytes()).map_err(|e| Error::Usage(format!("{}: {e}", cached.display())))?;
    if let Some(p) = &opts.csv {
        crate::image_io::write_file(p, csv.as_bytes()).map_err(|e| Error::Usage(format!("{}: {e}", p.display())))?;
    }
    if let Some(p) = &opts.png {
        plot::draw(&chart, p)?;
    }
    Ok(chart)
}

const METRIC_COLUMNS: [&str; 6] = ["rmse", "rel_mse", "mean_bias", "p99_abs_error", "max_abs_error", "flip"];

fn metric_values(m: &Metrics) -> [f64; 6] {
    [m.rmse, m.rel_mse, m.mean_bias, m.p99_abs_error, m.max_abs_error, m.flip_mean]
}

impl Chart {
    /// Configurations on the Pareto front: no other is both faster and more accurate.
    pub fn pareto_front(&self) -> Vec<usize> {
        let mut idx: Vec<usize> = (0..self.rows.len()).collect();
        idx.sort_by(|&a, &b| self.rows[a].frame_ms.total_cmp(&self.rows[b].frame_ms));
        let mut best = f64::INFINITY;
        let mut front = Vec::new();
        for i in idx {
            let e = self.rows[i].metrics.rel_mse;
            if e < best {
                best = e;
                front.push(i);
            }
        }
        front
    }

    /// One row per configuration: times (frame and every pass seen in any row), then metrics.
    pub fn csv(&self) -> String {
        let mut pass_names: Vec<String> = Vec::new();
        for r in &self.rows {
            for (p, _) in &r.passes {
                if !pass_names.contains(p) {
                    pass_names.push(p.clone());
                }
            }
        }
        let mut s = String::from("method,config,device,width,height,reference,frame_ms,bake_ms,bake_bytes");
        for p in &pass_names {
            let _ = write!(s, ",pass:{}_ms", p.replace(',', ";"));
        }
        for m in METRIC_COLUMNS {
            let _ = write!(s, ",{m}");
        }
        s.push('\n');
        for r in &self.rows {
            let _ = write!(
                s,
                "{},{},{},{},{},{},{},{},{}",
                r.method,
                r.config.replace(',', ";"),
                self.device.replace(',', ";"),
                self.size.0,
                self.size.1,
                r.reference.replace(',', ";"),
                r.frame_ms,
                r.bake_ms,
                r.bake_bytes
            );
            for p in &pass_names {
                match r.passes.iter().find(|(n, _)| n == p) {
                    Some((_, ms)) => {
                        let _ = write!(s, ",{ms}");
                    }
                    None => s.push(','),
                }
            }
            for v in metric_values(&r.metrics) {
                let _ = write!(s, ",{v}");
            }
            s.push('\n');
        }
        s
    }
}

/// A configuration read back from a chart table, for `capture --max-error`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredConfig {
    pub method: String,
    pub config: String,
    pub frame_ms: f64,
    pub rel_mse: f64,
}

/// Parses the table `csv()` writes.
pub fn parse_csv(text: &str) -> Result<Vec<MeasuredConfig>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).ok_or_else(|| Error::Usage(format!("chart table has no `{name}` column")));
    let (cm, cc, cf, ce) = (col("method")?, col("config")?, col("frame_ms")?, col("rel_mse")?);
    let mut out = Vec::new();
    for (i, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let num = |c: usize| f.get(c).and_then(|v| v.parse::<f64>().ok()).ok_or_else(|| Error::Usage(format!("chart table row {}: column {c} is not a number", i + 2)));
        out.push(MeasuredConfig { method: f.get(cm).unwrap_or(&"").to_string(), config: f.get(cc).unwrap_or(&"").to_string(), frame_ms: num(cf)?, rel_mse: num(ce)? });
    }
    Ok(out)
}

/// The choice `capture --max-error` makes, and why.
#[derive(Clone, Debug, PartialEq)]
pub enum Choice {
    /// The cheapest configuration within the bound; `rejected` are the cheaper ones that weren't.
    Picked { config: MeasuredConfig, rejected: Vec<MeasuredConfig> },
    /// None is within the bound; the most accurate one is named.
    NoneQualifies { closest: MeasuredConfig },
}

pub fn choose(configs: &[MeasuredConfig], max_rel_mse: f64) -> Option<Choice> {
    let mut by_time: Vec<&MeasuredConfig> = configs.iter().collect();
    by_time.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    match by_time.iter().position(|c| c.rel_mse <= max_rel_mse) {
        Some(i) => Some(Choice::Picked { config: by_time[i].clone(), rejected: by_time[..i].iter().map(|c| (*c).clone()).collect() }),
        None => configs.iter().min_by(|a, b| a.rel_mse.total_cmp(&b.rel_mse)).map(|c| Choice::NoneQualifies { closest: c.clone() }),
    }
}

impl std::fmt::Display for Choice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Choice::Picked { config, rejected } => {
                write!(f, "picked `{}`: relative MSE {:.4} at {:.3} ms, the cheapest within the bound", config.config, config.rel_mse, config.frame_ms)?;
                for r in rejected {
                    write!(f, "; `{}` is cheaper ({:.3} ms) but its relative MSE is {:.4}", r.config, r.frame_ms, r.rel_mse)?;
                }
                Ok(())
            }
            Choice::NoneQualifies { closest } => {
                write!(f, "no configuration reaches the bound; the closest is `{}` with relative MSE {:.4} at {:.3} ms", closest.config, closest.rel_mse, closest.frame_ms)
            }
        }
    }
}

/// Where `chart` cached the table for this scene and size.
pub fn cached_table(scene: &Scene, size: (u32, u32), cache_dir: &Path) -> PathBuf {
    cache_dir.join(format!("chart-{}.csv", cache_key(scene, size, "chart")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(name: &str, ms: f64, e: f64) -> MeasuredConfig {
        MeasuredConfig { method: "m".into(), config: name.into(), frame_ms: ms, rel_mse: e }
    }

    #[test]
    fn cheapest_within_the_bound_is_chosen() {
        let configs = vec![cfg("slow exact", 9.0, 0.001), cfg("fast rough", 1.0, 0.2), cfg("middle", 3.0, 0.04)];
        match choose(&configs, 0.05).unwrap() {
            Choice::Picked { config, rejected } => {
                assert_eq!(config.config, "middle");
                assert_eq!(rejected, vec![cfg("fast rough", 1.0, 0.2)]);
            }
            c => panic!("{c:?}"),
        }
        assert_eq!(choose(&configs, 1e-4).unwrap(), Choice::NoneQualifies { closest: cfg("slow exact", 9.0, 0.001) });
        let text = choose(&configs, 0.05).unwrap().to_string();
        assert!(text.contains("picked `middle`") && text.contains("`fast rough` is cheaper"), "{text}");
    }

    #[test]
    fn csv_round_trips_and_pareto_front_is_monotone() {
        let m = |e: f64| Metrics { rmse: e, rel_mse: e, mean_bias: 0.0, p99_abs_error: e, max_abs_error: e, flip_mean: e, pixels: 4 };
        let row = |c: &str, ms: f64, e: f64| ChartRow {
            method: "m".into(),
            config: c.into(),
            frame_ms: ms,
            bake_ms: 0.0,
            bake_bytes: 0,
            passes: vec![("p".into(), ms * 0.5)],
            metrics: m(e),
            reference: "direct, 4 spp".into(),
        };
        let chart = Chart { scene: "s".into(), device: "dev, x".into(), size: (8, 8), rows: vec![row("a", 1.0, 0.5), row("b", 2.0, 0.6), row("c", 3.0, 0.1)], skipped: Vec::new() };
        assert_eq!(chart.pareto_front(), vec![0, 2]);
        let parsed = parse_csv(&chart.csv()).unwrap();
        assert_eq!(parsed, vec![cfg("a", 1.0, 0.5), cfg("b", 2.0, 0.6), cfg("c", 3.0, 0.1)]);
        assert!(chart.csv().lines().next().unwrap().contains("pass:p_ms"));
    }
}
