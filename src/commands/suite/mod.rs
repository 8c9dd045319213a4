//! `penumbra suite`: every method, at its defaults, over generated scenes nobody tuned it for
//! ([`crate::scene::generate`]), each against the path-traced reference it models (see
//! [`crate::lighting::ReferenceKind`]), supersampled so that the error is lighting and not
//! aliasing. A method that refuses a scene is recorded as a refusal; an error, a panic, a
//! non-finite pixel or a validation message as a failure: none stops the sweep.
//!
//! It writes to its output folder the scenes (`scenes/*.toml`), one CSV row per scene and
//! configuration (`suite.csv`, or `suite-K-of-N.csv` for a shard), and a Markdown summary
//! (`summary.md`) of every CSV in the folder, so shards run apart are summarised together; the
//! worst scenes of each method, and every scene a method failed on, are copied into `worst/`.

pub(crate) mod table;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use crate::backend::{Gpu, GpuDesc};
use crate::commands::chart::{self, ChartOptions, Measured};
use crate::error::{Error, Result};
use crate::lighting::{registry, Configuration, ReferenceKind, Terms};
use crate::metrics::{self, CompareOptions, Metrics};
use crate::reference::Sampler;
use crate::scene::generate::{self, Generated, Theme};
use crate::scene::Scene;
use crate::util::image_io::HdrImage;

pub use table::{summarise, Row, Status, Summary, Target};

#[derive(Clone, Debug)]
pub struct SuiteOptions {
    /// Scenes in the whole suite (all shards together).
    pub scenes: u64,
    pub seed: u64,
    /// This process runs the scenes whose index is `shard.0 − 1` modulo `shard.1` (1-based).
    pub shard: (u64, u64),
    pub size: (u32, u32),
    pub supersample: u32,
    /// Frames timed per configuration at most, and the seconds after which timing stops.
    pub frames: usize,
    pub timing_budget_s: f64,
    pub reference_spp: u32,
    pub reference_noise: f64,
    pub out: PathBuf,
    pub cache_dir: PathBuf,
    pub gpu: GpuDesc,
    /// Only these configurations (all of each scene's when empty).
    pub methods: Vec<String>,
    /// Scenes saved per method in `worst/`, by relative MSE (failures are all saved).
    pub worst: usize,
}

impl SuiteOptions {
    /// The indices this shard runs, in order.
    pub fn indices(&self) -> Vec<u64> {
        let (k, n) = self.shard;
        (0..self.scenes).filter(|i| i % n == k - 1).collect()
    }

    fn check(&self) -> Result<()> {
        let (k, n) = self.shard;
        if n == 0 || k == 0 || k > n {
            return Err(Error::Usage(format!("--shard {k}/{n}: expected K/N with 1 <= K <= N")));
        }
        crate::commands::supersample::supersampled_size(self.size, self.supersample)?;
        let known: Vec<&str> = registry::schemas()
            .iter()
            .map(|s| s.name)
            .chain(generate::COMBINATIONS)
            .collect();
        if let Some(m) = self.methods.iter().find(|m| !known.contains(&m.as_str())) {
            return Err(Error::Usage(format!(
                "--method {m}: no generated scene declares it; known: {}",
                known.join(", ")
            )));
        }
        Ok(())
    }

    fn csv_name(&self) -> String {
        match self.shard {
            (1, 1) => "suite.csv".into(),
            (k, n) => format!("suite-{k}-of-{n}.csv"),
        }
    }

    fn chart_options(&self, scene: &Path) -> ChartOptions {
        ChartOptions {
            scene: scene.to_path_buf(),
            size: self.size,
            frames: self.frames,
            timing_budget_s: self.timing_budget_s,
            // The suite measures each method as declared: nothing is swept.
            bake_limit_s: 0.0,
            reference_spp: self.reference_spp,
            reference_noise: self.reference_noise,
            reference_sampler: Sampler::Sobol,
            supersample: self.supersample,
            png: None,
            csv: None,
            cache_dir: self.cache_dir.clone(),
            gpu: self.gpu.clone(),
            methods: Vec::new(),
            frame: 0,
            // Generated scenes carry no asset cameras.
            camera: None,
        }
    }
}

/// What the suite ran on and when, written into every CSV row.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Provenance {
    pub device: String,
    pub driver: String,
    pub commit: String,
    pub date: String,
}

