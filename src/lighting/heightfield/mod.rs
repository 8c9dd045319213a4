//! Soft shadows on dynamic height fields from an environment and spherical local lights (seed
//! 001, extending Snyder & Nowrouzezahrai 2008; digest the notes on the source document).
//!
//! Per height-field texel and per frame, all as compute passes (each with its own timestamp):
//! 1. **height update** — the scene's generator (or height image) at this frame's time;
//! 2. **pyramid** — decimation by s_r = 2^(1/ls) per level and cubic B-spline reconstruction of
//!    every level to full resolution ([`pyramid`]); the brute-force method instead finds the
//!    field's height bounds;
//! 3. **environment SH** — the environment in SH: a constant exactly (c_00 alone), an
//!    equirectangular map through the SH core's projection pass ([`crate::sh::ShProjector`]:
//!    exact texel solid angles, workgroup partial sums, then a reduction dispatch);
//! 4. **environment** — horizons in nφ directions (one sample per level at d_i = s_r^i texels,
//!    level offset lo, B-spline maximum, clamped at 0), hemisphere wedge-table lookups, z-rotation
//!    and sum into the SH visibility V, T = V • C with the clamped cosine about the normal, L · T;
//! 5. **one pass per sphere light** — horizons truncated at the light's planar distance and
//!    signed, the full-sphere table, the light as a cap ZH (half-angle asin(r/d)) rotated toward it;
//! 6. **accumulation** — environment plus lights, clamped at 0;
//!
//! then the displaced mesh is drawn with that shading image times the albedo (the material's
//! colour times its albedo map at the mesh uv). Two methods share this code:
//! `heightfield_pyramid` (the thesis) and `heightfield_bruteforce` (horizons ray-marched on the
//! bilinear field, exact up to the march step, for error and speed comparison).
//!
//! Scope: the method draws the scene's first height field and, with their emission only, every
//! other object (so sphere-light emitters look as in the reference); other objects neither cast
//! shadows on the field nor are lit. Lights must be spheres; the environment constant or an
//! equirectangular image (clear colour: the constant, black for images). Diffuse only: the
//! material's specular colour and map are ignored; a normal map is refused (the transfer uses the
//! field's own normals).

pub mod cpu;
pub(crate) mod gpu;
pub mod measure;
pub mod pyramid;
pub mod settings;
pub mod standalone;
pub mod wedge;

use crate::backend::{
    vk, Bind, ColorTarget, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc, SubresourceRange,
};
use crate::error::Result;
use crate::gpu_scene::{record_draws, vertex_layout, DrawCall};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{CreateContext, FrameContext, LightingMethod, RADIANCE_FORMAT};
use crate::scene::{MethodDecl, MethodSchema};
pub use gpu::{FieldInputs, HeightfieldGpu, SphereLight};
pub use settings::{Decimation, Horizon, Mode, Settings, Window};

pub const PYRAMID: &str = "heightfield_pyramid";
pub const BRUTE_FORCE: &str = "heightfield_bruteforce";

pub const PYRAMID_SCHEMA: MethodSchema = MethodSchema {
    name: PYRAMID,
    params: settings::PYRAMID_PARAMS,
};
pub const BRUTE_FORCE_SCHEMA: MethodSchema = MethodSchema {
    name: BRUTE_FORCE,
    params: settings::BRUTE_PARAMS,
};

fn push_unique(out: &mut Vec<(String, MethodDecl)>, decl: MethodDecl, horizon: Horizon) {
    let Ok(s) = Settings::from_decl(&decl, horizon) else {
        return;
    };
    let prefix = match horizon {
        Horizon::Pyramid => "pyramid",
        Horizon::BruteForce => "brute",
    };
    let label = format!("{prefix} {}", s.label());
    if !out.iter().any(|(l, _)| *l == label) {
        out.push((label, decl));
    }
}

