//! What a frame of the LPV will cost, before the first: the work of each stage from the
//! configuration (texels drawn, surfels injected, cell-steps propagated) times a time per unit
//! measured on this device when the method is set up (one RSM, G-buffer and injection at their
//! configured sizes, and two propagation steps over a sub-volume, timed with timestamp queries).

use super::config::{Config, Injection};
use crate::lighting::FrameCost;

/// The propagation's calibration volume: cells per side at most (a dispatch of 32³ cells lasts
/// long enough for a dispatch's fixed cost to vanish in it, and costs milliseconds).
pub const CALIBRATION_SIDE: u32 = 32;
/// Propagation steps timed; the fastest counts (the first may warm caches).
pub const CALIBRATION_STEPS: u32 = 2;

/// A frame's work per stage, in the units its time scales with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Work {
    /// Texels drawn: the RSM's and the G-buffer's.
    pub raster: f64,
    /// Surfels scattered (the RSM's and the G-buffer's texels) into each cascade, or the
    /// document's samples gathered by each cell.
    pub injection: f64,
    /// Cells × propagation steps × cascades.
    pub propagation: f64,
}

impl Work {
    pub fn of(config: &Config) -> Work {
        let texels = |side: u32| f64::from(side).powi(2);
        let drawn = texels(config.rsm) + texels(config.gbuffer);
        let cells = f64::from(config.grid).powi(3);
        let cascades = f64::from(config.cascades);
        Work {
            raster: drawn,
            injection: cascades
                * match config.injection {
                    Injection::Scatter => drawn,
                    Injection::Gather => cells * f64::from(config.samples),
                },
            propagation: cells * f64::from(config.iterations) * cascades,
        }
    }
}

/// Seconds per unit of [`Work`], measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    pub raster: f64,
    pub injection: f64,
    pub propagation: f64,
}

impl Rates {
    /// From one calibration's pass times (milliseconds, by pass name): `config`'s RSM and
    /// G-buffer, the injection (and resolve) into its finest volume, and `steps` propagation
    /// dispatches over `side`³ cells named by `is_step`.
    pub fn measured(config: &Config, times: &[(String, f64)], side: u32, is_step: impl Fn(&str) -> bool) -> Rates {
        let work = Work::of(config);
        let sum = |pick: &dyn Fn(&str) -> bool| times.iter().filter(|(n, _)| pick(n)).map(|(_, ms)| ms / 1e3).sum();
        let raster: f64 = sum(&|n: &str| n == "lpv rsm" || n == super::rsm::GBUFFER_PASS);
        let injection: f64 =
            sum(&|n: &str| !is_step(n) && (n.contains(" inject") || n.ends_with(" resolve") || n.ends_with(" gather")));
        let step = times
            .iter()
            .filter(|(n, _)| is_step(n))
            .map(|(_, ms)| ms / 1e3)
            .fold(f64::INFINITY, f64::min);
        let cells = f64::from(side).powi(3);
        let cascades = f64::from(config.cascades);
        Rates {
            raster: raster / work.raster.max(1.0),
            // The finest volume's injection is each cascade's.
            injection: injection * cascades / work.injection.max(1.0),
            propagation: if step.is_finite() { step / cells } else { 0.0 },
        }
    }
}

/// A frame of `config` at `rates`.
pub fn estimate(config: &Config, rates: &Rates) -> FrameCost {
    let work = Work::of(config);
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
                format!("RSM and G-buffer ({:.0} texels drawn)", work.raster),
                work.raster * rates.raster,
            ),
        ],
        remedy: "fewer iterations, a smaller grid, fewer cascades or a smaller rsm".into(),
    }
}

impl super::Lpv {
    /// Times one RSM, G-buffer and injection into the finest volume at the configured sizes, and
    /// [`CALIBRATION_STEPS`] propagation steps over at most [`CALIBRATION_SIDE`]³ of its cells;
    /// `None` where the device has no timestamps. The frames that follow overwrite all it wrote.
    pub(super) fn calibrate(
        &self,
        gpu: &mut crate::backend::Gpu,
        states: &mut crate::graph::ResourceStates,
        scene: &crate::gpu_scene::SceneGpu,
    ) -> crate::error::Result<Option<Rates>> {
        if gpu.caps().timestamp_valid_bits == 0 {
            return Ok(None);
        }
        let volume = &self.volumes[0];
        let side = volume.n.min(CALIBRATION_SIDE);
        let n = side as i32;
        let block = super::volume::VolumeBlock {
            size: [n, n, n, n * n * n],
            ..self.blocks[0]
        };
        let frame = gpu.create_frame()?;
        let mut graph = crate::graph::RenderGraph::new();
        self.rsm
            .add_raster(&mut graph, scene, &self.calls, self.transmittance, &self.blocks[0]);
        self.rsm
            .add_gbuffer(&mut graph, scene, &self.calls, self.transmittance, &self.gbuffer_raster);
        self.rsm
            .add_injection(&mut graph, volume, &self.blocks[0], &self.gbuffer_blocks[0]);
        let step = |k: u32| format!("lpv calibration step {k}");
        for k in 0..CALIBRATION_STEPS {
            volume.add_step(&mut graph, &block, k, &step(k));
        }
        graph.output_buffer(volume.accumulation);
        let ran = graph.run_and_wait(gpu, frame, states, "lpv calibration");
        let timings = ran
            .map_err(crate::error::Error::from)
            .and_then(|_| Ok(gpu.frame_timings(frame)?));
        gpu.destroy_frame(frame)?;
        let Some(timings) = timings? else {
            return Ok(None);
        };
        let times: Vec<(String, f64)> = timings.into_iter().map(|t| (t.name, t.ms)).collect();
        let steps: Vec<String> = (0..CALIBRATION_STEPS).map(step).collect();
        Ok(Some(Rates::measured(&self.config, &times, side, |name| {
            steps.iter().any(|s| s == name)
        })))
    }
}