impl Provenance {
    fn probe(gpu: &GpuDesc) -> Result<Provenance> {
        let caps = Gpu::new(gpu)?.caps().clone();
        let git = |args: &[&str]| {
            std::process::Command::new("git")
                .args(args)
                .output()
                .ok()
                .filter(|o| o.status.success())
                .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        };
        // The commit of the working tree it runs in, marked when the tree has changes.
        let commit = match (
            git(&["rev-parse", "--short=12", "HEAD"]),
            git(&["status", "--porcelain", "--untracked-files=no"]),
        ) {
            (Some(c), Some(changes)) if !changes.is_empty() => format!("{c}+changes"),
            (Some(c), _) => c,
            (None, _) => "unknown".into(),
        };
        Ok(Provenance {
            device: caps.name,
            driver: format!("{} {}", caps.driver_name, caps.driver_info),
            commit,
            date: today(),
        })
    }
}

/// Today's UTC date as YYYY-MM-DD (days since 1970 to the civil calendar).
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// Runs this shard's scenes, writes its CSV and the scenes, then summarises every CSV in the
/// output folder into `summary.md` and copies the worst scenes. Returns the summary.
pub fn run(opts: &SuiteOptions) -> Result<Summary> {
    opts.check()?;
    let scenes_dir = opts.out.join("scenes");
    std::fs::create_dir_all(&scenes_dir).map_err(|e| Error::Usage(format!("{}: {e}", scenes_dir.display())))?;
    let provenance = Provenance::probe(&opts.gpu)?;
    let mut rows = Vec::new();
    let indices = opts.indices();
    for (n, &index) in indices.iter().enumerate() {
        let generated = generate::generate(opts.seed, index);
        crate::errln!(
            "suite: scene {} of {} in this shard: {}",
            n + 1,
            indices.len(),
            generated.name
        );
        let path = scenes_dir.join(format!("{}.toml", generated.name));
        crate::util::image_io::write_file(&path, generated.text.as_bytes())
            .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
        rows.extend(run_scene(&generated, &path, opts, &provenance));
        let csv = opts.out.join(opts.csv_name());
        crate::util::image_io::write_file(&csv, table::csv(&rows).as_bytes())
            .map_err(|e| Error::Usage(format!("{}: {e}", csv.display())))?;
    }
    let summary = table::summarise_dir(&opts.out)?;
    table::save_worst(&summary, &opts.out, opts.worst)?;
    let md = opts.out.join("summary.md");
    crate::util::image_io::write_file(&md, summary.markdown().as_bytes())
        .map_err(|e| Error::Usage(format!("{}: {e}", md.display())))?;
    Ok(summary)
}

/// One configuration's render, or why there is none.
struct Attempt {
    config: Configuration,
    kind: ReferenceKind,
    outcome: std::result::Result<Measured, Status>,
}

/// Every configuration of one scene, measured against its references: one row each.
pub fn run_scene(generated: &Generated, path: &Path, opts: &SuiteOptions, provenance: &Provenance) -> Vec<Row> {
    let row = |config: &str, status: Status| Row::new(opts.seed, generated, config, status, provenance);
    let scene = match Scene::from_file(path) {
        Ok(s) => s,
        Err(e) => return vec![row("(scene)", Status::Error(e.to_string()))],
    };
    let configs = match registry::configurations(&scene) {
        Ok(c) => c,
        Err(e) => return vec![row("(scene)", Status::Error(e.to_string()))],
    };
    let chart_opts = opts.chart_options(path);
    let attempts: Vec<Attempt> = configs
        .into_iter()
        .filter(|c| opts.methods.is_empty() || opts.methods.contains(&c.name))
        .map(|config| {
            let kind = registry::reference_kind(&config).unwrap_or(ReferenceKind::Direct);
            let start = std::time::Instant::now();
            let outcome = attempt(&scene, &config, &chart_opts);
            let status = outcome.as_ref().map_or_else(|s| s.name(), |_| "rendered");
            crate::errln!(
                "suite: {} {}: {status} in {:.1} s",
                generated.name,
                config.name,
                start.elapsed().as_secs_f64()
            );
            Attempt { config, kind, outcome }
        })
        .collect();
    judge(&scene, generated, &attempts, &chart_opts, opts, provenance)
}

/// Renders one configuration; a refusal, an error or a panic becomes its status.
fn attempt(scene: &Scene, config: &Configuration, opts: &ChartOptions) -> std::result::Result<Measured, Status> {
    match catch_unwind(AssertUnwindSafe(|| chart::measure(scene, config, opts))) {
        Ok(Ok(m)) => Ok(m),
        Ok(Err(e @ (Error::Usage(_) | Error::Scene(_)))) => Err(Status::Refused(e.to_string())),
        Ok(Err(e)) => Err(Status::Error(e.to_string())),
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic".into());
            Err(Status::Crash(what))
        }
    }
}