/// The pyramid's sweep, one parameter at a time from the scene's declaration: nφ ∈ {4, 8, 16,
/// 32}, ls ∈ {1, 2, 3, 4}, lo ∈ {0, 2, 4}, bands ∈ {2, 3, 4, 6}, the faithful and corrected
/// modes (issue: chart sweep; thesis Tables 6.1–6.2 and Fig. 6.1–6.2), and a Hanning window on
/// the transfer (not in the thesis: the digest's remedy for ringing).
pub fn pyramid_sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out = Vec::new();
    push_unique(&mut out, decl.clone(), Horizon::Pyramid);
    for n in [4i64, 8, 16, 32] {
        push_unique(&mut out, decl.with("nphi", n.into()), Horizon::Pyramid);
    }
    for ls in [1i64, 2, 3, 4] {
        push_unique(&mut out, decl.with("ls", ls.into()), Horizon::Pyramid);
    }
    for lo in [0.0f64, 2.0, 4.0] {
        push_unique(&mut out, decl.with("lo", lo.into()), Horizon::Pyramid);
    }
    for b in [2i64, 3, 4, 6] {
        push_unique(&mut out, decl.with("bands", b.into()), Horizon::Pyramid);
    }
    for m in ["faithful", "corrected"] {
        push_unique(&mut out, decl.with("mode", m.into()), Horizon::Pyramid);
    }
    push_unique(&mut out, decl.with("window", "hanning".into()), Horizon::Pyramid);
    out
}

/// The brute force's sweep: march steps {2, 1, 0.5, 0.25} texels and nφ ∈ {8, 16, 32}, both
/// modes.
pub fn brute_sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out = Vec::new();
    push_unique(&mut out, decl.clone(), Horizon::BruteForce);
    for step in [2.0f64, 1.0, 0.5, 0.25] {
        push_unique(&mut out, decl.with("march_step", step.into()), Horizon::BruteForce);
    }
    for n in [8i64, 16, 32] {
        push_unique(&mut out, decl.with("nphi", n.into()), Horizon::BruteForce);
    }
    for m in ["faithful", "corrected"] {
        push_unique(&mut out, decl.with("mode", m.into()), Horizon::BruteForce);
    }
    out
}

/// One of the two height-field methods in a scene.
pub struct HeightfieldMethod {
    name: &'static str,
    pub core: HeightfieldGpu,
    terrain: PipelineId,
    emitter: PipelineId,
    /// This frame's animation time: the renderer's frame × time_step (frame 0 is time 0, the
    /// shape the reference traces).
    time: f32,
    /// Scene draws other than the height field (drawn with their emission only).
    others: Vec<usize>,
}

impl HeightfieldMethod {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<Self> {
        let (gpu, shaders) = (&mut *cx.gpu, cx.shaders);
        let (name, horizon) = if decl.name == BRUTE_FORCE {
            (BRUTE_FORCE, Horizon::BruteForce)
        } else {
            (PYRAMID, Horizon::Pyramid)
        };
        let settings = Settings::from_scene_decl(decl, horizon, cx.scene)?;
        let inputs = FieldInputs::from_scene(cx.scene, cx.environment, name)?;
        let object = inputs.object;
        let core = HeightfieldGpu::new(gpu, shaders, cx.states, cx.bakes, settings, inputs)?;
        if let Some(warning) = slow_warning(core.res, gpu.caps().device_type, &gpu.caps().name) {
            crate::errln!("{}: {name}: {warning}", cx.scene.source);
        }
        let mut desc = GraphicsPipelineDesc::new(
            "hf terrain",
            "heightfield/terrain.vert",
            Some("heightfield/terrain.frag"),
        );
        desc.raster.cull = vk::CullModeFlags::NONE;
        desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        desc.depth_format = Some(gpu.caps().depth_stencil_format);
        let terrain = gpu.create_graphics_pipeline(&desc, shaders)?;
        let mut desc = GraphicsPipelineDesc::new(
            "hf emitters",
            "heightfield/emitter.vert",
            Some("heightfield/emitter.frag"),
        );
        desc.vertex_layout = vertex_layout();
        desc.raster.cull = vk::CullModeFlags::NONE;
        desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        desc.depth_format = Some(gpu.caps().depth_stencil_format);
        let emitter = gpu.create_graphics_pipeline(&desc, shaders)?;
        let others = cx
            .scene_gpu
            .draws
            .iter()
            .enumerate()
            .filter(|(_, d)| d.object != Some(object))
            .map(|(i, _)| i)
            .collect();
        Ok(HeightfieldMethod {
            name,
            core,
            terrain,
            emitter,
            time: 0.0,
            others,
        })
    }
}

/// What to say before a frame that will be slow: the passes' work grows as resolution² (and
/// their loops as the resolution), so on a CPU implementation of Vulkan a large field takes
/// minutes per frame (1024 took 167 s for one 64×36 frame on llvmpipe).
pub fn slow_warning(resolution: u32, device_type: vk::PhysicalDeviceType, device: &str) -> Option<String> {
    (device_type == vk::PhysicalDeviceType::CPU && resolution >= 512).then(|| {
        format!("resolution {resolution} on {device}, a CPU implementation, is slow: 1024 measured 167 s for one 64×36 frame, and each halving divides the work by about 4 (e.g. resolution = 256)")
    })
}

