//! Light propagation volumes (Dickson et al. 2011, digest `seed-004-lpv-leaves.md`): one bounce of light
//! from a reflective shadow map, injected into a grid of 2-band SH, propagated cell to cell and
//! looked up per pixel — the indirect term over any direct method.
//!
//! Passes per frame: **rsm** (the scene from the light: reflected and transmitted flux, surfel
//! area, position, normal); **inject** and **resolve** (every texel scattered as a cosine lobe
//! into fixed-point sums, then floats; the geometry volume from the same surfels) or the
//! document's **gather**; **propagate** ×K (one compute dispatch each); **composite** (the
//! scene's surfaces drawn again, the volume looked up, added into the radiance).
//!
//! *Corrected* is Kaplanyan & Dachsbacher's LPV with leaf transmission; *faithful* is the
//! document's: gather with the compounding transform, delta lobes and the 0.75 fudge,
//! 18-neighbour propagation that accumulates in place, and the point look-up of SH(−n).

pub mod config;
pub mod cost;
pub mod grid;
pub mod rsm;
pub mod sh;
pub mod volume;

#[cfg(test)]
mod tests;

use glam::Vec3;

use crate::backend::{
    vk, Bind, BlendMode, BufferId, ColorTarget, DepthState, GraphicsPipelineDesc, PipelineId, RenderTarget,
    RenderingDesc, SpecConstant, SubresourceRange,
};
use crate::error::{Error, Result};
use crate::gpu_scene::{punctual_lights, record_draws, vertex_layout, DrawCall, GpuLight};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{CreateContext, FrameContext, LightingMethod, ReferenceKind, Term, RADIANCE_FORMAT};
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema};
use config::{Config, Injection, Lookup, Mode};
use rsm::{LightCamera, Rsm};
use volume::{Placement, VolumeBlock, VolumeGpu};

pub const NAME: &str = "lpv";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "grid",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "iterations",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "rsm",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "injection",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "lookup",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "geometry_volume",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "clamp",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "storage",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "samples",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "transform_bug",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "published_omega",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "light",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "max_lights",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "light_spin",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "snap",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "blend",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "centre",
            kind: ParamKind::FloatArray,
        },
        ParamSchema {
            name: "size",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "view",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "cascades",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "gbuffer",
            kind: ParamKind::Int,
        },
        // Refused with its new name.
        ParamSchema {
            name: "camera_surfels",
            kind: ParamKind::Int,
        },
    ],
};

/// An LPV computes the first bounce only.
pub fn reference(_decl: &MethodDecl) -> ReferenceKind {
    ReferenceKind::Indirect(1)
}

/// The chart's sweep: as declared; corrected at 16³, 32³ and 64³, with 4, 8 and 16
/// iterations, at RSM 128² and 512², without the geometry volume, with the camera's G-buffer
/// added to it (or without it where declared), with 3 cascades around the camera; the
/// document's mode, and with its transform bug fixed.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d, None) {
            let mut label = format!("lpv {:?} {}³ k={} rsm {}²", c.mode, c.grid, c.iterations, c.rsm).to_lowercase();
            if c.mode == Mode::Corrected && !c.occlusion {
                label += " no gv";
            }
            if c.cascades > 1 {
                label += &format!(" {} cascades", c.cascades);
            }
            if c.mode == Mode::Faithful && !c.transform_bug {
                label += " transform fixed";
            }
            if c.gbuffer > 0 {
                label += &format!(" gbuffer {}²", c.gbuffer);
            }
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    let corrected = decl.with("mode", "corrected".into());
    for g in [16i64, 32, 64] {
        push(corrected.with("grid", g.into()));
    }
    for k in [4i64, 8, 16] {
        push(corrected.with("iterations", k.into()));
    }
    for r in [128i64, 512] {
        push(corrected.with("rsm", r.into()));
    }
    // Without a geometry volume the G-buffer has nothing to feed: left out, not warned about.
    let mut no_volume = corrected.with("geometry_volume", false.into());
    no_volume.params.retain(|(n, _, _)| n != "gbuffer");
    push(no_volume);
    // The geometry volume from the RSM's surfels alone, and with the G-buffer's added.
    let gbuffer = Config::from_decl(&corrected, None).map_or(0, |c| c.gbuffer);
    push(corrected.with("gbuffer", (if gbuffer > 0 { 0i64 } else { 128 }).into()));
    // Cascades follow the camera: only a region's side carries over.
    let mut cascaded = corrected.with("cascades", 3i64.into());
    cascaded.params.retain(|(n, _, _)| n != "centre");
    push(cascaded);
    // The document's mode has no geometry volume: the G-buffer is left out of it likewise.
    let mut faithful = decl.with("mode", "faithful".into());
    faithful.params.retain(|(n, _, _)| n != "gbuffer");
    push(faithful.clone());
    push(faithful.with("transform_bug", false.into()));
    out
}

