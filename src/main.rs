//! The `penumbra` command line.

#![deny(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use penumbra::backend::{Gpu, GpuDesc};
use penumbra::commands::capture::CaptureOptions;

#[derive(Parser)]
#[command(
    name = "penumbra",
    version,
    about = "Classic real-time lighting methods on Vulkan, rendered side by side and measured"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Args, Clone)]
struct DeviceArgs {
    /// Use the Vulkan device whose name contains this text (default: a discrete GPU if present, else the first, e.g. lavapipe).
    #[arg(long, value_name = "NAME")]
    device: Option<String>,
    /// Enable VK_LAYER_KHRONOS_validation with synchronization validation; any message makes the command fail.
    /// Also enabled by PENUMBRA_VALIDATION=1.
    #[arg(long)]
    validation: bool,
}

#[derive(Args, Clone)]
struct RenderArgs {
    /// Scene file (TOML, see scenes/README.md), or an asset (.obj, .gltf, .glb) shown alone with its
    /// own cameras and lights (docs/assets.md); the built-in default scene when omitted.
    scene: Option<PathBuf>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Lighting method or combination (one the scene enables or declares in [[combinations]];
    /// any method for a scene or asset that declares none; default: the scene's first method).
    #[arg(long, value_name = "M")]
    method: Option<String>,
    #[command(flatten)]
    overrides: OverrideArgs,
    #[command(flatten)]
    device: DeviceArgs,
}

/// Settings put over the scene file's.
#[derive(Args, Clone)]
struct OverrideArgs {
    /// View through camera N of those the scene's assets carry (glTF cameras, counted over the
    /// assets in object order) instead of the scene's own.
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    /// What a method may allocate for its bake and volumes, in MB, over the scene's
    /// `memory_budget_mb` (default 2048): settings that would need more are refused up front.
    #[arg(long, value_name = "MB", value_parser = parse_memory_budget)]
    memory_budget_mb: Option<f64>,
}

impl OverrideArgs {
    fn get(&self) -> penumbra::scene::SceneOverrides {
        penumbra::scene::SceneOverrides {
            camera: self.camera,
            memory_budget_mb: self.memory_budget_mb,
        }
    }
}

/// How `report` measures each scene: `chart`'s settings.
#[derive(Args, Clone)]
struct SweepArgs {
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "320x180", value_parser = parse_size)]
    size: (u32, u32),
    /// Frames timed per configuration at most (the median is reported).
    #[arg(long, default_value_t = 20, value_parser = parse_frames)]
    frames: usize,
    /// Seconds of timed frames per configuration after which timing stops, once 3 are timed.
    #[arg(long, value_name = "S", default_value_t = 2.0)]
    timing_budget: f64,
    /// Seconds after which a swept point still baking is stopped and left out, with why (0: no
    /// limit); the scene's own configuration always runs.
    #[arg(long, value_name = "S", default_value_t = 600.0)]
    bake_limit: f64,
    /// Samples per pixel of the reference at most.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: u32,
    /// The reference renders until its noise adds at most this fraction of the smallest
    /// relative MSE it judges (0: exactly --reference-spp).
    #[arg(long, value_name = "F", default_value_t = 0.1)]
    reference_noise: f64,
    /// Render each configuration at N times the size in each axis, box-filtered down (1: no).
    #[arg(long, value_name = "N", default_value_t = 1)]
    supersample: u32,
    /// Where references, tables and bakes are cached.
    #[arg(long, value_name = "DIR", default_value = ".penumbra-cache")]
    cache_dir: PathBuf,
    /// Only this method or combination (repeat for more; default: all of each scene's).
    #[arg(long = "method", value_name = "M")]
    methods: Vec<String>,
    /// View every scene through camera N of those its assets carry, as `chart --camera N`.
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene headless; write the tone-mapped PNG and/or the linear-radiance EXR.
    Capture(CaptureArgs),
    /// Image metrics of TEST against REF (linear radiance EXRs): RMSE, relative MSE, mean bias,
    /// 99th-percentile and max per-pixel error, FLIP on the tone-mapped pair, the mean ratio and
    /// the relative RMSE left after the best-fit scale.
    Compare(CompareArgs),
    /// Speed against accuracy: every method the scene enables, at every point of its quality sweep,
    /// timed with GPU timestamps and measured against the scene's reference (rendered once and
    /// cached); a log–log chart with the Pareto front, and a CSV of every per-pass time and metric.
    Chart(ChartArgs),
    /// Every method at its defaults over seeded generated scenes (rooms joined by doors, a
    /// courtyard, terrain; lamps, panels, a sun through a window, many lights, a sky), each
    /// against its path-traced reference: a CSV row per scene and method, a Markdown summary
    /// of every CSV in DIR (so shards are summarised together), and the worst scenes as TOML.
    Suite(SuiteArgs),
    /// A static HTML report (opens from disk, no network): per scene the reference, every
    /// configuration `chart` measures with its FLIP and relative-error maps, a slider against the
    /// reference, faithful beside corrected, the chart as interactive SVG, per-pass times, bake
    /// costs and the failure cases; an index page links the scenes.
    Report(ReportArgs),
    /// Per-pass GPU time from timestamp queries: median, min and max over the frames.
    Profile(ProfileArgs),
    /// Run the bakes of the scene's methods and combinations (light-maps, transfer, visibility
    /// tables) ahead of time into the bake cache (.penumbra-cache/bake, or $PENUMBRA_CACHE/bake),
    /// and report each one's time and size.
    Bake(BakeArgs),
    /// Show the chosen device, its driver, and the features and limits penumbra uses.
    Info(InfoArgs),
    /// Open a window: fly camera (WASD, mouse drag to look, Q/E down/up, Shift faster),
    /// F12 saves a screenshot, R reloads shaders from glsl/, M switches to the scene's next method or combination, Esc quits. GPU pass times are shown in the title.
    Demo(DemoArgs),
    /// Ground truth: path-trace a scene (Monte Carlo, compute shader) and write the mean radiance
    /// EXR plus the per-pixel standard error of that mean as NAME.stderr.exr next to it. Prints
    /// the rate, the image's average with its standard error, and the relative variance of one
    /// sample (as the relative MSE weighs pixels) with the efficiency, samples/s over it.
    Reference(ReferenceArgs),
}

