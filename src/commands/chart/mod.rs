//! `penumbra chart`: every method the scene enables, at every point of its quality sweep, timed
//! with GPU timestamps and measured against the scene's path-traced reference; a log–log plot of
//! error against time with the Pareto front, and a CSV with every per-pass time and metric.
//!
//! The reference is rendered once per (scene content, size, reference settings) and cached in
//! `.penumbra-cache/`, as is the chart's table, which `capture --max-error` reads. The content is
//! the scene as seen: with `--camera N` the asset camera it is seen through, so each camera has
//! its own entries.
//!
//! Every configuration is rendered first; then each reference renders until its own noise is
//! well below the errors it judges: its expected contribution to the relative MSE (see
//! [`reference_noise`]) at most `reference_noise` (0.1 by default) times the smallest relative
//! MSE among the configurations measured against it, from 32 spp on, with `reference_spp` as
//! the cap. Beside every metric the table gives what an exact method would score against that
//! reference ([`reference_noise`]): the reference's own error.
//!
//! With `supersample` N > 1 each configuration is also rendered at N× the size in each axis and
//! box-filtered down, so that its pixels average their footprint as the reference's do; the
//! table keeps both the pixel-centre metrics (`rmse`, …) and the supersampled ones (`ss_rmse`,
//! …), so aliasing stays visible, and the plot shows the supersampled ones.

pub mod layout;
pub(crate) mod plot;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::backend::{Gpu, GpuDesc};
use crate::bake::{BakeReport, Baker};
use crate::error::{Error, Result};
use crate::lighting::{registry, Configuration, ReferenceKind};
use crate::metrics::{self, CompareOptions, Metrics};
use crate::reference::{LightPaths, ReferenceImage, ReferenceRenderer, Sampler, Settings, Stop, MIN_ADAPTIVE_SPP};
use crate::renderer::{FrameOutput, Renderer};
use crate::scene::Scene;
use crate::util::image_io::HdrImage;
use crate::util::timing::summarise;

#[derive(Clone, Debug)]
pub struct ChartOptions {
    pub scene: PathBuf,
    pub size: (u32, u32),
    /// Frames timed per configuration at most (the median is reported).
    pub frames: usize,
    /// Seconds of timed frames per configuration after which timing stops, once
    /// [`MIN_TIMED_FRAMES`] are timed (0: always `frames`). A configuration that takes a second a
    /// frame on a CPU device is timed over a few frames instead of `frames`.
    pub timing_budget_s: f64,
    /// Seconds after which a swept point still baking (counted from its start) is stopped and
    /// left out, with why (0: no limit). The scene's own configuration is never stopped: a
    /// scene whose bakes a sweep would multiply (a finer light-map, a slower baker) still charts
    /// in bounded time.
    pub bake_limit_s: f64,
    /// Samples per pixel of the reference: the cap when `reference_noise` > 0.
    pub reference_spp: u32,
    /// The reference renders until its noise's relative MSE is at most this fraction of the
    /// smallest relative MSE it judges (0: exactly `reference_spp`).
    pub reference_noise: f64,
    /// Where the reference's random draws come from; [`Sampler::Sobol`] (the command line's
    /// default) reaches the noise the chart asks for in fewer samples.
    pub reference_sampler: Sampler,
    /// Also render each configuration at this many times the size and box-filter it down (1: no).
    pub supersample: u32,
    pub png: Option<PathBuf>,
    pub csv: Option<PathBuf>,
    pub cache_dir: PathBuf,
    pub gpu: GpuDesc,
    /// Only these methods or combinations (all of the scene's when empty).
    pub methods: Vec<String>,
    /// The frame compared (its wind, light motion and light board; 0: the scene as written):
    /// each configuration renders frames 0 … N and is judged on frame N, against the reference
    /// traced at frame N.
    pub frame: u64,
    /// View through camera N of those the scene's assets carry instead of the scene's own
    /// (`--camera N`, [`Scene::choose_camera`]).
    pub camera: Option<usize>,
}

/// One configuration of one method, measured.
#[derive(Clone, Debug, PartialEq)]
pub struct ChartRow {
    pub method: String,
    /// The sweep point, e.g. `forward` or `lpv grid=32 iterations=8`.
    pub config: String,
    /// Median GPU milliseconds of the whole frame.
    pub frame_ms: f64,
    /// Frames the medians are over.
    pub frames_timed: usize,
    /// Median GPU milliseconds per pass.
    pub passes: Vec<(String, f64)>,
    /// Against the reference, the method's pixel centres.
    pub metrics: Metrics,
    /// Against the reference, the method supersampled and box-filtered (with `supersample` > 1).
    pub supersampled: Option<Metrics>,
    /// What an exact method would score against this reference: its own error.
    pub reference_noise: Metrics,
    /// What the method left out of its frame ([`crate::lighting::LightingMethod::warnings`]).
    pub warnings: Vec<String>,
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
    /// 1: the method's pixel centres; N: supersampled N×N and box-filtered (also in the rows).
    pub supersample: u32,
    pub rows: Vec<ChartRow>,
    /// Swept points left out, with why (a limit of the method on this scene).
    pub skipped: Vec<String>,
    /// Configurations whose image held NaN or infinity, with the first such pixel: no metric
    /// can judge them, so they are not rows.
    pub non_finite: Vec<String>,
    /// The frame compared ([`ChartOptions::frame`]).
    pub frame: u64,
    /// The assets' camera it was measured through ([`ChartOptions::camera`]); none: the
    /// scene's own.
    pub camera: Option<usize>,
}