/// Bytes a volume of `config` allocates: three sets (two wavefronts and the accumulation), the
/// injection sums (12 words a cell) and the geometry volume (sums, corners and faces, 32 words).
fn volume_bytes(config: &Config) -> u64 {
    3 * volume::set_bytes(config.grid, config.half) + (config.grid as u64).pow(3) * (12 + 4 + 4 + 12) * 4
}

/// The cells the scene spans along its longest axis in the volume `config` places: the fitted
/// volume spans it in `grid` − 2 cells; a region or the finest cascade in at most `grid`.
fn cells_across(config: &Config, extent: f64, eye: Vec3, bounds: (glam::DVec3, glam::DVec3)) -> u32 {
    let n = config.grid;
    let side = match (config.region, config.cascades) {
        (None, 1) => return n.saturating_sub(2).max(1),
        (Some((_, size)), _) => size as f64,
        (None, c) => {
            let eye = eye.as_dvec3();
            let reach = (bounds.0 - eye).abs().max((bounds.1 - eye).abs()).max_element();
            2.0 * reach / (1u32 << (c - 1)) as f64
        }
    };
    let cell = side / n as f64;
    ((extent / cell).ceil() as u32).clamp(1, n)
}

/// Corrected mode: `iterations` from the cells light must cross when unset (the document's mode
/// keeps its 2). Refused when the volumes and the RSM would not fit the memory budget.
pub fn plan(
    decl: &MethodDecl,
    facts: &crate::lighting::plan::Facts<'_>,
) -> Result<Vec<crate::lighting::plan::Derived>> {
    use crate::lighting::plan::Derived;
    let mut config = Config::from_decl(decl, Some(facts.scene))?;
    let mut derived = Vec::new();
    if config.mode == Mode::Corrected && decl.param("iterations").is_none() {
        if let Some(bounds) = facts.bounds(NAME)? {
            let extent = (bounds.1 - bounds.0).max_element();
            let cells = cells_across(&config, extent, facts.scene.camera.position, bounds);
            // Light from the scene's middle reaches its farthest side in half the cells across.
            // Crossing all of them over-carries: every pass adds its wavefront to the
            // accumulation, and in closed rooms the light that should have left piles up
            // (measured 1.38-1.55x the one-bounce light at 30 passes, 1.0-1.13x at 16).
            let passes = cells.div_ceil(2);
            config.iterations = passes;
            derived.push(Derived::new(
                "iterations",
                i64::from(passes),
                format!(
                    "grid {} cells: the scene's {extent:.2} m spans {cells}, light from its middle crosses {passes}",
                    config.grid
                ),
            ));
        }
    }
    let rsms = if every_light(decl, &config) {
        derived.extend(max_lights_note(decl, &config, facts.scene));
        (by_flux(&punctual_lights(facts.scene), glam::DVec3::ZERO).len()).clamp(1, config.max_lights) as u64
    } else {
        derived.extend(light_note(decl, facts.scene, facts.bounds(NAME)?));
        1
    };
    let texels = |side: u32| (side as u64).pow(2) * (4 * 16 + 4);
    let need = u64::from(config.cascades) * volume_bytes(&config) + rsms * texels(config.rsm) + texels(config.gbuffer);
    facts.check(
        NAME,
        &format!(
            "{} volume(s) of {}³ cells in {} with an RSM of {}²",
            config.cascades,
            config.grid,
            if config.half { "f16" } else { "f32" },
            config.rsm
        ),
        need,
        "set a smaller grid, fewer cascades or a smaller rsm",
    )?;
    Ok(derived)
}

/// The volume over the scene's objects (emitters left out) at their placement.
fn scene_bounds(cx: &CreateContext<'_>) -> Option<(Vec3, Vec3)> {
    let mut min = Vec3::splat(f32::INFINITY);
    let mut max = Vec3::splat(f32::NEG_INFINITY);
    for (d, mesh) in cx.scene_gpu.draws.iter().zip(&cx.scene_gpu.meshes) {
        if d.object.is_none() {
            continue;
        }
        for p in &mesh.positions {
            let w = d.model.transform_point3(*p);
            min = min.min(w);
            max = max.max(w);
        }
    }
    min.is_finite().then_some((min, max))
}