/// `Terrain` push constants of `terrain.vert`/`terrain.frag`.
fn terrain_push(core: &HeightfieldGpu) -> [u8; 48] {
    let mut out = [0u8; 48];
    let v: [f32; 12] = [
        core.origin.x,
        core.origin.y,
        core.spacing,
        core.res as f32,
        core.inputs.albedo.x,
        core.inputs.albedo.y,
        core.inputs.albedo.z,
        core.inputs.translation.y,
        core.inputs.emission.x,
        core.inputs.emission.y,
        core.inputs.emission.z,
        0.0,
    ];
    out.copy_from_slice(bytemuck::cast_slice(&v));
    out
}

impl LightingMethod for HeightfieldMethod {
    fn name(&self) -> &'static str {
        self.name
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        self.time = frame.clock.frame as f32 * self.core.settings.time_step;
        Ok(())
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        let core = &self.core;
        core.add_compute_passes(graph, self.time)?;
        let targets = frame.targets;
        let uniforms = frame.uniforms;
        let push = terrain_push(core);
        let vertices = core.res.saturating_sub(1).pow(2) * 6;
        let terrain = self.terrain;
        // The material's maps as the forward method binds them (uploaded once, never written).
        let scene = frame.scene;
        let albedo_map = scene
            .material_maps
            .get(core.inputs.material)
            .map(|m| m.albedo)
            .ok_or_else(|| {
                crate::error::Error::Internal(format!("{}: the height field's material has no GPU maps", self.name))
            })?;
        let map_sampler = scene.sampler;
        graph
            .pass("hf raster")
            .color_attachment(targets.radiance, SubresourceRange::mip(0), false)
            .depth_stencil_write(targets.depth_stencil, false)
            .sample(
                "heights",
                core.heights,
                SubresourceRange::mip(0),
                core.nearest,
                vk::PipelineStageFlags2::VERTEX_SHADER,
            )
            .sample(
                "shading",
                core.shading,
                SubresourceRange::mip(0),
                core.linear,
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
            )
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::load(targets.radiance)],
                    depth_stencil: Some(RenderTarget::load(targets.depth_stencil)),
                })?;
                ctx.rec.bind_pipeline(terrain)?;
                ctx.bind(&[
                    ("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms))),
                    (
                        "albedo_map",
                        Bind::Sampled {
                            image: albedo_map,
                            range: SubresourceRange::mip(0),
                            sampler: map_sampler,
                        },
                    ),
                ])?;
                ctx.rec.push_constants(&push)?;
                ctx.rec.draw(vertices, 1)?;
                ctx.rec.end_rendering();
                Ok(())
            });
        if !self.others.is_empty() {
            let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
            let emitter = self.emitter;
            let others = &self.others;
            graph
                .pass("hf emitters")
                .color_attachment(targets.radiance, SubresourceRange::mip(0), false)
                .depth_stencil_write(targets.depth_stencil, false)
                .buffer(scene.vertices, Access::VertexRead, None)
                .buffer(scene.indices, Access::IndexRead, None)
                .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
                .record(move |ctx| {
                    let _extent = ctx.rec.begin_rendering(&RenderingDesc {
                        colors: vec![RenderTarget::load(targets.radiance)],
                        depth_stencil: Some(RenderTarget::load(targets.depth_stencil)),
                    })?;
                    ctx.rec.bind_pipeline(emitter)?;
                    ctx.bind(&[("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms)))])?;
                    let calls: Vec<DrawCall> = others
                        .iter()
                        .filter_map(|&i| scene.draws.get(i))
                        .map(DrawCall::whole)
                        .collect();
                    record_draws(ctx, scene, &calls, |_, _| Ok(()))?;
                    ctx.rec.end_rendering();
                    Ok(())
                });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::environment::EnvironmentMap;
    use crate::scene::Scene;

    fn scene(extra: &str) -> Scene {
        let text = format!("methods = [\"heightfield_pyramid\"]\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"heightfield\"\ngenerator = \"flat\"\n{extra}\n");
        Scene::from_str(&text, "t.toml", std::path::Path::new(".")).unwrap()
    }

    #[test]
    fn large_fields_on_a_cpu_device_are_announced_as_slow() {
        let cpu = vk::PhysicalDeviceType::CPU;
        assert!(slow_warning(256, cpu, "llvmpipe").is_none());
        let w = slow_warning(512, cpu, "llvmpipe").expect("a warning");
        assert!(w.contains("resolution 512 on llvmpipe") && w.contains("167 s"), "{w}");
        assert!(slow_warning(1024, vk::PhysicalDeviceType::DISCRETE_GPU, "H200").is_none());
    }

    #[test]
    fn inputs_need_sphere_lights_and_a_translated_field() {
        let ok = scene(
            "translate = [1, 0, 2]\n[[lights]]\ntype = \"sphere\"\ncenter = [0, 1, 0]\nradius = 0.1\nradiance = 2",
        );
        let inputs = FieldInputs::from_scene(&ok, &EnvironmentMap::of_scene(&ok).unwrap(), PYRAMID).unwrap();
        assert_eq!(inputs.lights.len(), 1);
        assert_eq!(inputs.translation, glam::Vec3::new(1.0, 0.0, 2.0));
        let point = scene("[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 1");
        let e = FieldInputs::from_scene(&point, &EnvironmentMap::of_scene(&point).unwrap(), PYRAMID)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("t.toml: lights[0] (\"lights[0]\"): heightfield_pyramid lights with sphere lights and the environment only, not a point light"), "{e}");
        let rotated = scene("rotate_deg = [0, 30, 0]");
        let e = FieldInputs::from_scene(&rotated, &EnvironmentMap::of_scene(&rotated).unwrap(), PYRAMID)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("objects[0]") && e.contains("translate only"), "{e}");
    }

    #[test]
    fn settings_ranges_and_sweeps() {
        let decl = |params: &[(&str, toml::Value)]| MethodDecl {
            name: PYRAMID.into(),
            line: 3,
            params: params.iter().map(|(k, v)| (k.to_string(), v.clone(), 3)).collect(),
        };
        let s = Settings::from_decl(
            &decl(&[("nphi", 16.into()), ("lo", 2.5.into()), ("mode", "faithful".into())]),
            Horizon::Pyramid,
        )
        .unwrap();
        assert_eq!((s.nphi, s.lo, s.mode), (16, 2.5, Mode::Faithful));
        let e = Settings::from_decl(&decl(&[("bands", 9.into())]), Horizon::Pyramid)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("heightfield_pyramid.bands: expected an integer from 1 to 6, got 9"),
            "{e}"
        );
        let e = Settings::from_decl(&decl(&[("resolution", 300.into())]), Horizon::Pyramid)
            .unwrap_err()
            .to_string();
        assert!(e.contains("resolution: expected a power of two"), "{e}");
        let sweep: Vec<String> = pyramid_sweep(&decl(&[])).into_iter().map(|(l, _)| l).collect();
        for want in [
            "pyramid nphi=4 ls=4 lo=4 bands=4 corrected",
            "pyramid nphi=32 ls=1 lo=4 bands=4 corrected",
            "pyramid nphi=32 ls=4 lo=0 bands=4 corrected",
            "pyramid nphi=32 ls=4 lo=4 bands=2 corrected",
            "pyramid nphi=32 ls=4 lo=4 bands=4 faithful",
        ] {
            assert!(sweep.iter().any(|l| l == want), "{want} missing from {sweep:?}");
        }
        assert!(
            sweep
                .iter()
                .any(|l| l == "pyramid nphi=32 ls=4 lo=4 bands=4 corrected hanning=5"),
            "{sweep:?}"
        );
        assert_eq!(sweep.len(), 14, "{sweep:?}");
        let w = Settings::from_decl(
            &decl(&[("window", "lanczos".into()), ("window_width", 3.0.into())]),
            Horizon::Pyramid,
        )
        .unwrap();
        assert_eq!(w.window, Window::Lanczos(3.0));
        assert_eq!(w.window_factors()[0], 1.0);
        assert_eq!(Settings::default().window_factors(), vec![1.0; 4]);
        let e = Settings::from_decl(&decl(&[("window_width", 3.0.into())]), Horizon::Pyramid)
            .unwrap_err()
            .to_string();
        assert!(e.contains("heightfield_pyramid.window_width: needs window"), "{e}");
        let e = Settings::from_decl(&decl(&[("window", "box".into())]), Horizon::Pyramid)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("heightfield_pyramid.window: expected one of \"none\", \"hanning\", \"lanczos\""),
            "{e}"
        );
        let brute: Vec<String> = brute_sweep(&MethodDecl {
            name: BRUTE_FORCE.into(),
            line: 0,
            params: vec![],
        })
        .into_iter()
        .map(|(l, _)| l)
        .collect();
        assert!(
            brute.contains(&"brute nphi=32 step=2 bands=4 corrected".to_string()),
            "{brute:?}"
        );
    }
}
