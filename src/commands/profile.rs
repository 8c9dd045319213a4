//! `penumbra profile`: per-pass GPU time from timestamp queries, over many frames.

use serde::Serialize;

use crate::backend::Gpu;
use crate::bake::BakeReport;
use crate::commands::capture::{load_scene, CaptureOptions};
use crate::error::{Error, Result};
use crate::lighting::registry;
use crate::renderer::Renderer;
pub use crate::util::timing::{median, summarise, PassStats, TimingSummary};

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
    /// The configuration profiled (a method or a combination) and its methods in frame order.
    pub configuration: String,
    pub methods: Vec<String>,
    /// The bakes run (or read from the cache) when the methods were created: not frame time.
    pub bakes: Vec<BakeReport>,
    /// What the methods add to the report (their registry hooks), as text.
    pub method_report: String,
    /// The methods' device memory per resource group (the methods that itemise it).
    pub memory: Vec<crate::lighting::MemoryItem>,
    /// What the methods left out of the last frame ([`crate::lighting::LightingMethod::warnings`]).
    pub warnings: Vec<String>,
    /// What the last frame did that the timings do not show
    /// ([`crate::lighting::LightingMethod::frame_notes`]).
    pub notes: Vec<String>,
}

pub fn run(opts: &CaptureOptions, frames: usize) -> Result<ProfileReport> {
    let scene = load_scene(opts.scene.as_deref(), &opts.overrides)?;
    let gpu = Gpu::new(&opts.gpu)?;
    if gpu.caps().timestamp_valid_bits == 0 {
        return Err(Error::Backend(crate::backend::BackendError::Unsupported(format!(
            "{}: timestamps on the graphics queue (timestampValidBits = 0)",
            gpu.caps().name
        ))));
    }
    let config = registry::configuration(&scene, opts.method.as_deref())?;
    let bakes = crate::bake::Baker::new(Some(crate::bake::Baker::default_dir()));
    // The frames profiled and the one that warms the caches, estimated before the methods'
    // large allocations.
    let mut renderer = Renderer::for_run(gpu, scene, config, opts.size, bakes, frames.max(1) + 1)?;
    let camera = renderer.scene.camera.clone();
    // One frame to warm caches and learn which passes were culled.
    let culled = renderer
        .render(&camera, crate::renderer::FrameOutput::None)?
        .report
        .culled;
    renderer.gpu.submit_and_wait(renderer.last_frame())?;
    let mut timings = TimingSummary::default();
    renderer.profile_into(&camera, frames.max(1), &mut timings)?;
    let passes = timings.stats();
    let method_report = registry::reports(&renderer.configuration, &passes);
    let memory = renderer.method_memory()?;
    let warnings = renderer.method_warnings()?;
    let notes = renderer.method_frame_notes()?;
    let caps = renderer.gpu.caps();
    Ok(ProfileReport {
        configuration: renderer.configuration.name.clone(),
        methods: renderer.method_names().iter().map(|s| s.to_string()).collect(),
        bakes: renderer.bakes.clone(),
        method_report,
        memory,
        warnings,
        notes,
        device: caps.name.clone(),
        driver: format!("{} {}", caps.driver_name, caps.driver_info),
        width: opts.size.0,
        height: opts.size.1,
        frames: timings.frames(),
        passes,
        culled,
    })
}

impl ProfileReport {
    pub fn table(&self) -> String {
        let mut s = format!(
            "{} ({}), {}x{}, {} frames, {} ({})\n{:<28} {:>10} {:>10} {:>10}\n",
            self.device,
            self.driver,
            self.width,
            self.height,
            self.frames,
            self.configuration,
            self.methods.join(" + "),
            "pass",
            "median ms",
            "min ms",
            "max ms"
        );
        for p in &self.passes {
            s += &format!(
                "{:<28} {:>10.3} {:>10.3} {:>10.3}\n",
                p.name, p.median_ms, p.min_ms, p.max_ms
            );
        }
        if !self.culled.is_empty() {
            s += &format!("culled (outputs unused): {}\n", self.culled.join(", "));
        }
        s += &self.method_report;
        for n in &self.notes {
            s += &format!("{n}\n");
        }
        if !self.memory.is_empty() {
            s += &format!("{:<52} {:>12} {:>12}\n", "device memory", "requested", "allocated");
            for m in &self.memory {
                s += &format!("{:<52} {:>12} {:>12}\n", m.resource, m.requested, m.allocated);
            }
        }
        for w in &self.warnings {
            s += &format!("warning: {w}\n");
        }
        if !self.bakes.is_empty() {
            s += "bakes (at creation, not frame time):\n";
            s += &crate::bake::table(&self.bakes);
        }
        s
    }
}