/// Matches `Cascades` in glsl/lpv/composite.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct CascadeBlock {
    count: [u32; 4],
    /// xyz: corner; w: cell size.
    origin: [[f32; 4]; 4],
}

/// The cascades around `eye`: the finest of side `finest`, each next twice as wide, each snapped
/// to its own cells.
fn cascade_placements(eye: Vec3, finest: f32, config: &Config) -> Vec<Placement> {
    (0..config.cascades)
        .map(|k| Placement::around(eye, finest * (1 << k) as f32, config.grid))
        .collect()
}

fn cascade_block(placements: &[Placement]) -> CascadeBlock {
    let mut b = CascadeBlock {
        count: [placements.len() as u32, 0, 0, 0],
        ..Default::default()
    };
    for (o, p) in b.origin.iter_mut().zip(placements) {
        *o = p.origin.extend(p.cell).into();
    }
    b
}

/// Per material: the diffuse transmittance (rgb); emitters' materials, after the scene's,
/// transmit nothing.
fn transmittance_buffer(cx: &mut CreateContext<'_>) -> Result<BufferId> {
    let mut tau: Vec<[f32; 4]> = cx
        .scene
        .materials
        .iter()
        .map(|m| m.transmittance.extend(0.0).into())
        .collect();
    tau.resize(tau.len().max(cx.scene_gpu.material_maps.len()).max(1), [0.0; 4]);
    let transmittance = cx
        .gpu
        .create_storage_buffer("lpv transmittance", bytemuck::cast_slice(&tau))?;
    cx.states.forget_buffer(transmittance);
    Ok(transmittance)
}

/// The flux a spot or sun sends into a scene whose bounds are `size` across (W), `None` for
/// other lights: a spot's intensity over its cone, 2π(1 − cos θ_outer) sr; a sun's irradiance
/// over the bounds seen along its direction.
fn light_flux(l: &GpuLight, size: glam::DVec3) -> Option<f64> {
    use crate::gpu_scene::{LIGHT_DIRECTIONAL, LIGHT_SPOT};
    let power = f64::from(l.intensity[0].max(l.intensity[1]).max(l.intensity[2]));
    if l.position[3] == LIGHT_SPOT {
        Some(power * std::f64::consts::TAU * (1.0 - f64::from(l.cone[1])))
    } else if l.position[3] == LIGHT_DIRECTIONAL {
        let d = glam::Vec3::from_slice(&l.direction[..3])
            .as_dvec3()
            .normalize_or_zero()
            .abs();
        Some(power * (d.x * size.y * size.z + d.y * size.x * size.z + d.z * size.x * size.y))
    } else {
        None
    }
}

/// The spots and suns of `lights` (index, flux), the most flux first (scene order on a tie).
fn by_flux(lights: &[GpuLight], size: glam::DVec3) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = (lights.iter().enumerate())
        .filter_map(|(i, l)| light_flux(l, size).map(|f| (i, f)))
        .collect();
    out.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    out
}

/// `light` when unset and the volume takes one light (the document's mode, the gather): the
/// spot or sun that sends the most flux into the scene ([`light_flux`]; a point light would
/// need a cube RSM), so that the one light a volume bounces is the one with the most light to
/// bounce. `None` where that is light 0 (the default), or where the scene has no such light
/// (then the method is refused at creation, naming the light).
fn light_note(
    decl: &MethodDecl,
    scene: &crate::scene::Scene,
    bounds: Option<(glam::DVec3, glam::DVec3)>,
) -> Option<crate::lighting::plan::Derived> {
    if decl.param("light").is_some() {
        return None;
    }
    let size = bounds.map_or(glam::DVec3::ZERO, |(lo, hi)| hi - lo);
    let lights = punctual_lights(scene);
    let ranked = by_flux(&lights, size);
    let &(best, most) = ranked.first()?;
    (best != 0).then(|| {
        crate::lighting::plan::Derived::new(
            "light",
            best as i64,
            format!(
                "of the scene's {} point, spot and directional lights, the spot or sun that sends the most flux into the scene ({most:.3} W; point lights would need a cube RSM); {} other spot or sun light(s) left out, one light a volume",
                lights.len(),
                ranked.len() - 1
            ),
        )
    })
}

