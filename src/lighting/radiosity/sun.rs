//! The sun (the Ca3D-Engine thesis §3.3.2, digest §1.2 step C): a directional light reaches a patch where a
//! ray toward it, from each of the patch's sub-samples inside its polygon, reaches the sky; the
//! lit fraction scales its energy, and CaLight smooths the result to hide the staircase that
//! patch-sized shadows leave.
//!
//! What counts as reaching the sky (penumbra's choice where the seed is silent):
//! * faithful: the ray's first hit is a sky surface — unless the scene has no sky surface at
//!   all, when a ray that escapes counts (penumbra's scenes need no sky box; CaLight's levels
//!   always have one). Then the seed's smoothing filter.
//! * corrected: a sky surface is an opening to the sun, so the ray counts when it hits sky first
//!   or escapes; no smoothing (it would blur the true shadow), the sub-samples' mean is already
//!   the patch's mean irradiance.

use glam::DVec3;

use crate::lighting::lightmap::buried;
use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::{Mode, Occluders};
use crate::util::progress::Cancel;

/// Sub-samples per patch side (as the coverage estimate's).
const SAMPLES: usize = 4;

/// Each patch's lit fraction under a sun toward `to_sun` (unit, from the scene toward the sun);
/// 0 for patches outside their polygon, sky, or facing away. `None` when `cancel` asks it to stop
/// (looked at every row of patches).
pub fn lit_fraction(
    p: &Patches,
    occluders: &Occluders,
    to_sun: DVec3,
    mode: Mode,
    cancel: Option<&Cancel>,
) -> Option<Vec<f64>> {
    let escape_counts = mode == Mode::Corrected || !occluders.has_sky();
    let eps = 1e-4 * p.size;
    let mut out = vec![0.0; p.patches.len()];
    for c in &p.charts {
        if c.sky || c.normal.dot(to_sun) <= 0.0 {
            continue;
        }
        let flat = c.flat_triangles(&occluders.triangles);
        for j in 0..c.height {
            if cancel.is_some_and(Cancel::is_cancelled) {
                return None;
            }
            for i in 0..c.width {
                let k = c.first + j * c.width + i;
                if !p.patches[k].inside() {
                    continue;
                }
                // Corrected: only the part of the patch it keeps, not buried under other
                // geometry and on one side of a thin wall, as its area and centre are
                // (`lightmap::buried`).
                let samples: Vec<DVec3> = match mode {
                    Mode::Faithful => c
                        .inside_samples(&flat, p.size, i, j, SAMPLES)
                        .into_iter()
                        .map(|y| y + c.normal * eps)
                        .collect(),
                    Mode::Corrected => buried::seen_samples(occluders, c, &flat, p.size, (i, j)),
                };
                let inside = samples.len();
                let lit = samples
                    .iter()
                    .filter(|&&x| match occluders.first_hit(x, to_sun) {
                        Some((_, t)) => occluders.triangles[t].sky,
                        None => escape_counts,
                    })
                    .count();
                out[k] = if inside > 0 { lit as f64 / inside as f64 } else { 0.0 };
            }
        }
    }
    if mode == Mode::Faithful {
        smooth(p, &mut out);
    }
    Some(out)
}

/// The seed's smoothing filter (its kernel is not given): a 3×3 binomial kernel
/// (1 2 1)ᵀ(1 2 1)/16 over each chart's inside patches, renormalised where it meets the border.
pub fn smooth(p: &Patches, values: &mut [f64]) {
    let src = values.to_vec();
    for c in &p.charts {
        for j in 0..c.height {
            for i in 0..c.width {
                let k = c.first + j * c.width + i;
                if !p.patches[k].inside() {
                    continue;
                }
                let (mut sum, mut weight) = (0.0, 0.0);
                for dj in -1i64..=1 {
                    for di in -1i64..=1 {
                        let (ni, nj) = (i as i64 + di, j as i64 + dj);
                        if ni < 0 || nj < 0 || ni >= c.width as i64 || nj >= c.height as i64 {
                            continue;
                        }
                        let n = c.first + nj as usize * c.width + ni as usize;
                        if p.patches[n].inside() {
                            let w = ((2 - di.abs()) * (2 - dj.abs())) as f64;
                            sum += w * src[n];
                            weight += w;
                        }
                    }
                }
                values[k] = sum / weight;
            }
        }
    }
}