/// FNV-1a: a stable content hash for cache keys (std's hasher may change between releases).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// A key naming everything a cached result depends on: the parsed scene (so comments and
/// formatting don't matter, but every value does), the size, and the extra settings.
///
/// The scene is hashed with `--camera N` applied, so the key holds the camera the images are
/// seen through, by value: two cameras never share an entry, and the scene's own camera keeps
/// the key it had before cameras could be chosen. A chosen camera equal to the scene's own
/// shares its entries, rightly: the pictures are the same.
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

/// The tracer settings for a kind of reference (direct, bounces, indirect only) and its label.
pub fn reference_settings(kind: ReferenceKind, spp: u32, sampler: Sampler) -> (Settings, String) {
    let (paths, bounces, label) = match kind {
        ReferenceKind::Direct => (LightPaths::Direct, 0, "direct"),
        ReferenceKind::Bounces(k) => (LightPaths::All, k, "bounces"),
        ReferenceKind::Indirect(k) => (LightPaths::Indirect, k, "bounces (indirect only)"),
    };
    let label = if kind == ReferenceKind::Direct {
        label.to_string()
    } else {
        format!("{bounces} {label}")
    };
    let label = if sampler == Sampler::Independent {
        label
    } else {
        format!("{label}, {}", sampler.name())
    };
    (
        Settings {
            spp,
            bounces,
            paths,
            sampler,
            ..Settings::default()
        },
        label,
    )
}

/// A chart's reference: its mean, its standard error, and the label naming kind and spp.
pub struct ChartReference {
    pub image: ReferenceImage,
    pub label: String,
}

/// The relative MSE the reference's noise adds to a comparison (see [`reference_noise`]).
fn noise_rel_mse(image: &ReferenceImage) -> f64 {
    let mut sum = 0.0;
    for (m, s) in image.mean.pixels.iter().zip(&image.standard_error.pixels) {
        for c in 0..3 {
            sum += (s[c] as f64).powi(2) / ((m[c] as f64).powi(2) + crate::metrics::stats::REL_MSE_EPSILON);
        }
    }
    sum / (3 * image.mean.pixels.len().max(1)) as f64
}

/// How far the reference's noise is from good enough (at most 1: good enough) for judged
/// images whose smallest relative MSE and p99 error are `smallest_rel` and `smallest_p99`:
/// the larger of √(noise_rel / (F·smallest_rel)) and noise_p99 / (√F·smallest_p99). A p99 of
/// 0/0 (every judged image and the noise exact at 99 % of pixels) does not count.
pub fn stop_ratio(smallest_rel: f64, smallest_p99: f64, noise_rel: f64, noise_p99: f64, fraction: f64) -> f64 {
    let rel = (noise_rel / (fraction * smallest_rel)).sqrt();
    let p99 = noise_p99 / (fraction.sqrt() * smallest_p99);
    rel.max(if p99.is_nan() { 0.0 } else { p99 })
}

/// The reference for this scene and kind, good enough for `judged` (the images measured
/// against it): from the cache when the cached one is, or rendered and cached.
pub fn reference_image(
    scene: &Scene,
    size: (u32, u32),
    kind: ReferenceKind,
    judged: &[&HdrImage],
    opts: &ChartOptions,
) -> Result<ChartReference> {
    let (settings, label) = reference_settings(kind, opts.reference_spp, opts.reference_sampler);
    // Frame 0 keeps the key it had before frames could be charted, so caches stay valid.
    let frame_key = if opts.frame == 0 {
        String::new()
    } else {
        format!("|frame {}", opts.frame)
    };
    let key = cache_key(
        scene,
        size,
        &format!("{settings:?}|noise {}{frame_key}", opts.reference_noise),
    );
    let path = opts.cache_dir.join(format!("reference-{key}.exr"));
    let (se_path, spp_path) = (crate::reference::stderr_path(&path), path.with_extension("spp"));
    // The ratio of the reference's noise to the error it may have: at most 1 is good enough.
    // Relative MSE (squared): the noise's at most F times the smallest judged. The 99th
    // percentile of the per-pixel error (linear): the noise's, simulated as the CSV's
    // `ref_noise_p99_abs_error` is, at most √F times the smallest judged, which keeps the
    // noise's share of a judged p99 as small as its share of a relative MSE. The maximum is not
    // judged: the largest of N noisy pixels keeps growing with N.
    let ratio = |img: &ReferenceImage| -> f64 {
        let stats: Vec<_> = judged
            .iter()
            .map(|t| crate::metrics::stats::radiance_stats(&t.pixels, &img.mean.pixels))
            .collect();
        let smallest_rel = stats.iter().map(|s| s.rel_mse).fold(f64::INFINITY, f64::min);
        let smallest_p99 = stats.iter().map(|s| s.p99_abs_error).fold(f64::INFINITY, f64::min);
        let noise_p99 = crate::metrics::stats::radiance_stats(
            &noisy_copy(&img.mean, &img.standard_error, NOISE_SEED).pixels,
            &img.mean.pixels,
        )
        .p99_abs_error;
        stop_ratio(
            smallest_rel,
            smallest_p99,
            noise_rel_mse(img),
            noise_p99,
            opts.reference_noise,
        )
    };
    let cached = || -> Option<ReferenceImage> {
        let (mean, standard_error) = (HdrImage::read_exr(&path).ok()?, HdrImage::read_exr(&se_path).ok()?);
        let spp = std::fs::read_to_string(&spp_path).ok()?.trim().parse().ok()?;
        ((mean.width, mean.height) == size && (standard_error.width, standard_error.height) == size).then_some(
            ReferenceImage {
                mean,
                standard_error,
                spp,
                seconds: 0.0,
            },
        )
    };
    let labelled = |image: ReferenceImage| {
        let label = format!("{label}, {} spp", image.spp);
        ChartReference { image, label }
    };
    if let Some(image) = cached() {
        if image.spp >= opts.reference_spp || (opts.reference_noise > 0.0 && ratio(&image) <= 1.0) {
            return Ok(labelled(image));
        }
    }
    crate::errln!(
        "chart: rendering the reference ({label}, up to {} spp) for {}",
        opts.reference_spp,
        scene.source
    );
    let mut tracer = ReferenceRenderer::at_frame(Gpu::new(&opts.gpu)?, scene, size, opts.frame)?;
    let mut progress = crate::util::progress::Progress::new("reference (spp)");
    let mut update = |done: u32, total: u32| progress.update(done as u64, total as u64);
    let image = if opts.reference_noise > 0.0 {
        let mut check = |img: &ReferenceImage| ratio(img);
        tracer.render_until(
            &settings,
            Some(Stop {
                min_spp: MIN_ADAPTIVE_SPP,
                check: &mut check,
            }),
            &mut update,
        )?
    } else {
        tracer.render(&settings, &mut update)?
    };
    progress.finish();
    let dir = &opts.cache_dir;
    std::fs::create_dir_all(dir).map_err(|e| Error::Usage(format!("{}: {e}", dir.display())))?;
    image.mean.write_exr(&path)?;
    image.standard_error.write_exr(&se_path)?;
    crate::util::image_io::write_file(&spp_path, image.spp.to_string().as_bytes())
        .map_err(|e| Error::Usage(format!("{}: {e}", spp_path.display())))?;
    Ok(labelled(image))
}