/// `max_lights` when unset and the scene has more spots and suns than it: said, with how many
/// the volume leaves out (the dimmest), since each light costs an RSM and an injection a frame.
fn max_lights_note(
    decl: &MethodDecl,
    config: &Config,
    scene: &crate::scene::Scene,
) -> Option<crate::lighting::plan::Derived> {
    let lights = punctual_lights(scene);
    let candidates = by_flux(&lights, glam::DVec3::ZERO).len();
    (decl.param("max_lights").is_none() && candidates > config.max_lights).then(|| {
        crate::lighting::plan::Derived::new(
            "max_lights",
            config.max_lights as i64,
            format!(
                "the scene has {candidates} spot and sun lights, an RSM and an injection each a frame: the {} sending the most flux light the volume, {} are left out",
                config.max_lights,
                candidates - config.max_lights
            ),
        )
    })
}

/// Every light's block for every volume, `[volume][light]`: the fixed-point units shared, over
/// the lights' summed flux bounds (so that their sums add), and the blocking from the first
/// light's RSM alone (a surface two lights see would otherwise block twice).
fn light_blocks(cameras: &[LightCamera], placements: &[Placement], config: &Config) -> Vec<Vec<VolumeBlock>> {
    let flux: f32 = cameras.iter().map(|c| c.flux_bound).sum();
    (placements.iter())
        .map(|p| {
            (cameras.iter().enumerate())
                .map(|(k, c)| {
                    let mut b = c.block_sharing(p, config, flux);
                    b.rsm[3] = i32::from(k > 0);
                    b
                })
                .collect()
        })
        .collect()
}

/// The lights whose RSMs the volume takes: in the corrected scatter, with `light` unset, the
/// scene's spot and directional lights (point lights would need a cube RSM), at most
/// `max_lights` of them, the most flux first (the first adds the blocking); else the one light
/// `light` names (the document's mode and the gather take one).
fn lights_of(cx: &CreateContext<'_>, decl: &MethodDecl, config: &Config) -> Result<Vec<GpuLight>> {
    if every_light(decl, config) {
        let size = scene_bounds(cx).map_or(glam::DVec3::ZERO, |(lo, hi)| (hi - lo).as_dvec3());
        let lights = punctual_lights(cx.scene);
        let chosen: Vec<GpuLight> = (by_flux(&lights, size).into_iter())
            .take(config.max_lights)
            .map(|(i, _)| lights[i])
            .collect();
        if !chosen.is_empty() {
            return Ok(chosen);
        }
    }
    Ok(vec![light_of(cx, decl, config)?])
}

/// Whether the volume takes every spot and directional light: the corrected scatter with
/// `light` unset.
fn every_light(decl: &MethodDecl, config: &Config) -> bool {
    decl.param("light").is_none() && config.mode == Mode::Corrected && config.injection == Injection::Scatter
}

/// The scene's punctual light (point, spot or directional, in order) the configuration lights
/// the RSM with.
fn light_of(cx: &CreateContext<'_>, decl: &MethodDecl, config: &Config) -> Result<GpuLight> {
    let lights = punctual_lights(cx.scene);
    let light = lights.get(config.light).ok_or_else(|| {
        let msg = format!(
            "light {} does not exist: the scene has {} point, spot or directional light(s), and the RSM needs one",
            config.light,
            lights.len()
        );
        Error::from(cx.scene.method_param_error(decl, "light", msg))
    })?;
    Ok(*light)
}

/// Where the volumes lie: the cascades around the camera at `eye` (and the finest one's side),
/// or one volume over the region or over the objects' `bounds`.
fn place_volumes(eye: Vec3, bounds: (Vec3, Vec3), config: &Config) -> (Option<f32>, Vec<Placement>) {
    let finest = (config.cascades > 1).then(|| {
        // Without a size, the largest cascade reaches every object from the camera it is
        // centred on: twice the farthest bound along any axis (a camera outside the scene,
        // as in a Cornell box seen through its open side, would otherwise light nothing).
        let reach = (bounds.0 - eye).abs().max((bounds.1 - eye).abs()).max_element();
        config
            .region
            .map_or(2.0 * reach / (1 << (config.cascades - 1)) as f32, |r| r.1)
            .max(1e-3)
    });
    let placements = match (config.region, finest) {
        (_, Some(side)) => cascade_placements(eye, side, config),
        (Some((centre, size)), None) => {
            let half = glam::Vec3::splat(0.5 * size);
            vec![Placement::fit(
                glam::Vec3::from(centre) - half,
                glam::Vec3::from(centre) + half,
                config.grid,
            )]
        }
        (None, None) => vec![Placement::fit(bounds.0, bounds.1, config.grid)],
    };
    (finest, placements)
}

