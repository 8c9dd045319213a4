//! CaSHL, the "radiosity of transfer functions" (the Ca3D-Engine thesis §5.2–5.4, digest §1.5): per patch, the
//! SH coefficients of its transfer function, direct (visibility rays to the sky over the shared
//! sample set) and bounced (the radiosity shooting loop, [`solve::shoot`], on coefficient vectors).
//!
//! Units (penumbra's choice where the seed leaves ρ/π open, digest §6 item 2):
//! * *corrected*: a texel's transfer `T` gives `dot(T, L) = E/π` for a light `L` in SH radiance
//!   coefficients, E the irradiance it receives directly and after bounces; the renderer
//!   multiplies by the texel's albedo, so a constant sky L₀ over open ground shows ρ·L₀ (test A).
//!   Bounces reflect the mean of the albedo's RGB (the transfer is one scalar function: an RGB
//!   light is three dot products, the Ca3D-Engine thesis's cheapest colour extension, digest §6 item 9).
//! * *faithful* ([CAFU-SRC]): the direct transfer is Σ cos·y·4π/N without ρ/π, bounces reflect
//!   ρ = 0.3 everywhere, then the \[LRP97\] tone mapping of transfer vectors (per patch, the vector
//!   scaled by display/world of its max |c|; then globally to max |c| = 1).

use glam::DVec3;

use super::samples::SampleSet;
use crate::lighting::lightmap::border;
use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::{self, Geometry, Mode, Occluders, Unshot};
use crate::lighting::lightmap::tone;
use crate::util::progress::{Estimate, Progress};

/// The seed's bounce reflectance ([CAFU-SRC]: ρ = 0.3 for every surface).
pub const FAITHFUL_REFLECTANCE: f64 = 0.3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Form factors, shooter choice and stop as the radiosity baker's, and the units above.
    pub solve: solve::Settings,
    pub bands: usize,
    /// Bounce the direct transfer (the Ca3D-Engine thesis §5.4.3); false stops at shadowed diffuse transfer.
    pub bounces: bool,
    /// The seed's transfer tone mapping (faithful default); false keeps transfers linear.
    pub tone: bool,
}

/// What a bake produced, per patch.
pub struct Transfer {
    /// `bands²` coefficients per patch (patch-major), after the border passes.
    pub coeffs: Vec<f64>,
    pub bands: usize,
    pub report: solve::Report,
}

/// A ray from a patch reaches the sky: it escapes, or (in faithful mode, when the scene has sky
/// surfaces) its first hit is a sky surface — the radiosity sun's rule (`crate::lighting::radiosity::sun`).
pub fn reaches_sky(occluders: &Occluders, from: DVec3, dir: DVec3, mode: Mode) -> bool {
    match occluders.first_hit(from, dir) {
        Some((_, t)) => occluders.triangles[t].sky,
        None => mode == Mode::Corrected || !occluders.has_sky(),
    }
}

/// The directions of `samples` that count for patch `k`: in front of both its plane and its
/// (possibly normal-mapped) normal (the Ca3D-Engine thesis §5.7, both-normals test).
fn counts(p: &Patches, k: usize, dir: DVec3) -> bool {
    let q = &p.patches[k];
    dir.dot(p.charts[q.chart].normal) > 0.0 && dir.dot(q.normal) > 0.0
}

/// Patch `k`'s visibility bits: one a sample, set where the ray toward it reaches the sky.
fn visibility_row(p: &Patches, occluders: &Occluders, samples: &SampleSet, mode: Mode, k: usize) -> Vec<u32> {
    let mut row = vec![0u32; samples.len().div_ceil(32)];
    let from = p.patches[k].centre + p.charts[p.patches[k].chart].normal * (1e-4 * p.size);
    for (s, &dir) in samples.dirs.iter().enumerate() {
        if counts(p, k, dir) && reaches_sky(occluders, from, dir, mode) {
            row[s / 32] |= 1 << (s % 32);
        }
    }
    row
}

/// Patches per core the estimate of [`visibility_cpu`]'s time traces.
const CALIBRATION_PATCHES: usize = 4;