// `capture`'s arguments (the variant documents the command).
#[derive(Args)]
struct CaptureArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// PNG output (tone-mapped sRGB). Default capture.png when neither -o nor --exr is given.
    #[arg(short = 'o', long = "output", value_name = "PNG")]
    output: Option<PathBuf>,
    /// EXR output: unclamped linear radiance in W/(m²·sr), no exposure applied.
    #[arg(long, value_name = "EXR")]
    exr: Option<PathBuf>,
    /// Frames to render before capturing (the last is written).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Exposure multiplier applied before tone mapping the PNG.
    #[arg(long, default_value_t = 1.0, value_parser = parse_exposure)]
    exposure: f32,
    /// Render with the cheapest configuration (of those the chart measured for the scene) whose
    /// relative MSE against the reference is at most E, from the data `penumbra chart` cached
    /// for this scene and size; says which it picked and why.
    #[arg(long, value_name = "E", value_parser = parse_max_error)]
    max_error: Option<f64>,
    /// Where `chart` caches references and tables.
    #[arg(long, value_name = "DIR", default_value = ".penumbra-cache")]
    cache_dir: PathBuf,
    /// Render at N times the size in each axis and box-filter down to --size, so each pixel
    /// averages its footprint as the reference's does (N from 1 to 16; at most 4096x4096
    /// rendered pixels in all).
    #[arg(long, value_name = "N", default_value_t = 1)]
    supersample: u32,
    /// What to write, as the demo shows it: method, reference, split, error or difference.
    /// Every view but the method's path-traces the reference the configuration is judged
    /// against (--reference-spp samples); the EXR then holds the view's linear values.
    #[arg(long, default_value = "method", value_parser = parse_view)]
    view: penumbra::commands::views::View,
    /// Samples per pixel of the reference the views compare against.
    #[arg(long, value_name = "N", default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: u32,
    /// The split view's divider, as a fraction of the width.
    #[arg(long, value_name = "F", default_value_t = 0.5)]
    split: f32,
    /// The error view's per-pixel error: relative or flip.
    #[arg(long, value_name = "MAP", default_value = "relative", value_parser = parse_error_map)]
    error_map: penumbra::commands::views::ErrorMap,
    /// The error at the top of the error view's colour scale (the difference view's full
    /// colour, relative to the reference's mean).
    #[arg(long, value_name = "E", default_value_t = 1.0, value_parser = parse_exposure)]
    scale: f32,
}

// `compare`'s arguments (the variant documents the command).
#[derive(Args)]
struct CompareArgs {
    /// The image to judge.
    test: PathBuf,
    /// The reference.
    reference: PathBuf,
    /// Write a false-colour (magma) image of the per-pixel FLIP error.
    #[arg(long, value_name = "PNG")]
    diff: Option<PathBuf>,
    /// Exposure applied to both images before tone mapping for FLIP.
    #[arg(long, default_value_t = 1.0, value_parser = parse_exposure)]
    exposure: f32,
    /// Print the metrics as JSON instead of a table.
    #[arg(long)]
    json: bool,
}