/// `count` volumes' sets and sums, the finest first.
fn create_volumes(cx: &mut CreateContext<'_>, config: &Config, count: usize) -> Result<Vec<VolumeGpu>> {
    let mut volumes = Vec::new();
    for k in 0..count {
        let label = if k == 0 {
            NAME.to_string()
        } else {
            format!("{NAME} cascade {k}")
        };
        volumes.push(VolumeGpu::new(cx.gpu, cx.shaders, cx.states, config, &label)?);
    }
    Ok(volumes)
}

/// The scene's surfaces drawn again, the volume looked up and added into the radiance.
fn composite_pipeline(cx: &mut CreateContext<'_>, config: &Config) -> Result<PipelineId> {
    let mut desc = GraphicsPipelineDesc::new("lpv composite", "frame/surface.vert", Some("lpv/composite.frag"));
    desc.vertex_layout = vertex_layout();
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
    desc.depth_format = Some(cx.gpu.caps().depth_stencil_format);
    desc.depth = DepthState {
        test: true,
        write: false,
        compare: vk::CompareOp::LESS_OR_EQUAL,
    };
    desc.color_targets[0].blend = BlendMode::Additive;
    let view = if config.view.full_screen() { 0 } else { config.view.id() };
    desc.specialization = vec![
        SpecConstant {
            id: 0,
            bits: (config.lookup == Lookup::Point) as u32,
        },
        SpecConstant { id: 1, bits: view },
        SpecConstant {
            id: 2,
            bits: config.blend as u32,
        },
        SpecConstant {
            id: 10,
            bits: config.half as u32,
        },
    ];
    Ok(cx.gpu.create_graphics_pipeline(&desc, cx.shaders)?)
}

/// The full-screen debug view's pipeline, when the configuration's view is one.
fn debug_pipeline(cx: &mut CreateContext<'_>, config: &Config) -> Result<Option<PipelineId>> {
    if !config.view.full_screen() {
        return Ok(None);
    }
    let mut desc = GraphicsPipelineDesc::new("lpv debug view", "post/fullscreen.vert", Some("lpv/debug.frag"));
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.depth = DepthState {
        test: false,
        write: false,
        compare: vk::CompareOp::ALWAYS,
    };
    desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
    desc.specialization = vec![
        SpecConstant {
            id: 0,
            bits: config.view.id(),
        },
        SpecConstant {
            id: 10,
            bits: config.half as u32,
        },
    ];
    Ok(Some(cx.gpu.create_graphics_pipeline(&desc, cx.shaders)?))
}

/// The LPV as the indirect term.
pub struct Lpv {
    config: Config,
    /// One volume, or the cascades from the finest.
    pub placements: Vec<Placement>,
    /// The finest cascade's side when the cascades follow the camera.
    finest: Option<f32>,
    /// The lights as the last frame had them (the scene's light motion and board applied, then
    /// turned by `light_spin`), each with its index in the frame's lights.
    lights: Vec<(GpuLight, usize)>,
    /// Per light, over the largest volume.
    cameras: Vec<LightCamera>,
    /// Per volume (cascade), each light's block.
    blocks: Vec<Vec<VolumeBlock>>,
    /// The camera's G-buffer: drawing it, and injecting its surfels into each volume.
    gbuffer_raster: VolumeBlock,
    gbuffer_blocks: Vec<VolumeBlock>,
    cascade_block: CascadeBlock,
    pub volumes: Vec<VolumeGpu>,
    rsm: Rsm,
    /// Per material: the diffuse transmittance (rgb).
    transmittance: BufferId,
    composite: PipelineId,
    /// The full-screen debug view's pipeline, when one is chosen.
    debug: Option<PipelineId>,
    /// The objects' draws (emitters neither reflect nor receive).
    calls: Vec<DrawCall>,
    objects: Vec<Option<usize>>,
    animation: Vec<Option<crate::scene::Animation>>,
    /// Seconds per unit of each stage's work on this device, measured when it was set up.
    rates: Option<cost::Rates>,
}

