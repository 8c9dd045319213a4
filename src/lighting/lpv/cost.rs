//! What a frame of the LPV will cost, said before anything the configuration sizes is allocated:
//! the work of each stage from the configuration (texels drawn, surfels injected, cells resolved,
//! cell-steps propagated) times a time per unit measured on this device when the method is set
//! up. The measurement runs one frame's stages on small stand-ins (an RSM and G-buffer of at most
//! [`CALIBRATION_TEXELS`]², one volume of at most [`CALIBRATION_SIDE`]³ cells,
//! [`CALIBRATION_STEPS`] propagation steps), timed with timestamp queries and freed before the
//! full-size volumes and maps are made: at the documented maxima the estimate comes in seconds,
//! where the full-size resources alone would take longer to make than that.

use super::config::{Config, Injection};
use super::rsm::{self, LightCamera, Rsm};
use super::volume::{Placement, VolumeBlock, VolumeGpu};
use crate::backend::BufferId;
use crate::error::{Error, Result};
use crate::gpu_scene::{DrawCall, GpuLight};
use crate::graph::RenderGraph;
use crate::lighting::{CreateContext, FrameCost};

/// The calibration volume's cells per side at most. Its sets (about 70 MB in all at 64³) outgrow
/// the processor's caches as larger grids' do, so a cell-step's time carries over to them; a
/// volume that fits the caches runs faster per cell than a large one (measured on lavapipe: a
/// propagation step took 0.49 µs a cell at 32³, 0.76 at 64³ and 0.93 at 128³).
pub const CALIBRATION_SIDE: u32 = 64;
/// The calibration RSM's and G-buffer's texels per side at most: large enough that a draw's
/// fixed cost is small beside its texels', small enough to draw and inject in milliseconds.
pub const CALIBRATION_TEXELS: u32 = 512;
/// Propagation steps timed; the fastest counts (the first may warm caches).
pub const CALIBRATION_STEPS: u32 = 2;

/// The calibration's pass label: its passes are named "lpv calibration inject", ….
const LABEL: &str = "lpv calibration";

/// A frame's work per stage, in the units its time scales with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Work {
    /// Texels drawn: the RSMs' (one a light) and the G-buffer's.
    pub raster: f64,
    /// Surfels scattered (the RSM's and the G-buffer's texels) into each cascade, or the
    /// document's samples gathered by each cell.
    pub injection: f64,
    /// Cells × the passes that visit each cell once a frame (the resolve of the scattered sums,
    /// the geometry volume's faces) × cascades.
    pub cells: f64,
    /// Cells × propagation steps × cascades.
    pub propagation: f64,
}

impl Work {
    /// The work of `config` with an RSM for each of `lights` lights.
    pub fn of(config: &Config, lights: usize) -> Work {
        let texels = |side: u32| f64::from(side).powi(2);
        let drawn = texels(config.rsm) * lights.max(1) as f64 + texels(config.gbuffer);
        let cells = f64::from(config.grid).powi(3);
        let cascades = f64::from(config.cascades);
        let scatter = config.injection == Injection::Scatter;
        let faces = config.occlusion && !config.faithful_propagation() && config.iterations > 0;
        Work {
            raster: drawn,
            injection: cascades
                * match config.injection {
                    Injection::Scatter => drawn,
                    Injection::Gather => cells * f64::from(config.samples),
                },
            cells: cells * cascades * f64::from(u8::from(scatter) + u8::from(faces)),
            propagation: cells * f64::from(config.iterations) * cascades,
        }
    }
}

/// Seconds per unit of [`Work`], measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    pub raster: f64,
    pub injection: f64,
    pub cells: f64,
    pub propagation: f64,
}

impl Rates {
    /// From one calibration's pass times (milliseconds, by pass name) of the stages of `small`
    /// (one volume, its propagation steps named "… propagate k").
    pub fn measured(small: &Config, times: &[(String, f64)]) -> Rates {
        let work = Work::of(small, 1);
        let seconds = |pick: &dyn Fn(&str) -> bool| -> f64 {
            times.iter().filter(|(n, _)| pick(n)).map(|(_, ms)| ms / 1e3).sum()
        };
        let raster = seconds(&|n| n == "lpv rsm" || n == rsm::GBUFFER_PASS);
        let injection = seconds(&|n| n.contains(" inject") || n.ends_with(" gather"));
        let cells = seconds(&|n| n.ends_with(" resolve") || n.ends_with(" blocking faces"));
        let step = times
            .iter()
            .filter(|(n, _)| n.contains(" propagate "))
            .map(|(_, ms)| ms / 1e3)
            .fold(f64::INFINITY, f64::min);
        let per = |s: f64, units: f64| if units > 0.0 { s / units } else { 0.0 };
        Rates {
            raster: per(raster, work.raster),
            injection: per(injection, work.injection),
            cells: per(cells, work.cells),
            propagation: if step.is_finite() {
                step / f64::from(small.grid).powi(3)
            } else {
                0.0
            },
        }
    }
}

