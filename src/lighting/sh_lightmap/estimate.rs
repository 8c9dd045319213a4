//! The bounces' time, estimated before a bake starts. The bounces shoot on the CPU whichever
//! baker casts the visibility rays, and their time grows as patches × shots, so the visibility's
//! rate says nothing of it: a GPU bake at fine patches can finish its rays in seconds and then
//! shoot for hours.

use super::samples::SampleSet;
use super::transfer;
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::Occluders;
use crate::util::progress::{Estimate, Progress};

/// The calibration's first bake has about this many patches, each next one four times as many
/// while the last one's time (its rays and its bounces) × [`GROWTH`] stays under [`BUDGET_S`]
/// (twice that for the second, which the fit needs), as radiosity's estimate calibrates.
const FIRST_PATCHES: f64 = 256.0;
const BUDGET_S: f64 = 2.0;
/// A calibration's time as its patches quadruple: its bounces', shots × receivers, each 4×.
const GROWTH: f64 = 16.0;
/// Bakes with fewer inside patches than this many times the first calibration's are not
/// estimated: they take about as long as a calibration.
const ESTIMATE_OVER: f64 = 16.0;
/// The calibration's rays per patch, at most: the shooting's cost does not depend on them, and
/// the direct light they project sets how much there is to shoot closely enough.
const CALIBRATION_SAMPLES: usize = 256;

/// The bounces' time for `inside` patches of `size`: the same scene's bounces at coarser patches
/// (CPU rays, at most [`CALIBRATION_SAMPLES`] a patch), timed, then scaled as the patches ×
/// the shots, the shots growing as a power of the patches fitted between the last two runs, up
/// to `max_shots`. Growing the shots as the patches (radiosity's estimate) overestimated the
/// courtyard's bounces at 8 and 6 cm 2.3–2.4×: its shots grow as about the 0.85th power.
/// `None`: no bounces, a small bake, or a calibration cancelled.
pub fn bounces(
    geometry: &StaticGeometry,
    settings: &transfer::Settings,
    samples: usize,
    size: f64,
    inside: usize,
    progress: &Progress,
) -> Option<Estimate> {
    if !settings.bounces || (inside as f64) <= ESTIMATE_OVER * FIRST_PATCHES {
        return None;
    }
    let area: f64 = geometry.triangles.iter().filter(|t| !t.sky).map(|t| t.area()).sum();
    let samples = SampleSet::new(samples.min(CALIBRATION_SAMPLES), settings.bands).ok()?;
    let occluders = Occluders::new(&geometry.triangles);
    let mut quiet = Progress::quiet("sh light-map calibration");
    // (inside patches, shots, seconds) of each calibration, coarsest first.
    let mut runs: Vec<(f64, f64, f64)> = Vec::new();
    let mut target = FIRST_PATCHES;
    let coarse = loop {
        let coarse = (area / target).sqrt().max(size);
        let step = std::time::Instant::now();
        let p = Patches::build(&geometry.triangles, coarse);
        let bits = transfer::visibility_cpu(&p, &occluders, &samples, settings.solve.mode, &mut quiet);
        let start = std::time::Instant::now();
        let t = transfer::bake(&p, &occluders, &samples, &bits, settings, &mut quiet);
        let seconds = start.elapsed().as_secs_f64();
        // The budget holds the whole run (its rays too), the estimate only the bounces' time.
        let step = step.elapsed().as_secs_f64();
        if progress.cancelled() {
            return None;
        }
        let n = p.patches.iter().filter(|q| q.inside()).count().max(1) as f64;
        runs.push((n, t.report.shots.max(1) as f64, seconds));
        // The next run has four times the patches, at most a quarter of the bake's. A second
        // run (the shots' growth is fitted between the last two) may take twice the budget.
        let budget = if runs.len() < 2 { 2.0 * BUDGET_S } else { BUDGET_S };
        if step * GROWTH > budget || target * 16.0 > inside as f64 {
            break coarse;
        }
        target *= 4.0;
    };
    let (n, shots, seconds) = runs[runs.len() - 1];
    // The shots grow as a power of the patches, fitted between the last two runs (as the
    // patches, where there is one run); the time per patch and shot as measured in the last.
    let growth = match runs[..] {
        [.., (n0, s0, _), (n1, s1, _)] if n1 > n0 * 1.5 => ((s1 / s0).ln() / (n1 / n0).ln()).clamp(0.5, 1.0),
        _ => 1.0,
    };
    let ratio = (inside as f64 / n).max(1.0);
    let full_shots = (shots * ratio.powf(growth)).min(settings.solve.max_shots as f64);
    Some(Estimate {
        seconds: seconds * ratio * full_shots / shots,
        method: format!(
            "the bounces at patch_size {coarse:.3} timed: {n:.0} patches, {shots:.0} shots in {seconds:.2} s; the shots grow as patches^{growth:.2}, the time as patches × shots"
        ),
        dominant: format!("the bounces (about {full_shots:.0} shots to {inside} patches)"),
        remedy: "a coarser patch_size, a higher threshold or bounces = false".into(),
    })
}

/// One estimate of two stages that run one after the other.
pub fn sum(a: Option<Estimate>, b: Option<Estimate>) -> Option<Estimate> {
    match (a, b) {
        (Some(a), Some(b)) => {
            let (big, small) = if a.seconds >= b.seconds { (&a, &b) } else { (&b, &a) };
            Some(Estimate {
                seconds: a.seconds + b.seconds,
                method: format!("{}; {}", a.method, b.method),
                dominant: big.dominant.clone(),
                remedy: format!("{}; for {}: {}", big.remedy, small.dominant, small.remedy),
            })
        }
        (a, b) => a.or(b),
    }
}