impl Lpv {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<Lpv> {
        let config = Config::from_decl(decl, Some(cx.scene))?;
        for w in crate::lighting::params::Params::new(decl, Some(cx.scene)).inert_warnings(&config.inert()) {
            crate::errln!("{w}");
        }
        let lit = lights_of(cx, decl, &config)?;
        let light = lit[0];
        let bounds = scene_bounds(cx)
            .ok_or_else(|| Error::Usage(format!("{}: {NAME}: the scene has no object to light", cx.scene.source)))?;
        let (finest, placements) = place_volumes(cx.scene.camera.position, bounds, &config);
        // The frame's lights are `raster_lights`, one per scene light: each punctual light's slot.
        let raster = crate::gpu_scene::raster_lights(cx.scene);
        let lights: Vec<(GpuLight, usize)> = (lit.iter())
            .map(|l| (*l, raster.iter().position(|r| r == l).unwrap_or(0)))
            .collect();
        let largest = placements[placements.len() - 1];
        let cameras = (lit.iter())
            .map(|l| LightCamera::new(l, &largest, config.rsm, config.snap))
            .collect::<Result<Vec<_>>>()
            .map_err(|e| Error::Usage(format!("{}: {e}", cx.scene.source)))?;
        let blocks = light_blocks(&cameras, &placements, &config);
        let transmittance = transmittance_buffer(cx)?;
        let calls: Vec<DrawCall> = cx
            .scene_gpu
            .draws
            .iter()
            .filter(|d| d.object.is_some())
            .map(DrawCall::whole)
            .collect();
        // Measured on small stand-ins and said before the volumes and maps the configuration
        // sizes are made: at the maxima those alone take longer than the measurement.
        let rates = cost::calibrate(cx, &config, &light, &largest, &calls, transmittance)?;
        if let Some(rates) = &rates {
            cx.warn_cost(NAME, &cost::estimate(&config, rates, lights.len()));
        }
        let volumes = create_volumes(cx, &config, placements.len())?;
        let cascade_block = cascade_block(&placements);
        // The scene's camera until the first frame says where the camera is.
        let eye = cx.scene.camera.position.extend(1.0).into();
        let view_proj = cx.scene.camera.view_projection(1.0).to_cols_array();
        let gbuffer_raster = rsm::gbuffer_block(&blocks[0][0], view_proj, eye, config.gbuffer);
        let gbuffer_blocks = blocks
            .iter()
            .map(|b| rsm::gbuffer_injection_block(&b[0], config.gbuffer))
            .collect();
        let rsm = Rsm::new(cx.gpu, cx.shaders, cx.states, &config, lights.len())?;
        let composite = composite_pipeline(cx, &config)?;
        let debug = debug_pipeline(cx, &config)?;
        let objects: Vec<Option<usize>> = cx.scene_gpu.draws.iter().map(|d| d.object).collect();
        let animation = cx.scene.objects.iter().map(|o| o.animation).collect();
        let lpv = Lpv {
            config,
            placements,
            finest,
            lights,
            cameras,
            blocks,
            gbuffer_raster,
            gbuffer_blocks,
            cascade_block,
            volumes,
            rsm,
            transmittance,
            composite,
            debug,
            calls,
            objects,
            animation,
            rates,
        };
        Ok(lpv)
    }

    /// Seconds per unit of each stage's work, measured when it was set up (`None`: the device
    /// has no timestamps).
    pub fn rates(&self) -> Option<cost::Rates> {
        self.rates
    }

    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The first light's camera.
    pub fn camera(&self) -> &LightCamera {
        &self.cameras[0]
    }

    /// How many lights the volume bounces (an RSM each).
    pub fn light_count(&self) -> usize {
        self.lights.len()
    }

    /// The first light's uniform block of cascade `k` (what its sets store per W/sr among it).
    pub fn block(&self, k: usize) -> &VolumeBlock {
        &self.blocks[k][0]
    }

    /// The RSM, the injection and the propagation: the volume the composite reads
    /// ([`VolumeGpu::result`]).
    pub fn add_volume_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, scene: &'a crate::gpu_scene::SceneGpu) {
        let largest = self.blocks.len() - 1;
        self.rsm
            .add_raster(graph, scene, &self.calls, self.transmittance, &self.blocks[largest]);
        self.rsm
            .add_gbuffer(graph, scene, &self.calls, self.transmittance, &self.gbuffer_raster);
        for ((volume, block), gbuffer) in self.volumes.iter().zip(&self.blocks).zip(&self.gbuffer_blocks) {
            self.rsm.add_injection(graph, volume, block, gbuffer);
            volume.add_propagation(graph, &block[0]);
        }
    }
}

