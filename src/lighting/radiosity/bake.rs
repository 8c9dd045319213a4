//! From a scene to a baked light-map: the static triangles the baker sees, direct light from the
//! scene's punctual lights as initial energy, the solve, and the atlas (charts shelf-packed with
//! one-texel gaps, border patches filled by the seed's passes 1 and 2, [`crate::lighting::lightmap::border`], so
//! bilinear filtering never reads black at a polygon's edge nor steps at a seam).

use glam::DVec3;

use crate::backend::Gpu;
use crate::error::{Error, Result};
use crate::lighting::lightmap::atlas::{pack, texels, Atlas};
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::{self, Occluders, Settings};
use crate::scene::{Light, Scene};
use crate::shaders::ShaderLibrary;
use crate::util::progress::{Cancel, Estimate, Progress};

/// Where a bake cancelled before its first shot stopped: the patches, their buried parts, the
/// direct light and the shooter's tables.
pub const SET_UP: &str = "radiosity set-up";

fn set_up_cancelled() -> Error {
    Error::Cancelled(SET_UP.to_string())
}

/// What the light-map holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// Direct light from the scene's lights and emitters, and every bounce: the whole static frame.
    All,
    /// Only light that bounced at least once (for drawing under a direct method): no direct
    /// light of any light, quad lights and emissive surfaces included.
    Bounces,
}

/// Adds the reflected direct light of the scene's point, spot and directional lights (shadowed)
/// to every patch's total and unshot radiosity; returns each patch's share. Directional lights
/// are suns (`super::sun`) as the corrected mode treats them.
pub fn add_direct_light(p: &mut Patches, occluders: &Occluders, scene: &Scene) -> Result<Vec<DVec3>> {
    add_direct_light_in(p, occluders, scene, solve::Mode::Corrected, None)
}

/// [`add_direct_light`] with `mode`'s sun (faithful: rays must reach sky, then smoothing) and
/// point lights (faithful, in a BSP world: CaLight lights every patch in the light's PVS, with no
/// ray, so a pillar casts no shadow in the light-map; elsewhere, and corrected, a shadow ray).
/// Stops with [`SET_UP`] cancelled when `cancel` asks it to (the patches then unchanged).
pub fn add_direct_light_in(
    p: &mut Patches,
    occluders: &Occluders,
    scene: &Scene,
    mode: solve::Mode,
    cancel: Option<&Cancel>,
) -> Result<Vec<DVec3>> {
    let mut direct = vec![DVec3::ZERO; p.patches.len()];
    let eps = 1e-4 * p.size;
    // Corrected: the patch's mean irradiance over its visible sub-samples, as the sun's lit
    // fraction is: the light falls off as 1/d² and at a spot's cone, so the centre alone
    // misjudges patches near a light or across a cone's edge. Faithful: CaLight's one sample
    // per lumel.
    let points: Vec<Vec<DVec3>> = match mode {
        solve::Mode::Faithful => p.patches.iter().map(|q| vec![q.centre]).collect(),
        solve::Mode::Corrected => {
            let mut visible = crate::lighting::lightmap::buried::visible_samples(p, occluders, cancel)
                .ok_or_else(set_up_cancelled)?;
            for (points, q) in visible.iter_mut().zip(&p.patches) {
                if points.is_empty() {
                    // A sliver no sub-sample falls in: its centre.
                    points.push(q.centre + q.normal * eps);
                }
            }
            visible
        }
    };
    let irradiance = punctual_irradiance(p, occluders, scene, mode, &points, cancel)?;
    for (k, e) in irradiance.iter().enumerate() {
        direct[k] = p.patches[k].albedo * DVec3::from_array(*e);
    }
    if mode == solve::Mode::Corrected && scene.environment.is_some() {
        let env = crate::environment::EnvironmentMap::of_scene(scene)?;
        let sky =
            super::environment_light::irradiance(p, occluders, &env, &points, cancel).ok_or_else(set_up_cancelled)?;
        for (k, e) in sky.iter().enumerate() {
            direct[k] += p.patches[k].albedo * *e;
        }
    }
    for l in &scene.lights {
        if let Light::Directional {
            direction, irradiance, ..
        } = l
        {
            let to_sun = -direction.as_dvec3().normalize_or_zero();
            let lit = super::sun::lit_fraction(p, occluders, to_sun, mode, cancel).ok_or_else(set_up_cancelled)?;
            for (k, q) in p.patches.iter().enumerate() {
                direct[k] += q.albedo * irradiance.as_dvec3() * (q.normal.dot(to_sun).max(0.0) * lit[k]);
            }
        }
    }
    for (q, b) in p.patches.iter_mut().zip(&direct) {
        q.total += *b;
        q.unshot += *b;
    }
    Ok(direct)
}