/// [`visibility_cpu`]'s time, estimated before it starts: a few patches spread over the scene,
/// four a core, trace every sample (twice: the first run warms the caches), and the time scales
/// by the inside patches. The bounces that follow are estimated apart (`estimate::bounces`).
pub fn visibility_estimate(p: &Patches, occluders: &Occluders, samples: &SampleSet, mode: Mode) -> Option<Estimate> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let inside: Vec<usize> = (0..p.patches.len()).filter(|&k| p.patches[k].inside()).collect();
    let n = inside.len().min(CALIBRATION_PATCHES * threads);
    if n == 0 || samples.is_empty() {
        return None;
    }
    let picked: Vec<usize> = (0..n).map(|i| inside[i * inside.len() / n]).collect();
    let run = || {
        let start = std::time::Instant::now();
        std::thread::scope(|scope| {
            for mine in picked.chunks(n.div_ceil(threads)) {
                scope.spawn(move || {
                    for &k in mine {
                        std::hint::black_box(visibility_row(p, occluders, samples, mode, k));
                    }
                });
            }
        });
        start.elapsed().as_secs_f64()
    };
    run();
    let seconds = run();
    Some(Estimate {
        seconds: seconds * inside.len() as f64 / n as f64,
        method: format!(
            "{n} patches × {} samples timed: {:.2} µs a ray on {threads} core(s)",
            samples.len(),
            seconds * threads as f64 / (n * samples.len()) as f64 * 1e6
        ),
        dominant: format!("visibility of {} patches × {} samples", inside.len(), samples.len()),
        remedy: "fewer samples or a coarser patch_size (or baker = \"gpu\" on a GPU)".into(),
    })
}