/// What an exact method would score against this reference: the reference's own error in
/// each metric. With s a pixel's standard error in one channel, r its mean, N pixels:
/// - `rmse` = sqrt(Σ s² / 3N), the RMSE an exact image has in expectation (E (r̂ − r)² = s²);
/// - `rel_mse` = Σ s² / (r² + 0.01) / 3N, the relative MSE it adds in expectation;
/// - `mean_bias` = sqrt(Σ s²) / 3N, the standard deviation of the mean bias it causes;
/// - `p99_abs_error`, `max_abs_error`, `flip`, `mean_ratio` and `scaled_rel_rmse`: those
///   metrics of the reference against the
///   reference plus Gaussian noise of its standard error (a fixed seed; clamped at 0), an
///   exact image as a reference this noisy would see it.
///
/// Infinite where a standard error is (one sample per pixel).
pub fn reference_noise(reference: &ReferenceImage) -> Result<Metrics> {
    let (mean, se) = (&reference.mean, &reference.standard_error);
    let n = (3 * mean.pixels.len().max(1)) as f64;
    let sum_sq: f64 = se
        .pixels
        .iter()
        .map(|s| (0..3).map(|c| (s[c] as f64).powi(2)).sum::<f64>())
        .sum();
    if !sum_sq.is_finite() {
        let inf = f64::INFINITY;
        return Ok(Metrics {
            rmse: inf,
            rel_mse: inf,
            mean_bias: inf,
            p99_abs_error: inf,
            max_abs_error: inf,
            flip_mean: inf,
            mean_ratio: inf,
            scaled_rel_rmse: inf,
            pixels: mean.pixels.len(),
        });
    }
    let simulated = metrics::compare(&noisy_copy(mean, se, NOISE_SEED), mean, &CompareOptions::default())?;
    Ok(Metrics {
        rmse: (sum_sq / n).sqrt(),
        rel_mse: noise_rel_mse(reference),
        mean_bias: sum_sq.sqrt() / n,
        ..simulated
    })
}

/// The seed of the simulated noise behind `ref_noise_p99_abs_error` and the stop rule's p99.
const NOISE_SEED: u64 = 0x5eed;

/// `mean` plus independent Gaussian noise of standard deviation `se` in each channel (a fixed
/// `seed`; Box–Muller on a SplitMix64 stream), clamped at 0 as radiance is.
pub fn noisy_copy(mean: &HdrImage, se: &HdrImage, seed: u64) -> HdrImage {
    let mut state = seed;
    let mut uniform = || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut out = mean.clone();
    for (p, s) in out.pixels.iter_mut().zip(&se.pixels) {
        for c in 0..3 {
            let (u1, u2) = (uniform(), uniform());
            let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            p[c] = (p[c] as f64 + s[c] as f64 * z).max(0.0) as f32;
        }
    }
    out
}

/// One configuration rendered and timed.
pub struct Measured {
    /// At the pixel centres, at the chart's size.
    pub image: HdrImage,
    /// Supersampled and box-filtered to the chart's size (with `supersample` > 1).
    pub supersampled: Option<HdrImage>,
    pub frame_ms: f64,
    pub frames_timed: usize,
    pub passes: Vec<(String, f64)>,
    pub device: String,
    pub bakes: Vec<BakeReport>,
    pub warnings: Vec<String>,
    /// What the validation layer reported while it ran (empty without validation).
    pub validation: Vec<String>,
}

/// Frames a configuration is timed over at least (fewer only when `--frames` asks for fewer).
pub const MIN_TIMED_FRAMES: usize = 3;

/// Whether timing should go on after `timed` frames that took `elapsed_s` of wall time.
pub fn keep_timing(timed: usize, elapsed_s: f64, frames: usize, budget_s: f64) -> bool {
    timed < frames && (timed < MIN_TIMED_FRAMES || budget_s <= 0.0 || elapsed_s < budget_s)
}

/// Renders frames 0 … `frames` − 1, so that the next one rendered is frame `frames`.
fn advance(renderer: &mut Renderer, camera: &crate::scene::Camera, frames: u64) -> Result<()> {
    for _ in 0..frames {
        renderer.render(camera, FrameOutput::None)?;
    }
    Ok(())
}