impl Lpv {
    /// A full-screen debug view in place of the frame.
    fn add_debug_view<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>, pipeline: PipelineId) {
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let mip = SubresourceRange::mip(0);
        // The G-buffer's views read its layers and its block (the camera's eye); the others the
        // RSM's and the finest volume's.
        let (map, block) = match (&self.rsm.gbuffer, self.config.view.gbuffer()) {
            (Some(g), true) => (g, &self.gbuffer_raster),
            _ => (&self.rsm.map, &self.blocks[0][0]),
        };
        let layer = match self.config.view {
            config::View::RsmTransmitted => map.layers[1],
            config::View::RsmNormal | config::View::GbufferNormal => map.layers[3],
            config::View::RsmPosition | config::View::GbufferDepth => map.layers[2],
            _ => map.layers[0],
        };
        let (t, s) = (frame.targets, frame.scene.sampler);
        let mut pass = graph
            .pass("lpv debug view")
            .color_attachment(t.radiance, mip, false)
            .sample("rsm_flux", map.layers[0], mip, s, frag);
        // The flux layer is declared once; another layer is declared by its own name.
        let same = layer == map.layers[0];
        if !same {
            pass = pass.sample("rsm_layer", layer, mip, s, frag);
        }
        pass.buffer(
            self.volumes[0].result(),
            Access::StorageRead { stages: frag },
            Some("light"),
        )
        .record(move |ctx| {
            let _ = ctx.rec.begin_rendering(&RenderingDesc {
                colors: vec![RenderTarget::load(t.radiance)],
                depth_stencil: None,
            })?;
            ctx.rec.bind_pipeline(pipeline)?;
            let volume = ("volume", Bind::UniformData(bytemuck::bytes_of(block)));
            if same {
                ctx.bind(&[
                    volume,
                    (
                        "rsm_layer",
                        Bind::Sampled {
                            image: layer,
                            range: mip,
                            sampler: s,
                        },
                    ),
                ])?;
            } else {
                ctx.bind(&[volume])?;
            }
            ctx.rec.draw(3, 1)?;
            ctx.rec.end_rendering();
            Ok(())
        });
    }
}