// `chart`'s arguments (the variant documents the command).
#[derive(Args)]
struct ChartArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Chart image (PNG).
    #[arg(short = 'o', long = "output", value_name = "PNG", default_value = "chart.png")]
    output: PathBuf,
    /// Also write the table as CSV.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "128x128", value_parser = parse_size)]
    size: (u32, u32),
    /// Frames timed per configuration at most (the median is reported).
    #[arg(long, default_value_t = 20, value_parser = parse_frames)]
    frames: usize,
    /// Seconds of timed frames per configuration after which timing stops, once 3 frames are
    /// timed (0: always --frames); the CSV's frames_timed column says how many were.
    #[arg(long, value_name = "S", default_value_t = 2.0)]
    timing_budget: f64,
    /// Seconds after which a swept point still baking is stopped and left out, with why (0: no
    /// limit); the scene's own configuration always runs.
    #[arg(long, value_name = "S", default_value_t = 600.0)]
    bake_limit: f64,
    /// Samples per pixel of the reference: the most it may take (exactly this with --reference-noise 0).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: u32,
    /// The reference renders (from 32 spp on) until its noise adds at most this fraction of the
    /// smallest relative MSE among the configurations it judges, and its noise's p99 error is
    /// at most the square root of this fraction of the smallest p99; 0: exactly --reference-spp.
    #[arg(long, value_name = "F", default_value_t = 0.1)]
    reference_noise: f64,
    /// Where the reference's draws come from: `sobol` (scrambled Sobol points, the error
    /// from independent replicates; less error for the same samples) or `independent`.
    #[arg(long, value_name = "sobol|independent", default_value = "sobol")]
    reference_sampler: penumbra::reference::Sampler,
    /// Also render each configuration at N times the size in each axis, box-filtered down, and
    /// report both errors (pixel centres and supersampled); the plot shows the supersampled one.
    #[arg(long, value_name = "N", default_value_t = 1)]
    supersample: u32,
    /// Where references and tables are cached.
    #[arg(long, value_name = "DIR", default_value = ".penumbra-cache")]
    cache_dir: PathBuf,
    /// Chart only this method or combination (repeat for more; default: all of the scene's;
    /// any method for a scene or asset that declares none).
    #[arg(long = "method", value_name = "M")]
    methods: Vec<String>,
    /// Compare frame N (N/60 s: wind, light motion and light board applied): each
    /// configuration renders frames 0 to N and the reference traces frame N.
    #[arg(long, value_name = "N", default_value_t = 0)]
    frame: u64,
    /// View through camera N of those the scene's assets carry, as `capture --camera N`; the
    /// cached references and tables are the chosen camera's own.
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    #[command(flatten)]
    device: DeviceArgs,
}

// `suite`'s arguments (the variant documents the command).
#[derive(Args)]
struct SuiteArgs {
    /// Scenes in the whole suite (all shards together).
    #[arg(long, default_value_t = 12)]
    scenes: u64,
    /// Seed of the generator: the same seed gives the same scenes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "64x48", value_parser = parse_size)]
    size: (u32, u32),
    /// Render each method at N times the size in each axis and box-filter it down, so that
    /// its error is lighting and not aliasing.
    #[arg(long, value_name = "N", default_value_t = 4)]
    supersample: u32,
    /// Run the K-th of N interleaved parts of the scenes (1-based), e.g. 2/8.
    #[arg(long, value_name = "K/N", default_value = "1/1", value_parser = parse_shard)]
    shard: (u64, u64),
    /// Frames timed per configuration at most (the median is reported).
    #[arg(long, default_value_t = 5, value_parser = parse_frames)]
    frames: usize,
    /// Seconds of timed frames per configuration after which timing stops (once 3 are timed).
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    timing_budget: f64,
    /// The most samples per pixel a reference may take.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: u32,
    /// The reference renders until its noise adds at most this fraction of the smallest
    /// relative MSE it judges (see `chart`); 0: exactly --reference-spp.
    #[arg(long, value_name = "F", default_value_t = 0.1)]
    reference_noise: f64,
    /// Only this method or combination (repeat for more; default: every one a scene declares).
    #[arg(long = "method", value_name = "M")]
    methods: Vec<String>,
    /// Scenes saved per method in DIR/worst, by relative MSE (every failure is saved too).
    #[arg(long, default_value_t = 3)]
    worst: usize,
    /// Output folder.
    #[arg(short = 'o', long = "output", value_name = "DIR", default_value = "suite")]
    output: PathBuf,
    /// Where references and bakes are cached.
    #[arg(long, value_name = "DIR", default_value = ".penumbra-cache")]
    cache_dir: PathBuf,
    #[command(flatten)]
    device: DeviceArgs,
}

// `report`'s arguments (the variant documents the command).
#[derive(Args)]
struct ReportArgs {
    /// Scene files (TOML), one page each.
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// Directory the report is written to (index.html and one page per scene).
    #[arg(short = 'o', long = "output", value_name = "DIR", default_value = "report")]
    output: PathBuf,
    /// A results table (CSV) of the generated-scene suite, shown as one more page.
    #[arg(long, value_name = "CSV")]
    suite: Option<PathBuf>,
    #[command(flatten)]
    sweep: SweepArgs,
}