/// The frames a configuration renders at least: those before the judged frame, the judged one,
/// the fewest timed, and the supersampled ones. A configuration whose estimate passes a minute
/// over these warns before its large allocations.
fn frames_at_least(opts: &ChartOptions) -> usize {
    let judged = usize::try_from(opts.frame).unwrap_or(usize::MAX).saturating_add(1);
    let timed = MIN_TIMED_FRAMES.min(opts.frames.max(1));
    let supersampled = if opts.supersample > 1 { judged } else { 0 };
    judged.saturating_add(timed).saturating_add(supersampled)
}

/// Renders and times one configuration (timed at the chart's size only).
pub fn measure(scene: &Scene, config: &Configuration, opts: &ChartOptions) -> Result<Measured> {
    let bakes = Baker::new(Some(opts.cache_dir.join("bake")));
    let gpu = Gpu::new(&opts.gpu)?;
    let mut renderer = Renderer::for_run(
        gpu,
        scene.clone(),
        config.clone(),
        opts.size,
        bakes,
        frames_at_least(opts),
    )?;
    let device = renderer.gpu.caps().name.clone();
    let camera = renderer.scene.camera.clone();
    advance(&mut renderer, &camera, opts.frame)?;
    let image = renderer
        .render(&camera, FrameOutput::Readback)?
        .image
        .ok_or_else(|| Error::Internal("readback returned no image".into()))?;
    let warnings = renderer.method_warnings()?;
    let mut timings = Vec::new();
    let start = std::time::Instant::now();
    while keep_timing(
        timings.len(),
        start.elapsed().as_secs_f64(),
        opts.frames.max(1),
        opts.timing_budget_s,
    ) {
        let frame = renderer.profile(&camera, 1)?;
        if frame.is_empty() {
            // A device without timestamps: nothing to time.
            break;
        }
        timings.extend(frame);
    }
    let frames_timed = timings.len();
    let stats = summarise(&timings);
    let frame_ms = stats
        .iter()
        .find(|s| s.name == "frame")
        .map(|s| s.median_ms)
        .unwrap_or(f64::NAN);
    let passes = stats
        .into_iter()
        .filter(|s| s.name != "frame")
        .map(|s| (s.name, s.median_ms))
        .collect();
    let bakes = renderer.bakes.clone();
    let mut validation = renderer.gpu.validation_log().take();
    drop(renderer);
    let supersampled = if opts.supersample > 1 {
        let size = crate::commands::supersample::supersampled_size(opts.size, opts.supersample)?;
        let mut big = Renderer::with_configuration(
            Gpu::new(&opts.gpu)?,
            scene.clone(),
            config.clone(),
            size,
            1,
            Baker::new(Some(opts.cache_dir.join("bake"))),
        )?;
        let camera = big.scene.camera.clone();
        advance(&mut big, &camera, opts.frame)?;
        let image = big
            .render(&camera, FrameOutput::Readback)?
            .image
            .ok_or_else(|| Error::Internal("readback returned no image".into()))?;
        validation.extend(big.gpu.validation_log().take());
        Some(crate::commands::supersample::box_filter(&image, opts.supersample)?)
    } else {
        None
    };
    Ok(Measured {
        image,
        supersampled,
        frame_ms,
        frames_timed,
        passes,
        device,
        bakes,
        warnings,
        validation,
    })
}

/// A chart with what it measured: each row's image (the one its plotted metrics judge) and
/// the references.
pub struct ChartRun {
    pub chart: Chart,
    /// One per row of `chart.rows`.
    pub images: Vec<HdrImage>,
    pub references: Vec<ChartReference>,
    /// For each row, its reference's index in `references`.
    pub reference_of: Vec<usize>,
}

pub fn run(opts: &ChartOptions) -> Result<Chart> {
    run_keeping_images(opts).map(|r| r.chart)
}

/// The first pixel of `image` with a non-finite channel, as (x, y).
fn non_finite_pixel(image: &HdrImage) -> Option<(u32, u32)> {
    let w = image.width.max(1) as usize;
    let i = image
        .pixels
        .iter()
        .position(|p| !p[..3].iter().all(|c| c.is_finite()))?;
    Some(((i % w) as u32, (i / w) as u32))
}

/// [`run`], keeping the images the rows were measured on.
pub fn run_keeping_images(opts: &ChartOptions) -> Result<ChartRun> {
    let overrides = crate::scene::SceneOverrides {
        camera: opts.camera,
        ..Default::default()
    };
    let scene = crate::commands::capture::load_scene(Some(&opts.scene), &overrides)?;
    check_options(opts)?;
    let mut device = String::new();
    let all = chosen_configurations(&scene, opts)?;
    let swept = sweep_each(all, &scene)?;
    let (measured, skipped) = measure_all(&scene, swept, opts)?;
    let (keys, references) = references_for(&scene, &measured, opts)?;
    let (mut rows, mut images, mut reference_of, mut non_finite) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (method, config, kind, m) in measured {
        device = m.device.clone();
        if let Some((x, y)) = non_finite_pixel(&m.image).or_else(|| m.supersampled.as_ref().and_then(non_finite_pixel))
        {
            eprintln!("chart: {config} left out: a non-finite value at pixel ({x}, {y})");
            non_finite.push(format!(
                "{config}: a non-finite value (NaN or infinity) at pixel ({x}, {y})"
            ));
            continue;
        }
        let r = keys[&format!("{kind:?}")];
        let (reference, noise) = &references[r];
        let metrics = metrics::compare(&m.image, &reference.image.mean, &CompareOptions::default())?;
        let supersampled = m
            .supersampled
            .as_ref()
            .map(|img| metrics::compare(img, &reference.image.mean, &CompareOptions::default()))
            .transpose()?;
        rows.push(ChartRow {
            method,
            config,
            frame_ms: m.frame_ms,
            frames_timed: m.frames_timed,
            passes: m.passes,
            metrics,
            supersampled,
            reference_noise: noise.clone(),
            warnings: m.warnings,
            reference: reference.label.clone(),
            // A fold from +0: an empty float sum is -0, which the CSV would print as "-0".
            bake_ms: m.bakes.iter().fold(0.0, |sum, b| sum + b.ms),
            bake_bytes: m.bakes.iter().map(|b| b.bytes).sum(),
        });
        images.push(m.supersampled.unwrap_or(m.image));
        reference_of.push(r);
    }
    let chart = Chart {
        scene: opts.scene.display().to_string(),
        device,
        size: opts.size,
        supersample: opts.supersample.max(1),
        rows,
        skipped,
        non_finite,
        frame: opts.frame,
        camera: opts.camera,
    };
    write_outputs(&chart, &scene, opts)?;
    Ok(ChartRun {
        chart,
        images,
        references: references.into_iter().map(|(r, _)| r).collect(),
        reference_of,
    })
}