/// Each patch's mean irradiance from the scene's point and spot lights over its `points`
/// (shadowed: by rays, or by the BSP world's PVS in faithful mode). Stops with [`SET_UP`]
/// cancelled when `cancel` asks it to (looked at every patch).
fn punctual_irradiance(
    p: &Patches,
    occluders: &Occluders,
    scene: &Scene,
    mode: solve::Mode,
    points: &[Vec<DVec3>],
    cancel: Option<&Cancel>,
) -> Result<Vec<[f64; 3]>> {
    let stop = || cancel.is_some_and(Cancel::is_cancelled);
    let eps = 1e-4 * p.size;
    let pvs = if mode == solve::Mode::Faithful {
        crate::lighting::lightmap::visibility::bsp_world(scene)?
    } else {
        None
    };
    let leaf = |x: DVec3| {
        pvs.as_ref()
            .map(|(w, translate)| w.leaf_of(crate::scene::world_mesh::scene_to_world(x.as_vec3() - *translate)))
    };
    let lights: Vec<&Light> = scene
        .lights
        .iter()
        .filter(|l| matches!(l, Light::Point { .. } | Light::Spot { .. }))
        .collect();
    let indices: Vec<usize> = if lights.is_empty() {
        Vec::new()
    } else {
        (0..p.patches.len()).collect()
    };
    let irradiance = crate::util::parallel::map(&indices, 64, |&k| {
        let q = &p.patches[k];
        if !q.inside() || stop() {
            return [0.0; 3];
        }
        let mut e = DVec3::ZERO;
        for &x in &points[k] {
            let x = if mode == solve::Mode::Faithful {
                x + q.normal * eps
            } else {
                x
            };
            for l in &lights {
                let Some((to_light, irradiance, far)) = punctual(l, x) else {
                    continue;
                };
                let cos = q.normal.dot(to_light);
                if cos <= 0.0 {
                    continue;
                }
                let seen = match (&pvs, leaf(x), leaf(far)) {
                    (Some((w, _)), Some(a), Some(b)) => w.is_visible(a, b),
                    _ => occluders.visible(x, far),
                };
                if seen {
                    e += irradiance * cos;
                }
            }
        }
        (e / points[k].len().max(1) as f64).to_array()
    });
    // Patches skipped once it was cancelled hold nothing: never used.
    if stop() {
        return Err(set_up_cancelled());
    }
    Ok(irradiance)
}

/// A point or spot light seen from `x`: (unit direction to it, irradiance on a surface facing
/// it, its position); `None` for other lights.
fn punctual(l: &Light, x: DVec3) -> Option<(DVec3, DVec3, DVec3)> {
    match l {
        Light::Point {
            position, intensity, ..
        } => {
            let d = position.as_dvec3() - x;
            Some((
                d.normalize_or_zero(),
                intensity.as_dvec3() / d.length_squared().max(1e-12),
                position.as_dvec3(),
            ))
        }
        Light::Spot {
            position,
            direction,
            intensity,
            inner_deg,
            outer_deg,
            ..
        } => {
            let d = position.as_dvec3() - x;
            let l = d.normalize_or_zero();
            let falloff = crate::lighting::brdf::spot_falloff(
                outer_deg.to_radians().cos(),
                inner_deg.to_radians().cos(),
                (-l).as_vec3().dot(direction.normalize()),
            );
            Some((
                l,
                intensity.as_dvec3() * falloff as f64 / d.length_squared().max(1e-12),
                position.as_dvec3(),
            ))
        }
        _ => None,
    }
}

/// Where the shooting runs.
pub enum Shooter<'a> {
    Cpu,
    Gpu(&'a mut Gpu, &'a ShaderLibrary),
}

impl Shooter<'_> {
    fn reborrow(&mut self) -> Shooter<'_> {
        match self {
            Shooter::Cpu => Shooter::Cpu,
            Shooter::Gpu(gpu, shaders) => Shooter::Gpu(gpu, shaders),
        }
    }
}

