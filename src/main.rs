//! The `penumbra` command line.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use penumbra::backend::{Gpu, GpuDesc};
use penumbra::capture::CaptureOptions;

#[derive(Parser)]
#[command(name = "penumbra", version, about = "Classic real-time lighting methods on Vulkan, rendered side by side and measured")]
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
    /// Scene file (TOML, see scenes/README.md); the built-in default scene when omitted.
    scene: Option<PathBuf>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    size: (u32, u32),
    /// Lighting method (one the scene enables; default: the scene's first).
    #[arg(long, value_name = "M")]
    method: Option<String>,
    #[command(flatten)]
    device: DeviceArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene headless; write the tone-mapped PNG and/or the linear-radiance EXR.
    Capture {
        #[command(flatten)]
        render: RenderArgs,
        /// PNG output (tone-mapped sRGB). Default capture.png when neither -o nor --exr is given.
        #[arg(short = 'o', long = "output", value_name = "PNG")]
        output: Option<PathBuf>,
        /// EXR output: unclamped linear radiance in W/(m²·sr), no exposure applied.
        #[arg(long, value_name = "EXR")]
        exr: Option<PathBuf>,
        /// Frames to render before capturing (the last is written).
        #[arg(long, default_value_t = 1)]
        frames: u32,
        /// Exposure multiplier applied before tone mapping the PNG.
        #[arg(long, default_value_t = 1.0)]
        exposure: f32,
    },
    /// Per-pass GPU time from timestamp queries: median, min and max over the frames.
    Profile {
        #[command(flatten)]
        render: RenderArgs,
        /// Frames to time.
        #[arg(long, default_value_t = 30)]
        frames: usize,
        /// Also write the report as JSON (with device and driver).
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
    },
    /// Show the chosen device, its driver, and the features and limits penumbra uses.
    Info {
        #[command(flatten)]
        device: DeviceArgs,
    },
    /// Open a window: fly camera (WASD, mouse drag to look, Q/E down/up, Shift faster),
    /// F12 saves a screenshot, R reloads shaders from glsl/, Esc quits. GPU pass times are shown in the title.
    Demo {
        #[command(flatten)]
        render: RenderArgs,
        /// Quit by itself after this many frames (for tests and scripted runs).
        #[arg(long)]
        frames: Option<u64>,
        /// Save a screenshot (PNG) of the last frame when quitting.
        #[arg(long, value_name = "PNG")]
        screenshot: Option<PathBuf>,
    },
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("`{s}`: expected WIDTHxHEIGHT, e.g. 640x360"))?;
    let p = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| n > 0 && n <= 16384);
    match (p(w), p(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{s}`: width and height must be whole numbers from 1 to 16384")),
    }
}

fn gpu_desc(d: &DeviceArgs) -> GpuDesc {
    let env = std::env::var("PENUMBRA_VALIDATION").map(|v| v == "1").unwrap_or(false);
    GpuDesc { validation: d.validation || env, device_name: d.device.clone(), display: None }
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
    }
}

fn run(cli: Cli) -> penumbra::Result<()> {
    match cli.command {
        Command::Capture { render, output, exr, frames, exposure } => {
            let opts = CaptureOptions { png: output, exr, frames, exposure, ..options(&render) };
            for path in penumbra::capture::run(&opts)? {
                println!("wrote {path}");
            }
        }
        Command::Profile { render, frames, json } => {
            let report = penumbra::profile::run(&options(&render), frames)?;
            print!("{}", report.table());
            if let Some(p) = json {
                let text = serde_json::to_string_pretty(&report).map_err(|e| penumbra::Error::Usage(e.to_string()))?;
                std::fs::write(&p, text).map_err(|e| penumbra::Error::Usage(format!("{}: {e}", p.display())))?;
                println!("wrote {}", p.display());
            }
        }
        Command::Info { device } => {
            let gpu = Gpu::new(&gpu_desc(&device))?;
            for (k, v) in gpu.caps().report() {
                println!("{k:<38} {v}");
            }
        }
        Command::Demo { render, frames, screenshot } => {
            let opts = options(&render);
            penumbra::demo::run(&opts, frames, screenshot)?;
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