/// Refuses a timing budget, bake limit or reference noise that is not a number of at least 0,
/// and a supersampled size over the limit.
fn check_options(opts: &ChartOptions) -> Result<()> {
    if !(opts.timing_budget_s.is_finite() && opts.timing_budget_s >= 0.0) {
        return Err(Error::Usage(format!(
            "--timing-budget {}: expected seconds, at least 0 (0: every --frames frame)",
            opts.timing_budget_s
        )));
    }
    if !(opts.bake_limit_s.is_finite() && opts.bake_limit_s >= 0.0) {
        return Err(Error::Usage(format!(
            "--bake-limit {}: expected seconds, at least 0 (0: no limit)",
            opts.bake_limit_s
        )));
    }
    if !(opts.reference_noise.is_finite() && opts.reference_noise >= 0.0) {
        return Err(Error::Usage(format!(
            "--reference-noise {}: expected a fraction of at least 0 (0: exactly --reference-spp)",
            opts.reference_noise
        )));
    }
    crate::commands::supersample::supersampled_size(opts.size, opts.supersample)?;
    Ok(())
}

/// The scene's configurations that `--method` chose (all without it; a scene that declares no
/// method takes any by name, [`registry::undeclared`]); an unknown name is an error listing the
/// known ones.
fn chosen_configurations(scene: &Scene, opts: &ChartOptions) -> Result<Vec<Configuration>> {
    let mut all = registry::configurations(scene)?;
    for name in &opts.methods {
        if all.iter().any(|c| c.name == *name) {
            continue;
        }
        match registry::undeclared(scene, name) {
            Some(c) => all.push(c),
            None => {
                let offered = registry::offered(scene)?;
                let known: Vec<&str> = offered.iter().map(|c| c.name.as_str()).collect();
                return Err(Error::Usage(format!(
                    "{}: --method {name}: the scene has no such method or combination (it has {})",
                    opts.scene.display(),
                    known.join(", ")
                )));
            }
        }
    }
    Ok(all
        .into_iter()
        .filter(|c| opts.methods.is_empty() || opts.methods.contains(&c.name))
        .collect())
}

/// Each configuration's name, reference kind and swept points (name, configuration), with the
/// defaults derived from the scene said once.
type Swept = Vec<(String, ReferenceKind, Vec<(String, Configuration)>)>;

fn sweep_each(all: Vec<Configuration>, scene: &Scene) -> Result<Swept> {
    // Every configuration first, so that each reference knows the errors it must resolve.
    let mut swept = Vec::new();
    for configuration in all {
        // Defaults derived from the scene are part of what is measured: said once, swept around.
        let (configuration, notes) = registry::plan(&configuration, scene)?;
        for line in notes {
            crate::errln!("{line}");
        }
        let kind = registry::reference_kind(&configuration)?;
        swept.push((configuration.name.clone(), kind, registry::sweep(&configuration)?));
    }
    Ok(swept)
}

/// Runs `work` with this thread's bakes asked to stop once `limit_s` seconds have passed
/// (0: no limit); they stop at their next check and return [`Error::Cancelled`].
fn with_bake_limit<T>(limit_s: f64, work: impl FnOnce() -> Result<T>) -> Result<T> {
    use crate::util::progress::{cancel_this_thread, Cancel};
    use std::sync::mpsc::{channel, RecvTimeoutError};
    let Some(limit) = (limit_s > 0.0)
        .then(|| std::time::Duration::try_from_secs_f64(limit_s).ok())
        .flatten()
    else {
        return work();
    };
    let cancel = Cancel::new();
    let (done, finished) = channel::<()>();
    let timer = {
        let cancel = cancel.clone();
        std::thread::spawn(move || {
            if let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(limit) {
                cancel.cancel();
            }
        })
    };
    cancel_this_thread(Some(cancel));
    let out = work();
    cancel_this_thread(None);
    drop(done);
    // The timer returns as soon as `done` is dropped.
    let _ = timer.join();
    out
}

/// A measured point: method, configuration name, reference kind, measurement.
type MeasuredPoint = (String, String, ReferenceKind, Measured);