/// The calibration's first bake has about this many patches; each next one four times as many,
/// while the last one's time × [`CALIBRATION_GROWTH`] stays under [`CALIBRATION_BUDGET_S`]
/// (on lavapipe a release build calibrates at about 1,000 patches in under a second).
const CALIBRATION_PATCHES: f64 = 256.0;
const CALIBRATION_BUDGET_S: f64 = 2.0;
/// A calibration bake's time as its patches quadruple: the shooting's (16×) dominates.
const CALIBRATION_GROWTH: f64 = 16.0;
/// Bakes with fewer patches than this many times the calibration's first are not estimated:
/// they take about as long as a calibration.
const ESTIMATE_OVER: f64 = 16.0;

/// Where a bake's time went, by how it grows with the patches.
#[derive(Clone, Copy, Debug, Default)]
struct StageSeconds {
    /// Patches, occluders, direct light, atlas and borders: each patch once.
    set_up: f64,
    /// The shooting (and the emitters' first shot): every shot visits every receiver.
    shooting: f64,
}

/// The bake's time at `patch_size`, estimated before it starts: the same bake (same scene,
/// settings and shooter) run at coarser patches and timed, then extrapolated by the patches
/// inside: the set-up as the patches, the shooting as the patches × the shots, the shots as the
/// patches (the shooter count grows with the blocks; measured on the Cornell box, 706 → 2,700 →
/// 10,558 patches took 571 → 1,612 → 5,944 shots) but at most `max_shots`. `None`: a small bake
/// (or a cancelled calibration).
pub fn estimate(
    geometry: &StaticGeometry,
    scene: &Scene,
    patch_size: f64,
    settings: &Settings,
    content: Content,
    shooter: &mut Shooter<'_>,
) -> Result<Option<Estimate>> {
    let area: f64 = geometry.triangles.iter().filter(|t| !t.sky).map(|t| t.area()).sum();
    let patches = area / (patch_size * patch_size);
    if patches.is_nan() || patches <= ESTIMATE_OVER * CALIBRATION_PATCHES {
        return Ok(None);
    }
    let mut quiet = Progress::quiet("radiosity calibration");
    let mut target = CALIBRATION_PATCHES;
    let (size, inside, shots, times) = loop {
        let size = (area / target).sqrt();
        // A cancel during the calibration stops the bake before its own first shot: set-up.
        let ((p, _, _, report), times) =
            match bake_timed(geometry, scene, size, settings, content, shooter.reborrow(), &mut quiet) {
                Err(Error::Cancelled(_)) => return Err(set_up_cancelled()),
                r => r?,
            };
        if quiet.cancelled() {
            return Ok(None);
        }
        let inside = p.patches.iter().filter(|q| q.inside()).count().max(1) as f64;
        let seconds = times.set_up + times.shooting;
        if seconds * CALIBRATION_GROWTH > CALIBRATION_BUDGET_S || target * 4.0 * 4.0 > patches {
            break (size, inside, report.shots.max(1), times);
        }
        target *= 4.0;
    };
    let ratio = (patches / inside).max(1.0);
    let full_shots = (shots as f64 * ratio).min(settings.max_shots as f64);
    let shooting = times.shooting * ratio * full_shots / shots as f64;
    let set_up = times.set_up * ratio;
    Ok(Some(Estimate {
        seconds: shooting + set_up,
        method: format!(
            "the same bake at patch_size {size:.3} timed: {inside:.0} patches, {shots} shots in {:.2} s; the set-up grows as the patches, the shooting as patches × shots",
            times.set_up + times.shooting
        ),
        dominant: if shooting >= set_up {
            format!("shooting (about {full_shots:.0} shots to {patches:.0} patches)")
        } else {
            format!("patching and direct light ({patches:.0} patches)")
        },
        remedy: "a larger patch_size, a larger block or a higher threshold".into(),
    }))
}

/// What [`bake`] makes: the patches, the atlas, its texels and the solve's report.
pub type Baked = (Patches, Atlas, Vec<[f32; 4]>, solve::Report);

/// Bakes the light-map of `geometry`: patches, direct light, the solve, the texels. A bake
/// [`estimate`]d past a minute says so first.
pub fn bake(
    geometry: &StaticGeometry,
    scene: &Scene,
    patch_size: f64,
    settings: &Settings,
    content: Content,
    mut shooter: Shooter<'_>,
    progress: &mut Progress,
) -> Result<Baked> {
    if let Some(e) = estimate(geometry, scene, patch_size, settings, content, &mut shooter)? {
        progress.warn_before(&e);
    }
    Ok(bake_timed(geometry, scene, patch_size, settings, content, shooter, progress)?.0)
}