/// The image judged: the supersampled one when there is.
fn judged(m: &Measured) -> &HdrImage {
    m.supersampled.as_ref().unwrap_or(&m.image)
}

fn non_finite(m: &Measured) -> Option<String> {
    let bad = |img: &HdrImage| img.pixels.iter().position(|p| !p[..3].iter().all(|c| c.is_finite()));
    for (what, img) in [
        ("image", Some(&m.image)),
        ("supersampled image", m.supersampled.as_ref()),
    ] {
        if let Some(i) = img.and_then(bad) {
            let w = img.map_or(1, |im| im.width.max(1) as usize);
            return Some(format!(
                "the {what} has a non-finite value at pixel ({}, {})",
                i % w,
                i / w
            ));
        }
    }
    None
}

/// The render of an attempt that has one with finite pixels.
fn finite(a: &Attempt) -> Option<&Measured> {
    a.outcome.as_ref().ok().filter(|m| non_finite(m).is_none())
}

/// The rows of one scene: each rendered configuration compared with its reference; for a
/// configuration with an indirect part, its direct parts' own render also compared with that
/// reference (what the indirect term must improve on).
fn judge(
    scene: &Scene,
    generated: &Generated,
    attempts: &[Attempt],
    chart_opts: &ChartOptions,
    opts: &SuiteOptions,
    provenance: &Provenance,
) -> Vec<Row> {
    let mut references: Vec<(ReferenceKind, Result<(chart::ChartReference, Metrics)>)> = Vec::new();
    for a in attempts {
        if finite(a).is_none() || references.iter().any(|(k, _)| *k == a.kind) {
            continue;
        }
        let images: Vec<&HdrImage> = attempts
            .iter()
            .filter(|b| b.kind == a.kind)
            .filter_map(finite)
            .map(judged)
            .collect();
        let reference = chart::reference_image(scene, opts.size, a.kind, &images, chart_opts).and_then(|r| {
            let noise = chart::reference_noise(&r.image)?;
            Ok((r, noise))
        });
        references.push((a.kind, reference));
    }
    let mut rows = Vec::new();
    for a in attempts {
        let mut row = Row::new(opts.seed, generated, &a.config.name, Status::Ok, provenance);
        let m = match &a.outcome {
            Ok(m) => m,
            Err(status) => {
                row.status = status.clone();
                rows.push(row);
                continue;
            }
        };
        row.frame_ms = m.frame_ms;
        row.bake_ms = m.bakes.iter().fold(0.0, |total, b| total + b.ms);
        row.warnings = m.warnings.clone();
        if let Some(why) = non_finite(m) {
            row.status = Status::NonFinite(why);
        } else if let Some((_, reference)) = references.iter().find(|(k, _)| *k == a.kind) {
            match reference {
                Ok((r, noise)) => {
                    row.reference = r.label.clone();
                    row.noise_rel_mse = noise.rel_mse;
                    match metrics::compare(judged(m), &r.image.mean, &CompareOptions::default()) {
                        Ok(metrics) => row.metrics = Some(metrics),
                        Err(e) => row.status = Status::Error(e.to_string()),
                    }
                    row.direct_alone = direct_alone(&a.config, attempts, &r.image.mean);
                }
                Err(e) => row.status = Status::Error(format!("reference: {e}")),
            }
        }
        if !m.validation.is_empty() && row.status == Status::Ok {
            row.status = Status::Validation(m.validation.join(" | "));
        }
        rows.push(row);
    }
    rows
}

/// For a configuration with an indirect part: the configuration of its direct part alone
/// (measured in the same scene) against `reference`.
fn direct_alone(config: &Configuration, attempts: &[Attempt], reference: &HdrImage) -> Option<Metrics> {
    if config.parts.len() < 2 || !config.terms().contains(Terms::INDIRECT) {
        return None;
    }
    let direct = config.parts.iter().find(|p| p.terms.contains(Terms::DIRECT))?;
    let alone = attempts.iter().find(|a| a.config.name == direct.decl.name)?;
    let m = alone.outcome.as_ref().ok().filter(|m| non_finite(m).is_none())?;
    metrics::compare(judged(m), reference, &CompareOptions::default()).ok()
}

/// The generated scenes of a suite, for tests and tools: (index, scene) for `indices`.
pub fn scenes(seed: u64, indices: impl IntoIterator<Item = u64>) -> Vec<Generated> {
    indices.into_iter().map(|i| generate::generate(seed, i)).collect()
}

/// Every theme, for tests that pick scenes by theme.
pub fn themes() -> &'static [Theme] {
    &Theme::ALL
}