/// Renders and times every swept point; a point past the method's limits for this scene (not
/// the scene's own configuration) is left out with its reason, in the second list.
fn measure_all(scene: &Scene, swept: Swept, opts: &ChartOptions) -> Result<(Vec<MeasuredPoint>, Vec<String>)> {
    let mut skipped: Vec<String> = Vec::new();
    let total = swept.iter().map(|(_, _, p)| p.len() as u64).sum();
    let mut progress = crate::util::progress::Progress::new("chart (configurations)");
    let mut measured: Vec<MeasuredPoint> = Vec::new();
    let mut done = 0;
    for (method, kind, points) in swept {
        for (i, (config, point)) in points.into_iter().enumerate() {
            progress.update(done, total);
            done += 1;
            // The scene's own configuration runs however long its bakes take.
            let limit = if i > 0 { opts.bake_limit_s } else { 0.0 };
            match with_bake_limit(limit, || measure(scene, &point, opts)) {
                Ok(m) => measured.push((method.clone(), config, kind, m)),
                Err(Error::Cancelled(what)) if i > 0 => {
                    let why = format!(
                        "its bake ({what}) ran past --bake-limit {} s and was stopped",
                        opts.bake_limit_s
                    );
                    progress.finish();
                    eprintln!("chart: {config} left out: {why}");
                    skipped.push(format!("{config}: {why}"));
                }
                // A swept point beyond one of the method's limits for this scene (a finer
                // segmentation over its memory limit) is left out with its reason; the scene's
                // own configuration must run.
                Err(e @ (Error::Usage(_) | Error::Scene(_))) if i > 0 => {
                    let why = e.to_string();
                    progress.finish();
                    eprintln!("chart: {config} left out: {why}");
                    skipped.push(format!("{config}: {why}"));
                }
                Err(e) => return Err(e),
            }
        }
    }
    progress.update(done, total);
    progress.finish();
    Ok((measured, skipped))
}

/// One reference per kind, and where each kind's is in the list.
type References = (BTreeMap<String, usize>, Vec<(ChartReference, Metrics)>);

fn references_for(scene: &Scene, measured: &[MeasuredPoint], opts: &ChartOptions) -> Result<References> {
    // One reference per kind, asked for the error the images it judges need (the supersampled
    // ones when there are: those are the lighting errors the chart shows).
    let mut keys: BTreeMap<String, usize> = BTreeMap::new();
    let mut references: Vec<(ChartReference, Metrics)> = Vec::new();
    for (_, _, kind, _) in measured {
        let key = format!("{kind:?}");
        if keys.contains_key(&key) {
            continue;
        }
        let judged: Vec<&HdrImage> = measured
            .iter()
            .filter(|(_, _, k, m)| k == kind && non_finite_pixel(judged_image(m)).is_none())
            .map(|(_, _, _, m)| judged_image(m))
            .collect();
        if judged.is_empty() {
            continue;
        }
        let reference = reference_image(scene, opts.size, *kind, &judged, opts)?;
        let noise = reference_noise(&reference.image)?;
        keys.insert(key, references.len());
        references.push((reference, noise));
    }
    Ok((keys, references))
}

/// The chart's CSV into the cache (for `capture --max-error`, frame 0 only) and, as asked, beside
/// the PNG.
fn write_outputs(chart: &Chart, scene: &Scene, opts: &ChartOptions) -> Result<()> {
    let csv = chart.csv();
    // `capture --max-error` renders the scene as written, so it reads the frame-0 table only; a
    // chart of a later frame must not replace it.
    if opts.frame == 0 {
        std::fs::create_dir_all(&opts.cache_dir)
            .map_err(|e| Error::Usage(format!("{}: {e}", opts.cache_dir.display())))?;
        let cached = cached_table(scene, opts.size, &opts.cache_dir);
        crate::util::image_io::write_file(&cached, csv.as_bytes())
            .map_err(|e| Error::Usage(format!("{}: {e}", cached.display())))?;
    }
    if let Some(p) = &opts.csv {
        crate::util::image_io::write_file(p, csv.as_bytes())
            .map_err(|e| Error::Usage(format!("{}: {e}", p.display())))?;
    }
    if let Some(p) = &opts.png {
        plot::draw(chart, p)?;
    }
    Ok(())
}

/// The image a row's plotted metrics judge: the supersampled one when there is.
fn judged_image(m: &Measured) -> &HdrImage {
    m.supersampled.as_ref().unwrap_or(&m.image)
}

const METRIC_COLUMNS: [&str; 8] = [
    "rmse",
    "rel_mse",
    "mean_bias",
    "p99_abs_error",
    "max_abs_error",
    "flip",
    "mean_ratio",
    "scaled_rel_rmse",
];

fn metric_values(m: &Metrics) -> [f64; 8] {
    [
        m.rmse,
        m.rel_mse,
        m.mean_bias,
        m.p99_abs_error,
        m.max_abs_error,
        m.flip_mean,
        m.mean_ratio,
        m.scaled_rel_rmse,
    ]
}

impl ChartRow {
    /// The metrics the plot shows: the supersampled ones when there are, else the pixel centres'.
    pub fn lighting_metrics(&self) -> &Metrics {
        self.supersampled.as_ref().unwrap_or(&self.metrics)
    }
}

impl Chart {
    /// Which comparison the plotted error is, for titles.
    pub fn comparison(&self) -> String {
        let how = if self.supersample > 1 {
            format!(
                "method supersampled {0}x{0} and box-filtered, as the reference averages each pixel (lighting error)",
                self.supersample
            )
        } else {
            "method at pixel centres, reference averaged over each pixel (aliasing included)".to_string()
        };
        how + &self.view_note()
    }

    /// ", camera N" when seen through an asset's camera, ", frame N" when the chart compares a
    /// frame other than the first.
    fn view_note(&self) -> String {
        let mut note = String::new();
        if let Some(n) = self.camera {
            let _ = write!(note, ", camera {n}");
        }
        if self.frame != 0 {
            let _ = write!(note, ", frame {}", self.frame);
        }
        note
    }

    /// The camera the chart was measured through, as the CSV's `camera` column has it: `scene`
    /// (the scene's own) or N (`--camera N`).
    pub fn camera_column(&self) -> String {
        self.camera.map_or_else(|| "scene".to_owned(), |n| n.to_string())
    }

    /// The camera in words, for pages: the scene's own, or the assets' camera N.
    pub fn camera_name(&self) -> String {
        match self.camera {
            None => "the scene's own".to_owned(),
            Some(n) => format!("camera {n} of the scene's assets (--camera {n})"),
        }
    }