/// A frame of `config` at `rates`.
pub fn estimate(config: &Config, rates: &Rates, lights: usize) -> FrameCost {
    let work = Work::of(config, lights);
    FrameCost {
        parts: vec![
            (
                format!(
                    "propagation ({}³ cells × {} steps × {} cascade(s))",
                    config.grid, config.iterations, config.cascades
                ),
                work.propagation * rates.propagation,
            ),
            (
                match config.injection {
                    Injection::Scatter => format!("injection ({:.0} surfels into each cascade)", work.raster),
                    Injection::Gather => format!("gather ({} samples a cell)", config.samples),
                },
                work.injection * rates.injection,
            ),
            (
                format!(
                    "resolve and geometry volume ({}³ cells × {} cascade(s))",
                    config.grid, config.cascades
                ),
                work.cells * rates.cells,
            ),
            (
                format!("RSM and G-buffer ({:.0} texels drawn)", work.raster),
                work.raster * rates.raster,
            ),
        ],
        remedy: "fewer iterations, a smaller grid, fewer cascades or a smaller rsm".into(),
    }
}

/// The configuration the calibration runs: `config`'s settings on one volume of at most
/// [`CALIBRATION_SIDE`]³ cells, maps of at most [`CALIBRATION_TEXELS`]² and
/// [`CALIBRATION_STEPS`] steps.
pub fn calibration_config(config: &Config) -> Config {
    Config {
        grid: config.grid.min(CALIBRATION_SIDE),
        rsm: config.rsm.min(CALIBRATION_TEXELS),
        gbuffer: config.gbuffer.min(CALIBRATION_TEXELS),
        iterations: CALIBRATION_STEPS,
        cascades: 1,
        ..*config
    }
}

/// Times one frame's stages of [`calibration_config`] over the cube `placement` covers, lit by
/// `light`, and frees all it made; `None` where the device has no timestamps.
pub(super) fn calibrate(
    cx: &mut CreateContext<'_>,
    config: &Config,
    light: &GpuLight,
    placement: &Placement,
    calls: &[DrawCall],
    transmittance: BufferId,
) -> Result<Option<Rates>> {
    if cx.gpu.caps().timestamp_valid_bits == 0 {
        return Ok(None);
    }
    let small = calibration_config(config);
    let cover = Placement::around(placement.centre(), placement.n as f32 * placement.cell, small.grid);
    let camera = LightCamera::new(light, &cover, small.rsm, small.snap)?;
    let block = camera.block(&cover, &small);
    let eye = cx.scene.camera.position.extend(1.0).into();
    let view_proj = cx.scene.camera.view_projection(1.0).to_cols_array();
    let gbuffer = rsm::gbuffer_block(&block, view_proj, eye, small.gbuffer);
    cx.gpu.begin_resource_scope();
    let timed = time_stages(cx, &small, [&block, &gbuffer], calls, transmittance);
    let scope = cx.gpu.end_resource_scope();
    let freed = cx.gpu.destroy_scope(&scope);
    for &b in &scope.buffers {
        cx.states.forget_buffer(b);
    }
    for &i in &scope.images {
        cx.states.forget_image(i);
    }
    let times = timed?;
    freed?;
    Ok(times.map(|t| Rates::measured(&small, &t)))
}

/// One frame's stages of `small` (its RSM at `blocks[0]`, its G-buffer at `blocks[1]`): pass
/// names and milliseconds.
fn time_stages(
    cx: &mut CreateContext<'_>,
    small: &Config,
    blocks: [&VolumeBlock; 2],
    calls: &[DrawCall],
    transmittance: BufferId,
) -> Result<Option<Vec<(String, f64)>>> {
    let scene = cx.scene_gpu;
    let volume = VolumeGpu::new(cx.gpu, cx.shaders, cx.states, small, LABEL)?;
    let maps = Rsm::new(cx.gpu, cx.shaders, cx.states, small, 1)?;
    let mut graph = RenderGraph::new();
    maps.add_raster(&mut graph, scene, calls, transmittance, std::slice::from_ref(blocks[0]));
    maps.add_gbuffer(&mut graph, scene, calls, transmittance, blocks[1]);
    maps.add_injection(&mut graph, &volume, std::slice::from_ref(blocks[0]), blocks[1]);
    volume.add_propagation(&mut graph, blocks[0]);
    graph.output_buffer(volume.accumulation);
    let frame = cx.gpu.create_frame()?;
    let ran = graph.run_and_wait(cx.gpu, frame, cx.states, LABEL);
    let timings = ran.map_err(Error::from).and_then(|_| Ok(cx.gpu.frame_timings(frame)?));
    cx.gpu.destroy_frame(frame)?;
    Ok(timings?.map(|t| t.into_iter().map(|t| (t.name, t.ms)).collect()))
}