// `profile`'s arguments (the variant documents the command).
#[derive(Args)]
struct ProfileArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// Frames to time.
    #[arg(long, default_value_t = 30, value_parser = parse_frames)]
    frames: usize,
    /// Also write the report as JSON (with device and driver).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

// `bake`'s arguments (the variant documents the command).
#[derive(Args)]
struct BakeArgs {
    #[command(flatten)]
    render: RenderArgs,
}

// `info`'s arguments (the variant documents the command).
#[derive(Args)]
struct InfoArgs {
    #[command(flatten)]
    device: DeviceArgs,
}

// `demo`'s arguments (the variant documents the command).
#[derive(Args)]
struct DemoArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// Quit by itself after this many frames (for tests and scripted runs).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    frames: Option<u64>,
    /// Save a screenshot (PNG) of the last frame when quitting.
    #[arg(long, value_name = "PNG")]
    screenshot: Option<PathBuf>,
    /// Scripted resize, for tests: after FRAME frames resize the window to WxH (e.g. 10:320x200).
    #[arg(long, value_name = "FRAME:WxH", value_parser = parse_resize)]
    resize_at: Option<(u64, u32, u32)>,
    /// Scripted method switching, for tests: the next method or combination every N frames
    /// (as the M key does).
    #[arg(long, value_name = "N")]
    cycle_every: Option<u64>,
    /// Timed input events, one a line: `FRAME key M`, `FRAME move DX DY DZ`, `FRAME turn YAW
    /// PITCH`, `FRAME budget SHARE`, `FRAME split F`, `FRAME screenshot PATH` (docs/demo.md).
    #[arg(long, value_name = "FILE")]
    script: Option<PathBuf>,
    /// Write each frame's configuration, view, reference spp and error (JSON) when quitting.
    #[arg(long, value_name = "FILE")]
    report_json: Option<PathBuf>,
    /// Start with the panel hidden (F1 toggles it).
    #[arg(long)]
    hide_panel: bool,
    /// Start with the live reference on, taking this share of the frame time (0 < S < 1).
    #[arg(long, value_name = "S", value_parser = parse_budget)]
    reference_budget: Option<f32>,
    /// The view to start in: method, reference, split, error or difference.
    #[arg(long, default_value = "method", value_parser = parse_view)]
    view: penumbra::commands::views::View,
}

// `reference`'s arguments (the variant documents the command).
#[derive(Args)]
struct ReferenceArgs {
    /// Scene file (TOML, see scenes/README.md).
    scene: PathBuf,
    /// Samples per pixel (default 256); with --max-stderr the most it may take (default 65536).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Keep sampling until the relative standard error is at most E (see --stderr-over), with
    /// --spp as the cap; judged from 32 spp on. Prints the spp used and the error reached.
    #[arg(long, value_name = "E", value_parser = parse_max_stderr)]
    max_stderr: Option<f64>,
    /// What --max-stderr bounds: `image` = the standard error of the image's mean over that
    /// mean (worst RGB channel); `pixel` = the 99th percentile over pixels of s.e./sqrt(mean²+0.01)
    /// (worst channel).
    #[arg(long, value_name = "SCOPE", default_value = "image", value_parser = parse_scope, requires = "max_stderr")]
    stderr_over: penumbra::reference::ErrorScope,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Surface interactions followed after the first hit: light that made at most K+1 is counted (0: direct light only).
    #[arg(long, value_name = "K", default_value_t = penumbra::reference::DEFAULT_BOUNCES)]
    bounces: u32,
    /// Russian roulette where the K-th bounce and every later one hits a surface (unbiased: the same expected value within --bounces), or `off`.
    #[arg(long, value_name = "K|off", default_value_t = Roulette(Some(penumbra::reference::DEFAULT_ROULETTE_AFTER)), value_parser = parse_roulette)]
    roulette_after: Roulette,
    /// Next-event estimation: `every` light at every vertex, `one` drawn per colour channel in
    /// proportion to its unshadowed contribution (one to three shadow rays a vertex, unbiased),
    /// or `auto` (every light up to 32, one beyond).
    #[arg(long, value_name = "every|one|auto", default_value = "auto", value_parser = parse_light_selection)]
    light_selection: penumbra::reference::LightSelection,
    /// Where the 2D draws (point in the pixel, on an area light, environment and BSDF
    /// directions) come from: scrambled `sobol` points in 8 independent replicates per pixel
    /// (unbiased, less error for the same samples; the standard error from the replicates'
    /// scatter), or `independent` numbers.
    #[arg(long, value_name = "sobol|independent", default_value = "sobol")]
    sampler: penumbra::reference::Sampler,
    /// Write the scene as the tracer sees it (triangles per material as PLY, camera, materials and lights as JSON) into DIR and exit, for tools/reference_vs_mitsuba.py.
    #[arg(long, value_name = "DIR")]
    export_scene: Option<PathBuf>,
    /// Only emission seen directly and light after exactly one surface interaction (same as --bounces 0).
    #[arg(long, conflicts_with_all = ["indirect_only", "bounces"])]
    direct_only: bool,
    /// Everything but what --direct-only counts: light after 2 to K+1 interactions.
    #[arg(long)]
    indirect_only: bool,
    /// Random seed: the same seed gives a bit-identical image, another seed independent noise.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u32,
    /// Trace the scene as the renderer's frame N has it (N/60 s: wind, light motion and
    /// light board applied); `capture --frames N` shows frame N-1.
    #[arg(long, value_name = "N", default_value_t = 0)]
    frame: u64,
    /// Output EXR of the mean radiance, W/(m²·sr).
    #[arg(short = 'o', long = "output", value_name = "EXR", default_value = "reference.exr")]
    output: PathBuf,
    /// View through camera N of those the scene's assets carry, as `capture --camera N`.
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    #[command(flatten)]
    device: DeviceArgs,
}