    /// [`comparison`](Self::comparison) in a few words.
    pub fn short_comparison(&self) -> String {
        let how = if self.supersample > 1 {
            format!("method supersampled {0}x{0}, box-filtered", self.supersample)
        } else {
            "method at pixel centres".to_string()
        };
        how + &self.view_note()
    }

    /// Configurations on the Pareto front: no other is both faster and more accurate.
    pub fn pareto_front(&self) -> Vec<usize> {
        let mut idx: Vec<usize> = (0..self.rows.len()).collect();
        idx.sort_by(|&a, &b| self.rows[a].frame_ms.total_cmp(&self.rows[b].frame_ms));
        let mut best = f64::INFINITY;
        let mut front = Vec::new();
        for i in idx {
            let e = self.rows[i].lighting_metrics().rel_mse;
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
        let mut s = String::from(
            "method,config,device,width,height,camera,reference,supersample,frame_ms,frames_timed,bake_ms,bake_bytes",
        );
        for p in &pass_names {
            let _ = write!(s, ",pass:{}_ms", p.replace(',', ";"));
        }
        for prefix in ["", "ss_", "ref_noise_"] {
            for m in METRIC_COLUMNS {
                let _ = write!(s, ",{prefix}{m}");
            }
        }
        s.push_str(",warnings\n");
        for r in &self.rows {
            let _ = write!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{},{}",
                r.method,
                r.config.replace(',', ";"),
                self.device.replace(',', ";"),
                self.size.0,
                self.size.1,
                self.camera_column(),
                r.reference.replace(',', ";"),
                self.supersample,
                r.frame_ms,
                r.frames_timed,
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
            match &r.supersampled {
                Some(m) => {
                    for v in metric_values(m) {
                        let _ = write!(s, ",{v}");
                    }
                }
                None => s.push_str(&",".repeat(METRIC_COLUMNS.len())),
            }
            for v in metric_values(&r.reference_noise) {
                let _ = write!(s, ",{v}");
            }
            let _ = writeln!(s, ",{}", r.warnings.join(" | ").replace([',', '\n'], ";"));
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
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| Error::Usage(format!("chart table has no `{name}` column")))
    };
    let (cm, cc, cf, ce) = (col("method")?, col("config")?, col("frame_ms")?, col("rel_mse")?);
    let mut out = Vec::new();
    for (i, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let num = |c: usize| {
            f.get(c)
                .and_then(|v| v.parse::<f64>().ok())
                .ok_or_else(|| Error::Usage(format!("chart table row {}: column {c} is not a number", i + 2)))
        };
        out.push(MeasuredConfig {
            method: f.get(cm).unwrap_or(&"").to_string(),
            config: f.get(cc).unwrap_or(&"").to_string(),
            frame_ms: num(cf)?,
            rel_mse: num(ce)?,
        });
    }
    Ok(out)
}

/// The choice `capture --max-error` makes, and why.
#[derive(Clone, Debug, PartialEq)]
pub enum Choice {
    /// The cheapest configuration within the bound; `rejected` are the cheaper ones that weren't.
    Picked {
        config: MeasuredConfig,
        rejected: Vec<MeasuredConfig>,
    },
    /// None is within the bound; the most accurate one is named.
    NoneQualifies { closest: MeasuredConfig },
}

pub fn choose(configs: &[MeasuredConfig], max_rel_mse: f64) -> Option<Choice> {
    let mut by_time: Vec<&MeasuredConfig> = configs.iter().collect();
    by_time.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    match by_time.iter().position(|c| c.rel_mse <= max_rel_mse) {
        Some(i) => Some(Choice::Picked {
            config: by_time[i].clone(),
            rejected: by_time[..i].iter().map(|c| (*c).clone()).collect(),
        }),
        None => configs
            .iter()
            .min_by(|a, b| a.rel_mse.total_cmp(&b.rel_mse))
            .map(|c| Choice::NoneQualifies { closest: c.clone() }),
    }
}

impl std::fmt::Display for Choice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Choice::Picked { config, rejected } => {
                write!(
                    f,
                    "picked `{}`: relative MSE {:.4} at {:.3} ms, the cheapest within the bound",
                    config.config, config.rel_mse, config.frame_ms
                )?;
                for r in rejected {
                    write!(
                        f,
                        "; `{}` is cheaper ({:.3} ms) but its relative MSE is {:.4}",
                        r.config, r.frame_ms, r.rel_mse
                    )?;
                }
                Ok(())
            }
            Choice::NoneQualifies { closest } => {
                write!(
                    f,
                    "no configuration reaches the bound; the closest is `{}` with relative MSE {:.4} at {:.3} ms",
                    closest.config, closest.rel_mse, closest.frame_ms
                )
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
        MeasuredConfig {
            method: "m".into(),
            config: name.into(),
            frame_ms: ms,
            rel_mse: e,
        }
    }

    #[test]
    fn cheapest_within_the_bound_is_chosen() {
        let configs = vec![
            cfg("slow exact", 9.0, 0.001),
            cfg("fast rough", 1.0, 0.2),
            cfg("middle", 3.0, 0.04),
        ];
        match choose(&configs, 0.05).unwrap() {
            Choice::Picked { config, rejected } => {
                assert_eq!(config.config, "middle");
                assert_eq!(rejected, vec![cfg("fast rough", 1.0, 0.2)]);
            }
            c => panic!("{c:?}"),
        }
        assert_eq!(
            choose(&configs, 1e-4).unwrap(),
            Choice::NoneQualifies {
                closest: cfg("slow exact", 9.0, 0.001)
            }
        );
        let text = choose(&configs, 0.05).unwrap().to_string();
        assert!(
            text.contains("picked `middle`") && text.contains("`fast rough` is cheaper"),
            "{text}"
        );
    }