/// Per inside patch, one bit per sample: the ray toward it reaches the sky (CPU path; the GPU
/// path is [`super::gpu`]). Words are `⌈N/32⌉` per patch.
pub fn visibility_cpu(
    p: &Patches,
    occluders: &Occluders,
    samples: &SampleSet,
    mode: Mode,
    progress: &mut Progress,
) -> Vec<u32> {
    let words = samples.len().div_ceil(32);
    let mut bits = vec![0u32; p.patches.len() * words];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let inside: Vec<usize> = (0..p.patches.len()).filter(|&k| p.patches[k].inside()).collect();
    let chunk = 64;
    // The rate is timed from here, not from the bake's start.
    progress.update(0, inside.len() as u64);
    for (done, part) in inside.chunks(chunk * threads).enumerate() {
        let rows: Vec<(usize, Vec<u32>)> = std::thread::scope(|scope| {
            let handles: Vec<_> = part
                .chunks(chunk)
                .map(|mine| {
                    scope.spawn(move || {
                        mine.iter()
                            .map(|&k| (k, visibility_row(p, occluders, samples, mode, k)))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        });
        for (k, row) in rows {
            bits[k * words..(k + 1) * words].copy_from_slice(&row);
        }
        progress.update(
            ((done + 1) * chunk * threads).min(inside.len()) as u64,
            inside.len() as u64,
        );
        // Cancelled: the bake this is part of stops after it and caches nothing.
        if progress.cancelled() {
            break;
        }
    }
    bits
}

/// The direct transfer from the visibility bits: Σ over visible samples of cos·y (cos against
/// the patch's normal), × 4π/N (the Ca3D-Engine thesis Eq. 10 without ρ/π).
pub fn project(p: &Patches, samples: &SampleSet, bits: &[u32]) -> Vec<f64> {
    let dim = samples.dim();
    let words = samples.len().div_ceil(32);
    let mut out = vec![0.0; p.patches.len() * dim];
    for (k, q) in p.patches.iter().enumerate() {
        if !q.inside() {
            continue;
        }
        let acc = &mut out[k * dim..(k + 1) * dim];
        for s in 0..samples.len() {
            if bits[k * words + s / 32] & (1 << (s % 32)) == 0 {
                continue;
            }
            let cos = samples.dirs[s].dot(q.normal);
            for (a, y) in acc.iter_mut().zip(samples.y(s)) {
                *a += cos * y;
            }
        }
        for a in acc.iter_mut() {
            *a *= samples.weight;
        }
    }
    out
}

/// Transfer vectors as the shooting loop's payload (the Ca3D-Engine thesis §5.4.3): L1 magnitude, a scalar
/// reflectance per patch.
struct Vectors {
    dim: usize,
    total: Vec<f64>,
    unshot: Vec<f64>,
    reflectance: Vec<f64>,
    /// Corrected: `total` is irradiance transfer (a receiver adds the incident shot, its
    /// reflectance applies only to what it shoots on); faithful: both are radiosity-like.
    corrected: bool,
}

impl Unshot for Vectors {
    fn magnitude(&self, k: usize) -> f64 {
        self.unshot[k * self.dim..(k + 1) * self.dim]
            .iter()
            .map(|c| c.abs())
            .sum()
    }
    fn reflects(&self, k: usize) -> bool {
        self.reflectance[k] > 0.0
    }
    fn shoot(&mut self, members: &[usize], area: &[f64], shares: &[(usize, f64)]) {
        let dim = self.dim;
        let mut flux = vec![0.0; dim];
        for &k in members {
            for (f, u) in flux.iter_mut().zip(&mut self.unshot[k * dim..(k + 1) * dim]) {
                *f += *u * area[k];
                *u = 0.0;
            }
        }
        for &(r, f) in shares {
            let rho = self.reflectance[r];
            let to_total = if self.corrected { f } else { rho * f };
            let (total, unshot) = (
                &mut self.total[r * dim..(r + 1) * dim],
                &mut self.unshot[r * dim..(r + 1) * dim],
            );
            for ((t, u), x) in total.iter_mut().zip(unshot.iter_mut()).zip(&flux) {
                *t += to_total * x;
                *u += rho * f * x;
            }
        }
    }
}

/// Bakes every patch's transfer: direct from `bits`, bounces, tone mapping, the border passes.
pub fn bake(
    p: &Patches,
    occluders: &Occluders,
    samples: &SampleSet,
    bits: &[u32],
    settings: &Settings,
    progress: &mut Progress,
) -> Transfer {
    let dim = samples.dim();
    let direct = project(p, samples, bits);
    let corrected = settings.solve.mode == Mode::Corrected;
    let reflectance: Vec<f64> = p
        .patches
        .iter()
        .map(|q| {
            if !q.inside() {
                0.0
            } else if corrected {
                (q.albedo.x + q.albedo.y + q.albedo.z) / 3.0
            } else {
                FAITHFUL_REFLECTANCE
            }
        })
        .collect();
    let unshot: Vec<f64> = if corrected {
        direct
            .iter()
            .enumerate()
            .map(|(i, c)| c * reflectance[i / dim])
            .collect()
    } else {
        direct.clone()
    };
    let mut v = Vectors {
        dim,
        total: direct,
        unshot,
        reflectance,
        corrected,
    };
    let report = if settings.bounces {
        solve::shoot(Geometry::from(p), occluders, &settings.solve, progress, &mut v)
    } else {
        solve::Report::default()
    };
    let mut coeffs = v.total;
    if corrected {
        for c in &mut coeffs {
            *c /= std::f64::consts::PI;
        }
    }
    if settings.tone {
        tone_map(p, &mut coeffs, dim);
    }
    let plan = border::Plan::new(p, occluders);
    plan.apply_flat(&mut coeffs, dim);
    Transfer {
        coeffs,
        bands: samples.bands,
        report: solve::Report {
            border_refused: plan.refused,
            ..report
        },
    }
}

/// The seed's transfer tone mapping ([CAFU-SRC], digest §1.5): the luminance proxy of a patch is
/// its max |c|; its vector is scaled by the \[LRP97\] display/world ratio of that proxy; then all
/// coefficients are rescaled together so that max |c| = 1.
pub fn tone_map(p: &Patches, coeffs: &mut [f64], dim: usize) {
    let lum: Vec<f64> = (0..p.patches.len())
        .map(|k| {
            if p.patches[k].inside() {
                coeffs[k * dim..(k + 1) * dim]
                    .iter()
                    .fold(0.0f64, |m, c| m.max(c.abs()))
            } else {
                0.0
            }
        })
        .collect();
    let scale = tone::display_scale(&lum);
    for (k, s) in scale.iter().enumerate() {
        for c in &mut coeffs[k * dim..(k + 1) * dim] {
            *c *= s;
        }
    }
    let max = coeffs.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if max > 0.0 {
        for c in coeffs.iter_mut() {
            *c /= max;
        }
    }
}

/// Shades a patch's transfer with light coefficients (one channel): `Σ T·L`.
pub fn shade(t: &[f64], light: &[f64]) -> f64 {
    t.iter().zip(light).map(|(a, b)| a * b).sum()
}