impl LightingMethod for Lpv {
    fn name(&self) -> &'static str {
        NAME
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        let t = frame.clock.time_s;
        let items = frame.scene.draws.iter().zip(&self.objects).filter(|(_, o)| o.is_some());
        for (call, (item, object)) in self.calls.iter_mut().zip(items) {
            let anim = object.and_then(|o| self.animation.get(o).copied().flatten());
            call.model = anim.map_or(item.model, |a| a.transform_at(item.model, t));
        }
        let moved = match self.finest {
            Some(side) => {
                let eye = Vec3::from_slice(&frame.uniforms.camera_pos[..3]);
                let placements = cascade_placements(eye, side, &self.config);
                let moved = placements != self.placements;
                self.placements = placements;
                moved
            }
            None => false,
        };
        // The frame's lights (the scene's light motion turns them for every method), then the
        // LPV's own `light_spin` about world up.
        let turn = glam::Quat::from_rotation_y((self.config.light_spin * t as f64).to_radians() as f32);
        let lights: Vec<(GpuLight, usize)> = (self.lights.iter())
            .map(|&(last, index)| {
                let mut light = frame.scene.lights.get(index).copied().unwrap_or(last);
                if self.config.light_spin != 0.0 {
                    light.direction = (turn * Vec3::from_slice(&light.direction[..3])).extend(0.0).into();
                }
                (light, index)
            })
            .collect();
        // A light's change of intensity moves every light's shared fixed-point units.
        if lights != self.lights || moved {
            let largest = self.placements[self.placements.len() - 1];
            self.cameras = (lights.iter())
                .map(|(l, _)| LightCamera::new(l, &largest, self.config.rsm, self.config.snap))
                .collect::<Result<Vec<_>>>()?;
            self.lights = lights;
            self.blocks = light_blocks(&self.cameras, &self.placements, &self.config);
            self.cascade_block = cascade_block(&self.placements);
        }
        if self.config.gbuffer > 0 {
            let (view_proj, eye, size) = (frame.uniforms.view_proj, frame.uniforms.camera_pos, self.config.gbuffer);
            self.gbuffer_raster = rsm::gbuffer_block(&self.blocks[0][0], view_proj, eye, size);
            self.gbuffer_blocks = self
                .blocks
                .iter()
                .map(|b| rsm::gbuffer_injection_block(&b[0], size))
                .collect();
        }
        Ok(())
    }

    /// Per volume (each cascade): its three sets of 3 × 4 SH coefficients per cell (the
    /// document's 3 × 8 B × N³ per set in fp16), the fixed-point injection sums and the geometry
    /// volume; then the RSM and the camera's G-buffer.
    fn memory(&self, gpu: &crate::backend::Gpu) -> Result<Vec<crate::lighting::MemoryItem>> {
        let item = |resource: String, requested: u64, allocated: u64| crate::lighting::MemoryItem {
            method: NAME,
            resource,
            requested,
            allocated,
        };
        let mut out = Vec::new();
        for v in &self.volumes {
            for (name, requested, allocated) in v.memory(gpu)? {
                out.push(item(name, requested, allocated));
            }
        }
        for (k, map) in self.rsm.maps().enumerate() {
            let (requested, allocated) = map.memory(gpu)?;
            let which = if k == 0 { String::new() } else { format!(" {k}") };
            out.push(item(
                format!("{NAME} rsm{which} ({0}x{0}, 4 x RGBA32F + depth)", map.size),
                requested,
                allocated,
            ));
        }
        if let Some(c) = &self.rsm.gbuffer {
            let (requested, allocated) = c.memory(gpu)?;
            out.push(item(
                format!("{NAME} gbuffer ({0}x{0}, 4 x RGBA32F + depth)", c.size),
                requested,
                allocated,
            ));
        }
        Ok(out)
    }

    fn frame_cost(&self) -> Option<crate::lighting::FrameCost> {
        Some(cost::estimate(&self.config, &self.rates?, self.lights.len()))
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        if !frame.terms.has(Term::Indirect) {
            return Ok(());
        }
        let scene = frame.scene;
        self.add_volume_passes(graph, scene);
        if let Some(pipeline) = self.debug {
            self.add_debug_view(graph, frame, pipeline);
            return Ok(());
        }
        let (t, uniforms) = (frame.targets, frame.uniforms);
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        const NAMES: [&str; 4] = ["light0", "light1", "light2", "light3"];
        let mut pass = graph
            .pass("lpv composite")
            .color_attachment(t.radiance, SubresourceRange::mip(0), false)
            .depth_stencil_read(t.depth_stencil)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .buffer(
                self.transmittance,
                Access::StorageRead { stages: frag },
                Some("transmittance"),
            )
            .sample(
                "rsm_position",
                self.rsm.map.layers[2],
                SubresourceRange::mip(0),
                scene.sampler,
                frag,
            );
        for (volume, name) in self.volumes.iter().zip(NAMES) {
            pass = pass.buffer(volume.result(), Access::StorageRead { stages: frag }, Some(name));
        }
        // Unused cascade slots read the finest volume.
        let spare = self.volumes[0].result();
        let used = self.volumes.len();
        pass.record(move |ctx| {
            let depth = RenderTarget {
                read_only: true,
                ..RenderTarget::load(t.depth_stencil)
            };
            let _ = ctx.rec.begin_rendering(&RenderingDesc {
                colors: vec![RenderTarget::load(t.radiance)],
                depth_stencil: Some(depth),
            })?;
            ctx.rec.bind_pipeline(self.composite)?;
            let uniform_bytes = bytemuck::bytes_of(&uniforms);
            let (s, whole) = (scene.sampler, SubresourceRange::mip(0));
            record_draws(ctx, scene, &self.calls, |ctx, material| {
                let maps = scene.material_maps[material as usize];
                let mut binds = vec![
                    ("frame", Bind::UniformData(uniform_bytes)),
                    ("volume", Bind::UniformData(bytemuck::bytes_of(&self.blocks[0][0]))),
                    ("cascades", Bind::UniformData(bytemuck::bytes_of(&self.cascade_block))),
                    (
                        "albedo_map",
                        Bind::Sampled {
                            image: maps.albedo,
                            range: whole,
                            sampler: s,
                        },
                    ),
                    (
                        "normal_map",
                        Bind::Sampled {
                            image: maps.normal,
                            range: whole,
                            sampler: s,
                        },
                    ),
                ];
                binds.extend(NAMES[used..].iter().map(|&n| (n, Bind::StorageBuffer(spare))));
                ctx.bind(&binds)
            })?;
            ctx.rec.end_rendering();
            Ok(())
        });
        Ok(())
    }
}