    #[test]
    fn the_reference_stops_when_its_noise_is_small_in_relative_mse_and_in_p99() {
        use super::stop_ratio;
        // Both within: F = 0.1, noise 0.05 of the relative MSE and 0.2 of the p99 (√0.1 = 0.316).
        assert!(stop_ratio(1e-2, 0.5, 5e-4, 0.1, 0.1) <= 1.0);
        // The relative MSE alone would stop; the p99 asks for more samples.
        let r = stop_ratio(1e-2, 0.5, 5e-4, 0.2, 0.1);
        assert!(r > 1.0 && (r - 0.2 / (0.1f64.sqrt() * 0.5)).abs() < 1e-12, "{r}");
        // The relative MSE asks for more.
        assert!((stop_ratio(1e-2, 0.5, 4e-3, 0.01, 0.1) - 2.0).abs() < 1e-12);
        // Exact everywhere that counts for the p99: only the relative MSE decides.
        assert!((stop_ratio(1e-2, 0.0, 1e-3, 0.0, 0.1) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn timing_stops_at_the_frame_count_or_the_budget_after_the_minimum() {
        use super::{keep_timing, MIN_TIMED_FRAMES};
        assert_eq!(MIN_TIMED_FRAMES, 3);
        assert!(keep_timing(0, 0.0, 20, 2.0));
        assert!(
            keep_timing(2, 100.0, 20, 2.0),
            "the minimum is timed whatever the budget"
        );
        assert!(!keep_timing(3, 2.5, 20, 2.0), "past the budget with the minimum timed");
        assert!(keep_timing(3, 1.0, 20, 2.0));
        assert!(!keep_timing(20, 0.0, 20, 2.0), "never past --frames");
        assert!(!keep_timing(1, 0.0, 1, 2.0), "--frames below the minimum wins");
        assert!(keep_timing(19, 100.0, 20, 0.0), "budget 0: every frame");
    }

    #[test]
    fn csv_round_trips_and_pareto_front_is_monotone() {
        let m = |e: f64| Metrics {
            rmse: e,
            rel_mse: e,
            mean_bias: 0.0,
            p99_abs_error: e,
            max_abs_error: e,
            flip_mean: e,
            mean_ratio: 1.0,
            scaled_rel_rmse: e,
            pixels: 4,
        };
        let row = |c: &str, ms: f64, e: f64| ChartRow {
            method: "m".into(),
            config: c.into(),
            frame_ms: ms,
            frames_timed: 20,
            bake_ms: 0.0,
            bake_bytes: 0,
            passes: vec![("p".into(), ms * 0.5)],
            metrics: m(e),
            supersampled: None,
            reference_noise: m(e / 100.0),
            warnings: vec!["x: 2, of 3 dropped".into()],
            reference: "direct, 4 spp".into(),
        };
        let chart = Chart {
            scene: "s".into(),
            device: "dev, x".into(),
            size: (8, 8),
            supersample: 1,
            rows: vec![row("a", 1.0, 0.5), row("b", 2.0, 0.6), row("c", 3.0, 0.1)],
            skipped: Vec::new(),
            non_finite: Vec::new(),
            frame: 0,
            camera: None,
        };
        assert_eq!(chart.pareto_front(), vec![0, 2]);
        let parsed = parse_csv(&chart.csv()).unwrap();
        assert_eq!(parsed, vec![cfg("a", 1.0, 0.5), cfg("b", 2.0, 0.6), cfg("c", 3.0, 0.1)]);
        assert!(chart.csv().lines().next().unwrap().contains("pass:p_ms"));
        assert!(
            chart.csv().lines().nth(1).unwrap().ends_with(",x: 2; of 3 dropped"),
            "a warning is one CSV field: {}",
            chart.csv()
        );
    }

    /// The noise `reference_noise` simulates has the standard error's scale: over 3 × 4,096
    /// draws of σ = 0.05 about 0.5, the RMSE is σ within 3% and the mean within 4 standard
    /// errors of 0; the same seed gives the same image; the closed forms by hand.
    #[test]
    fn simulated_noise_has_the_standard_errors_scale() {
        let (m, sigma) = (0.5f32, 0.05f32);
        let mut mean = HdrImage::new(64, 64);
        let mut se = HdrImage::new(64, 64);
        for p in &mut mean.pixels {
            *p = [m, m, m, 1.0];
        }
        for p in &mut se.pixels {
            *p = [sigma, sigma, sigma, 1.0];
        }
        let noisy = noisy_copy(&mean, &se, 7);
        assert_eq!(noisy, noisy_copy(&mean, &se, 7));
        let d: Vec<f64> = noisy
            .pixels
            .iter()
            .flat_map(|p| (0..3).map(move |c| (p[c] - m) as f64))
            .collect();
        let n = d.len() as f64;
        let (sigma, m) = (sigma as f64, m as f64);
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
        let avg = d.iter().sum::<f64>() / n;
        assert!((rms / sigma - 1.0).abs() < 0.03, "rms {rms}");
        assert!(avg.abs() < 4.0 * sigma / n.sqrt(), "mean {avg}");
        let image = ReferenceImage {
            mean,
            standard_error: se,
            spp: 64,
            seconds: 0.0,
        };
        let noise = reference_noise(&image).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * b;
        assert!(
            close(noise.rmse, sigma)
                && close(noise.rel_mse, sigma * sigma / (m * m + 0.01))
                && close(noise.mean_bias, sigma / n.sqrt()),
            "{noise:?}"
        );
        // An exact image's typical pixel error: the mean of three |N(0, σ)| is about 0.8 σ.
        assert!(
            noise.p99_abs_error > sigma && noise.max_abs_error >= noise.p99_abs_error && noise.flip_mean > 0.0,
            "{noise:?}"
        );
    }
}