/// [`bake`] without the estimate, and where its time went.
fn bake_timed(
    geometry: &StaticGeometry,
    scene: &Scene,
    patch_size: f64,
    settings: &Settings,
    content: Content,
    shooter: Shooter<'_>,
    progress: &mut Progress,
) -> Result<(Baked, StageSeconds)> {
    let start = std::time::Instant::now();
    let cancel = progress.cancellation();
    let cancel = cancel.as_ref();
    let mut p = progress.stage("patches", || Patches::build(&geometry.triangles, patch_size));
    crate::bake::check_cancelled(progress, SET_UP)?;
    if let Some(r) = settings.reflectivity {
        // Every reflecting patch reflects `r`; the light-map then holds irradiance/π, drawn
        // times the material's albedo as ever.
        for q in p.patches.iter_mut().filter(|q| q.albedo != DVec3::ZERO) {
            q.albedo = DVec3::splat(r);
        }
    }
    let mut occluders = progress.stage("occluders", || Occluders::new(&geometry.triangles));
    if settings.mode == solve::Mode::Corrected {
        progress
            .stage("buried patch parts", || {
                crate::lighting::lightmap::buried::exclude(&mut p, &occluders, cancel)
            })
            .ok_or_else(set_up_cancelled)?;
    }
    occluders.pvs = progress.stage("chart visibility", || {
        crate::lighting::lightmap::visibility::scene_chart_pvs(scene, &p, &geometry.triangles)
    })?;
    crate::bake::check_cancelled(progress, SET_UP)?;
    let direct = progress.stage("direct light", || {
        add_direct_light_in(&mut p, &occluders, scene, settings.mode, cancel)
    })?;
    let shooting = std::time::Instant::now();
    let mut report = match shooter {
        Shooter::Cpu => solve::solve(&mut p, &occluders, settings, progress),
        Shooter::Gpu(gpu, shaders) => super::gpu::solve_in(
            gpu,
            shaders,
            &mut p,
            &geometry.triangles,
            occluders.pvs.as_ref(),
            settings,
            progress,
        )?,
    };
    // Light that bounced leaves out all direct light: the punctual lights' (added above) and the
    // area emitters' first shot, which the solve mixed into every receiver's total.
    let direct = match content {
        Content::All => direct,
        Content::Bounces => {
            let emitted = solve::emitters_first_shot(&p, &occluders, settings);
            direct.iter().zip(emitted).map(|(a, b)| *a + b).collect()
        }
    };
    let shooting = shooting.elapsed().as_secs_f64();
    let atlas = pack(&p);
    let mut values: Vec<DVec3> = p
        .patches
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let mut reflected = q.total - q.emission;
            if content == Content::Bounces {
                reflected -= direct[k];
            }
            let inv = |a: f64| if a > 0.0 { 1.0 / (a * std::f64::consts::PI) } else { 0.0 };
            (reflected * DVec3::new(inv(q.albedo.x), inv(q.albedo.y), inv(q.albedo.z))).max(DVec3::ZERO)
        })
        .collect();
    if settings.mode == solve::Mode::Faithful {
        // CaLight's light-maps are display values: tone reproduction, 8 bits, read as [0, 1].
        let inside: Vec<usize> = (0..values.len()).filter(|&k| p.patches[k].inside()).collect();
        let mapped = crate::lighting::lightmap::tone::reproduce(&inside.iter().map(|&k| values[k]).collect::<Vec<_>>());
        for (&k, c) in inside.iter().zip(mapped) {
            values[k] = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) / 255.0;
        }
    }
    report.border_refused = progress.stage("borders", || {
        crate::lighting::lightmap::border::apply(&p, &occluders, &mut values)
    });
    if settings.mode == solve::Mode::Faithful {
        // CaLight stores light-maps as RGB8: the border passes averaged display values, which
        // are quantized again here, so the texels are exactly the bytes the texture holds.
        for v in &mut values {
            *v = (*v * 255.0).round().clamp(DVec3::ZERO, DVec3::splat(255.0)) / 255.0;
        }
    }
    let texels = texels(&p, &atlas, |k| values[k]);
    let times = StageSeconds {
        set_up: start.elapsed().as_secs_f64() - shooting,
        shooting,
    };
    Ok(((p, atlas, texels, report), times))
}