/// `--roulette-after`: an interaction count of at least 1, or `off`.
#[derive(Clone, Copy, Debug)]
struct Roulette(Option<u32>);

impl std::fmt::Display for Roulette {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self.0 {
            Some(k) => write!(f, "{k}"),
            None => f.write_str("off"),
        }
    }
}

fn parse_roulette(s: &str) -> Result<Roulette, String> {
    if s.trim().eq_ignore_ascii_case("off") {
        return Ok(Roulette(None));
    }
    match s.trim().parse::<u32>() {
        Ok(k) if k >= 1 => Ok(Roulette(Some(k))),
        _ => Err(format!("`{s}`: expected a whole number of at least 1, or `off`")),
    }
}

fn parse_light_selection(s: &str) -> Result<penumbra::reference::LightSelection, String> {
    use penumbra::reference::LightSelection;
    match s.trim().to_ascii_lowercase().as_str() {
        "every" => Ok(LightSelection::Every),
        "one" => Ok(LightSelection::One),
        "auto" => Ok(LightSelection::Auto),
        _ => Err(format!("`{s}`: expected every, one or auto")),
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("`{s}`: expected WIDTHxHEIGHT, e.g. 640x360"))?;
    let p = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| n > 0 && n <= 16384);
    match (p(w), p(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{s}`: width and height must be whole numbers from 1 to 16384")),
    }
}

/// A frame count: a whole number of at least 1.
fn parse_shard(s: &str) -> Result<(u64, u64), String> {
    let parsed = s
        .split_once('/')
        .and_then(|(k, n)| Some((k.trim().parse::<u64>().ok()?, n.trim().parse::<u64>().ok()?)));
    match parsed {
        Some((k, n)) if k >= 1 && k <= n => Ok((k, n)),
        _ => Err(format!("expected K/N with 1 <= K <= N (e.g. 2/8), got {s:?}")),
    }
}

fn parse_frames(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("`{s}`: expected a whole number of frames, at least 1")),
    }
}

/// A relative-MSE bound: a finite number above 0.
fn parse_max_error(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(e) if e.is_finite() && e > 0.0 => Ok(e),
        _ => Err(format!(
            "`{s}`: expected a relative MSE, a finite number above 0 (e.g. 0.01)"
        )),
    }
}

/// A relative standard error: a finite number above 0.
fn parse_max_stderr(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(e) if e.is_finite() && e > 0.0 => Ok(e),
        _ => Err(format!(
            "`{s}`: expected a relative standard error, a finite number above 0 (e.g. 0.01)"
        )),
    }
}

fn parse_scope(s: &str) -> Result<penumbra::reference::ErrorScope, String> {
    match s.trim() {
        "image" => Ok(penumbra::reference::ErrorScope::Image),
        "pixel" => Ok(penumbra::reference::ErrorScope::Pixel),
        _ => Err(format!("`{s}`: expected `image` or `pixel`")),
    }
}

/// An exposure multiplier: a finite number above 0.
fn parse_view(s: &str) -> Result<penumbra::commands::views::View, String> {
    penumbra::commands::views::View::parse(s).map_err(|e| e.to_string())
}

fn parse_error_map(s: &str) -> Result<penumbra::commands::views::ErrorMap, String> {
    match s {
        "relative" => Ok(penumbra::commands::views::ErrorMap::Relative),
        "flip" => Ok(penumbra::commands::views::ErrorMap::Flip),
        _ => Err(format!("`{s}`: expected relative or flip")),
    }
}

fn parse_budget(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(b) if b > 0.0 && b < 1.0 => Ok(b),
        _ => Err(format!(
            "`{s}`: expected a share of the frame time, above 0 and below 1"
        )),
    }
}

fn parse_memory_budget(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 1.0 => Ok(v),
        _ => Err(format!("{s:?}: expected a memory budget in MB, at least 1")),
    }
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(e) if e.is_finite() && e > 0.0 => Ok(e),
        _ => Err(format!(
            "`{s}`: expected an exposure multiplier, a finite number above 0"
        )),
    }
}

fn parse_resize(s: &str) -> Result<(u64, u32, u32), String> {
    let (frame, size) = s
        .split_once(':')
        .ok_or_else(|| format!("`{s}`: expected FRAME:WxH, e.g. 10:320x200"))?;
    let frame = frame
        .trim()
        .parse::<u64>()
        .map_err(|_| format!("`{frame}`: expected a frame number"))?;
    let (w, h) = parse_size(size)?;
    Ok((frame, w, h))
}

fn gpu_desc(d: &DeviceArgs) -> GpuDesc {
    let env = std::env::var("PENUMBRA_VALIDATION").map(|v| v == "1").unwrap_or(false);
    GpuDesc {
        validation: d.validation || env,
        device_name: d.device.clone(),
        display: None,
    }
}

fn options(r: &RenderArgs) -> CaptureOptions {
    CaptureOptions {
        scene: r.scene.clone(),
        png: None,
        exr: None,
        size: r.size,
        frames: 1,
        method: r.method.clone(),
        exposure: 1.0,
        gpu: gpu_desc(&r.device),
        config: None,
        supersample: 1,
        overrides: r.overrides.get(),
    }
}

fn run(cli: Cli) -> penumbra::Result<()> {
    match cli.command {
        Command::Capture(args) => capture(args),
        Command::Profile(args) => profile(args),
        Command::Bake(args) => bake(args),
        Command::Compare(args) => compare(args),
        Command::Suite(args) => suite(args),
        Command::Chart(args) => chart(args),
        Command::Report(args) => report(args),
        Command::Info(args) => info(args),
        Command::Demo(args) => demo(args),
        Command::Reference(args) => reference(args),
    }
}

fn capture(args: CaptureArgs) -> penumbra::Result<()> {
    let CaptureArgs {
        render,
        output,
        exr,
        frames,
        exposure,
        max_error,
        cache_dir,
        supersample,
        view,
        reference_spp,
        split,
        error_map,
        scale,
    } = args;
    let mut opts = CaptureOptions {
        png: output,
        exr,
        frames,
        exposure,
        supersample,
        ..options(&render)
    };
    if let Some(e) = max_error {
        let (decl, why) = penumbra::commands::capture::choose_configuration(&opts, e, &cache_dir)?;
        penumbra::outln!("{why}");
        opts.config = Some(decl);
    }
    let written = if view == penumbra::commands::views::View::Method {
        penumbra::commands::capture::run(&opts)?
    } else {
        let settings = penumbra::commands::views::ViewSettings {
            view,
            exposure,
            split,
            error_map,
            scale,
        };
        penumbra::commands::capture::run_view(&opts, &settings, reference_spp)?
    };
    for path in written {
        penumbra::outln!("wrote {path}");
    }
    Ok(())
}

fn profile(args: ProfileArgs) -> penumbra::Result<()> {
    let ProfileArgs { render, frames, json } = args;
    let report = penumbra::commands::profile::run(&options(&render), frames)?;
    penumbra::out!("{}", report.table());
    if let Some(p) = json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| penumbra::Error::Internal(e.to_string()))?;
        penumbra::util::image_io::write_file(&p, text.as_bytes())
            .map_err(|e| penumbra::Error::Usage(format!("{}: {e}", p.display())))?;
        penumbra::outln!("wrote {}", p.display());
    }
    Ok(())
}

fn bake(args: BakeArgs) -> penumbra::Result<()> {
    let BakeArgs { render } = args;
    for (config, reports) in penumbra::commands::bake::run(&options(&render))? {
        if reports.is_empty() {
            penumbra::outln!("{config}: nothing to bake");
        } else {
            penumbra::out!("{config}:\n{}", penumbra::bake::table(&reports));
        }
        if let Some(why) = reports.iter().find_map(|r| r.not_stored.as_ref()) {
            return Err(penumbra::Error::Usage(format!(
                "{config}: a bake could not be stored in the cache: {why}"
            )));
        }
    }
    Ok(())
}

fn compare(args: CompareArgs) -> penumbra::Result<()> {
    let CompareArgs {
        test,
        reference,
        diff,
        exposure,
        json,
    } = args;
    use penumbra::metrics::{colorize, compare_with_map, CompareOptions};
    use penumbra::util::image_io::HdrImage;
    let (t, r) = (HdrImage::read_exr(&test)?, HdrImage::read_exr(&reference)?);
    let (metrics, map) = compare_with_map(
        &t,
        &r,
        &CompareOptions {
            exposure,
            ..CompareOptions::default()
        },
    )?;
    if json {
        penumbra::outln!(
            "{}",
            serde_json::to_string_pretty(&metrics).map_err(|e| penumbra::Error::Internal(e.to_string()))?
        );
    } else {
        penumbra::out!("{}", metrics.table());
    }
    if let Some(p) = diff {
        penumbra::util::image_io::save_image(&p, colorize(&map).into(), image::ImageFormat::Png)?;
        penumbra::outln!("wrote {}", p.display());
    }
    Ok(())
}

fn suite(args: SuiteArgs) -> penumbra::Result<()> {
    let SuiteArgs {
        scenes,
        seed,
        size,
        supersample,
        shard,
        frames,
        timing_budget,
        reference_spp,
        reference_noise,
        methods,
        worst,
        output,
        cache_dir,
        device,
    } = args;
    let opts = penumbra::commands::suite::SuiteOptions {
        scenes,
        seed,
        shard,
        size,
        supersample,
        frames,
        timing_budget_s: timing_budget,
        reference_spp,
        reference_noise,
        out: output.clone(),
        cache_dir,
        gpu: gpu_desc(&device),
        methods,
        worst,
    };
    let summary = penumbra::commands::suite::run(&opts)?;
    penumbra::out!("{}", summary.markdown());
    penumbra::outln!("wrote {}", output.join("summary.md").display());
    Ok(())
}

fn chart(args: ChartArgs) -> penumbra::Result<()> {
    let ChartArgs {
        scene,
        output,
        csv,
        size,
        frames,
        timing_budget,
        bake_limit,
        reference_spp,
        reference_noise,
        reference_sampler,
        supersample,
        cache_dir,
        methods,
        frame,
        camera,
        device,
    } = args;
    let opts = penumbra::commands::chart::ChartOptions {
        scene,
        size,
        frames,
        timing_budget_s: timing_budget,
        bake_limit_s: bake_limit,
        reference_spp,
        reference_noise,
        reference_sampler,
        supersample,
        png: Some(output.clone()),
        csv: csv.clone(),
        cache_dir,
        gpu: gpu_desc(&device),
        methods,
        frame,
        camera,
    };
    let start = std::time::Instant::now();
    let chart = penumbra::commands::chart::run(&opts)?;
    penumbra::outln!(
        "{}; each metric is followed by [the reference's own error: what an exact method would score]",
        chart.comparison()
    );
    for r in &chart.rows {
        let (m, n) = (r.lighting_metrics(), &r.reference_noise);
        let centre = match &r.supersampled {
            Some(_) => format!("   centre-sampled rel MSE {:.3e}", r.metrics.rel_mse),
            None => String::new(),
        };
        penumbra::outln!(
            "{:<32} {:>9.3} ms   rel MSE {:.3e} [{:.1e}]   RMSE {:.3e} [{:.1e}]   bias {:+.2e} [{:.1e}]   p99 {:.3e} [{:.1e}]   max {:.3e} [{:.1e}]   FLIP {:.4} [{:.4}]   mean ratio {:.3}   scaled rel RMSE {:.3} [{:.3}]   ({}){centre}",
            r.config,
            r.frame_ms,
            m.rel_mse,
            n.rel_mse,
            m.rmse,
            n.rmse,
            m.mean_bias,
            n.mean_bias,
            m.p99_abs_error,
            n.p99_abs_error,
            m.max_abs_error,
            n.max_abs_error,
            m.flip_mean,
            n.flip_mean,
            m.mean_ratio,
            m.scaled_rel_rmse,
            n.scaled_rel_rmse,
            r.reference
        );
        for w in &r.warnings {
            penumbra::outln!("    warning: {w}");
        }
    }
    penumbra::outln!(
        "chart: {} configurations in {:.1} s wall",
        chart.rows.len(),
        start.elapsed().as_secs_f64()
    );
    penumbra::outln!("wrote {}", output.display());
    if let Some(p) = csv {
        penumbra::outln!("wrote {}", p.display());
    }
    Ok(())
}

fn report(args: ReportArgs) -> penumbra::Result<()> {
    let ReportArgs {
        scenes,
        output,
        suite,
        sweep,
    } = args;
    let chart = penumbra::commands::chart::ChartOptions {
        scene: PathBuf::new(),
        size: sweep.size,
        frames: sweep.frames,
        timing_budget_s: sweep.timing_budget,
        bake_limit_s: sweep.bake_limit,
        reference_spp: sweep.reference_spp,
        reference_noise: sweep.reference_noise,
        reference_sampler: penumbra::reference::Sampler::Sobol,
        supersample: sweep.supersample,
        png: None,
        csv: None,
        cache_dir: sweep.cache_dir,
        gpu: gpu_desc(&sweep.device),
        methods: sweep.methods,
        frame: 0,
        camera: sweep.camera,
    };
    let opts = penumbra::commands::report::ReportOptions {
        scenes,
        out_dir: output.clone(),
        suite,
        chart,
    };
    let start = std::time::Instant::now();
    let pages = penumbra::commands::report::run(&opts)?;
    for p in &pages {
        penumbra::outln!(
            "{}: {} configurations, {} failure cases, most accurate within 10 ms: {}",
            p.page,
            p.configurations,
            p.failures,
            p.best_within_10ms.as_deref().unwrap_or("none")
        );
    }
    penumbra::outln!(
        "wrote {} in {:.1} s wall",
        output.join("index.html").display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn info(args: InfoArgs) -> penumbra::Result<()> {
    let InfoArgs { device } = args;
    let gpu = Gpu::new(&gpu_desc(&device))?;
    for (k, v) in gpu.caps().report() {
        penumbra::outln!("{k:<38} {v}");
    }
    Ok(())
}

fn demo(args: DemoArgs) -> penumbra::Result<()> {
    let DemoArgs {
        render,
        frames,
        screenshot,
        resize_at,
        cycle_every,
        script,
        report_json,
        hide_panel,
        reference_budget,
        view,
    } = args;
    let opts = options(&render);
    let script = script.map(|p| penumbra::commands::demo::Script::load(&p)).transpose()?;
    penumbra::commands::demo::run(
        &opts,
        penumbra::commands::demo::DemoScript {
            frames,
            screenshot,
            resize_at,
            cycle_every,
            script,
            report_json,
            hide_panel,
            reference_budget: reference_budget.unwrap_or(0.0),
            view,
        },
    )?;
    Ok(())
}

fn reference(args: ReferenceArgs) -> penumbra::Result<()> {
    let ReferenceArgs {
        scene,
        spp,
        max_stderr,
        stderr_over,
        size,
        bounces,
        roulette_after,
        light_selection,
        sampler,
        export_scene,
        direct_only,
        indirect_only,
        seed,
        frame,
        output,
        camera,
        device,
    } = args;
    if let Some(dir) = export_scene {
        for p in penumbra::reference::export::export_file(&scene, &dir)? {
            penumbra::outln!("wrote {}", p.display());
        }
        return Ok(());
    }
    use penumbra::reference::{Batching, ErrorTarget, LightPaths, ReferenceOptions, Settings, MIN_ADAPTIVE_SPP};
    let paths = if direct_only {
        LightPaths::Direct
    } else if indirect_only {
        LightPaths::Indirect
    } else {
        LightPaths::All
    };
    let spp = spp.unwrap_or(if max_stderr.is_some() { 65536 } else { 256 });
    let target = max_stderr.map(|max| ErrorTarget {
        max,
        scope: stderr_over,
        min_spp: MIN_ADAPTIVE_SPP,
    });
    let settings = Settings {
        spp,
        bounces,
        paths,
        seed,
        batching: Batching::Adaptive,
        roulette_after: roulette_after.0,
        light_selection,
        sampler,
    };
    let report = penumbra::reference::run(&ReferenceOptions {
        scene,
        output,
        size,
        settings,
        target,
        frame,
        camera,
        gpu: gpu_desc(&device),
    })?;
    print_reference_report(&report, target, sampler);
    Ok(())
}

/// What `reference` prints: the files written, the rate, the average with its standard error,
/// the efficiency, and whether the error target was reached.
fn print_reference_report(
    report: &penumbra::reference::ReferenceReport,
    target: Option<penumbra::reference::ErrorTarget>,
    sampler: penumbra::reference::Sampler,
) {
    for p in &report.written {
        penumbra::outln!("wrote {}", p.display());
    }
    let img = &report.image;
    penumbra::outln!(
        "reference: {} spp at {}x{} in {:.2} s: {:.0} samples/s ({} sampler)",
        img.spp,
        img.mean.width,
        img.mean.height,
        img.seconds,
        img.samples_per_second(),
        sampler.name()
    );
    let (mean, se) = img.average();
    penumbra::outln!(
        "average radiance (RGB): {:.6} {:.6} {:.6}, standard error {:.2e} {:.2e} {:.2e}",
        mean[0],
        mean[1],
        mean[2],
        se[0],
        se[1],
        se[2]
    );
    let variance = img.relative_variance_per_sample();
    penumbra::outln!(
        "relative variance per sample: {variance:.4e}; efficiency (samples/s over it): {:.4e}",
        img.samples_per_second() / variance
    );
    if let (Some(t), Some(a)) = (target, report.achieved) {
        let over = if t.scope == penumbra::reference::ErrorScope::Image {
            "image"
        } else {
            "pixel"
        };
        let verdict = if a <= t.max {
            "reached"
        } else {
            "NOT reached: the --spp cap came first"
        };
        penumbra::outln!(
            "relative standard error ({over}): {a:.3e} at {} spp, target {:.3e} {verdict}",
            img.spp,
            t.max
        );
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => match penumbra::util::console::stdout_failure() {
            None => ExitCode::SUCCESS,
            Some(e) => {
                penumbra::errln!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Err(e) => {
            penumbra::errln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
