//! Radiosity light-maps (the Ca3D-Engine thesis §3, CaLight; digest §1.2) on the light-map substrate
//! ([`crate::lighting::lightmap`]: patches, the surface-visibility matrix, form factors, the shooting loop,
//! border passes, tone reproduction): direct light and the sun ([`bake`], `sun`), and the
//! shooting on the CPU or the GPU ([`gpu`]); faithful to CaLight or corrected (exact form factors,
//! energy that closes, radiometric light-maps).
//!
//! The method supplies the base term: the scene's static triangles drawn as emission + albedo ×
//! light-map ([`bake`] bakes it through the bake stage's cache), entities with their emission
//! only. Bounces reflect each material's albedo times its albedo map's mean, not the map texel by
//! texel.

pub(crate) mod environment_light;
pub mod gpu;
pub(crate) mod sun;

#[cfg(test)]
mod tests;

pub mod bake;

use crate::backend::{
    vk, ColorTarget, ImageDesc, ImageId, PipelineId, SamplerDesc, SamplerId, SpecConstant, SubresourceRange,
};
use crate::bake::BakeKey;
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph};
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::lighting::lightmap::solve::{Mode, Settings};
use crate::lighting::plan::{Derived, Facts};
use crate::lighting::{CreateContext, FrameContext, LightingMethod, Term, RADIANCE_FORMAT};
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema, Scene};
use bake::Content;

pub const NAME: &str = "radiosity";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "patch_size",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "block",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "threshold",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "light",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "baker",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "full_visibility",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "ambient_nz",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "reflectivity",
            kind: ParamKind::Float,
        },
    ],
};

/// Bumped whenever the CPU baker's output for the same inputs changes (the GPU shooter's SPIR-V is
/// hashed into the key).
const BAKER_VERSION: u32 = 16;

/// The method's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    pub settings: Settings,
    /// Patch (light-map texel) size, metres.
    pub patch_size: f64,
    pub content: Content,
    /// Multiply the light-map by the normal map's N_z when drawing (the Ca3D-Engine thesis's ambient term).
    pub ambient_nz: bool,
    /// Where to shoot: `None` (auto) picks the GPU unless the device is a CPU implementation
    /// (lavapipe), which runs the compute passes slower than the native solve on the same cores.
    pub on_gpu: Option<bool>,
}

impl Config {
    /// The parameters of `decl`; a bad value is one line naming the parameter (and the scene
    /// file and line, given the scene).
    pub fn from_decl(decl: &MethodDecl) -> Result<Config> {
        Config::from_decl_in(decl, None)
    }

    pub fn from_decl_in(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = crate::lighting::params::Params::new(decl, scene);
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        let mut c = Config {
            settings: Settings::default(),
            patch_size: 0.1,
            content: Content::All,
            ambient_nz: false,
            on_gpu: None,
        };
        if let Some(mode) =
            params.get_choice("mode", &[("faithful", Mode::Faithful), ("corrected", Mode::Corrected)])?
        {
            c.settings.mode = mode;
        }
        if c.settings.mode == Mode::Corrected {
            c.settings.threshold = crate::lighting::lightmap::solve::CORRECTED_THRESHOLD;
        }
        if let Some(v) = decl.param("patch_size") {
            c.patch_size = v
                .as_float()
                .or(v.as_integer().map(|i| i as f64))
                .filter(|x| x.is_finite() && *x > 0.0)
                .ok_or_else(|| bad("patch_size", "a size in metres above 0", v))?;
        }
        if let Some(v) = decl.param("block") {
            c.settings.block = v
                .as_integer()
                .filter(|b| (1..=16).contains(b))
                .ok_or_else(|| bad("block", "an integer from 1 to 16", v))? as usize;
        }
        if let Some(v) = decl.param("threshold") {
            c.settings.threshold = v
                .as_float()
                .or(v.as_integer().map(|i| i as f64))
                .filter(|x| *x > 0.0 && *x < 1.0)
                .ok_or_else(|| bad("threshold", "a fraction in (0, 1)", v))?;
        }
        if let Some(v) = decl.param("full_visibility") {
            c.settings.full_visibility = v.as_bool().ok_or_else(|| bad("full_visibility", "true or false", v))?;
        }
        if let Some(v) = decl.param("light") {
            c.content = match v.as_str() {
                Some("all") => Content::All,
                Some("bounces") => Content::Bounces,
                _ => return Err(bad("light", "\"all\" or \"bounces\"", v)),
            };
        }
        if let Some(v) = decl.param("reflectivity") {
            c.settings.reflectivity = Some(
                v.as_float()
                    .or(v.as_integer().map(|i| i as f64))
                    .filter(|r| *r > 0.0 && *r < 1.0)
                    .ok_or_else(|| {
                        bad(
                            "reflectivity",
                            "one reflectivity in (0, 1) for every surface, such as CaLight's 0.3",
                            v,
                        )
                    })?,
            );
        }
        if let Some(v) = decl.param("ambient_nz") {
            c.ambient_nz = v.as_bool().ok_or_else(|| bad("ambient_nz", "true or false", v))?;
        }
        if let Some(v) = decl.param("baker") {
            c.on_gpu = match v.as_str() {
                Some("auto") => None,
                Some("gpu") => Some(true),
                Some("cpu") => Some(false),
                _ => return Err(bad("baker", "\"auto\", \"gpu\" or \"cpu\"", v)),
            };
        }
        Ok(c)
    }
}

/// What the light-map models: every bounce (to 16, where the solve has converged), or only
/// light that bounced. (Its emitters are drawn either way, which an indirect reference lacks.)
pub fn reference(decl: &MethodDecl) -> crate::lighting::ReferenceKind {
    match Config::from_decl(decl).map(|c| c.content) {
        Ok(Content::Bounces) => crate::lighting::ReferenceKind::Indirect(16),
        _ => crate::lighting::ReferenceKind::Bounces(16),
    }
}

/// The chart's sweep: patch sizes around the declared one (twice, once and half), a looser stop,
/// and the faithful mode.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d) {
            let label = format!(
                "radiosity {:?} patch={} block={} threshold={}",
                c.settings.mode, c.patch_size, c.settings.block, c.settings.threshold
            )
            .to_lowercase();
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    let declared = Config::from_decl(decl).map(|c| c.patch_size).unwrap_or(0.1);
    for s in [2.0 * declared, declared, 0.5 * declared] {
        push(decl.with("patch_size", s.into()));
    }
    push(decl.with("threshold", 1e-2.into()));
    push(decl.with("mode", "faithful".into()));
    out
}

/// The patches a light-map gets when the scene sets no `patch_size`: the solve's time grows with
/// the patch count times the shots, so the count, not the scene's size, is what is budgeted.
pub const PATCH_BUDGET: f64 = 4096.0;

/// Bytes the bake holds per patch: the patch, its direct light and final value, its texel, and
/// the solve's per-patch area and receiver index.
const BYTES_PER_PATCH: u64 =
    (std::mem::size_of::<crate::lighting::lightmap::patches::Patch>() + 2 * 24 + 16 + 16) as u64;

/// `patch_size` from the scene's area and [`PATCH_BUDGET`] when unset; the bake refused when its
/// patches would not fit the memory budget.
pub fn plan(decl: &MethodDecl, facts: &Facts<'_>) -> Result<Vec<Derived>> {
    let config = Config::from_decl_in(decl, Some(facts.scene))?;
    let mut derived = Vec::new();
    let mut size = config.patch_size;
    let area = facts.area(NAME)?;
    if decl.param("patch_size").is_none() && area > 0.0 {
        let (derived_size, why) = crate::lighting::plan::lightmap_patch_size(facts.triangles(NAME)?, PATCH_BUDGET);
        size = derived_size;
        derived.push(Derived::new("patch_size", size, why));
    }
    let patches = crate::lighting::lightmap::patches::count(facts.triangles(NAME)?, size);
    facts.check(
        NAME,
        &format!("the light-map at patch_size = {size} ({patches} patches)"),
        patches * BYTES_PER_PATCH,
        "set a larger patch_size",
    )?;
    Ok(derived)
}

/// The light-map's texture format: CaLight's 8-bit display values in faithful mode (the bake
/// quantizes them, so the bytes are exact), linear radiometric floats in corrected mode.
pub fn lightmap_format(mode: Mode) -> vk::Format {
    match mode {
        Mode::Faithful => vk::Format::R8G8B8A8_UNORM,
        Mode::Corrected => vk::Format::R32G32B32A32_SFLOAT,
    }
}

/// The light-map base term: the scene's static triangles drawn with emission + albedo ×
/// light-map.
pub struct Radiosity {
    pipeline: PipelineId,
    mesh: crate::lighting::lightmap::mesh::Mesh,
    lightmap: ImageId,
    sampler: SamplerId,
}

impl Radiosity {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<Radiosity> {
        let config = Config::from_decl_in(decl, Some(cx.scene))?;
        let mut geometry = crate::lighting::lightmap::geometry::static_geometry(cx.scene, cx.scene_gpu, NAME)?;
        if let Some(w) = crate::lighting::lightmap::geometry::behind_warning(cx.scene, &geometry.triangles, NAME) {
            crate::errln!("{w}");
        }
        // The document's light-maps let texels straddle thin walls; the corrected mode cuts there.
        let uncut = (config.settings.mode == Mode::Corrected)
            .then(|| crate::lighting::lightmap::cut::cut_copy(&mut geometry, config.patch_size))
            .flatten();
        if geometry.triangles.is_empty() {
            return Err(Error::Usage(format!(
                "{}: {NAME}: the scene has no static geometry to light-map",
                cx.scene.source
            )));
        }
        let baked = bake_lightmap(cx, &config, &geometry)?;
        let (w, h) = (
            baked.first().copied().unwrap_or(0.0) as u32,
            baked.get(1).copied().unwrap_or(0.0) as u32,
        );
        let texel_floats = 4 * (w as usize) * (h as usize);
        if w == 0 || h == 0 || baked.len() != 2 + texel_floats + 6 * geometry.triangles.len() {
            return Err(Error::Internal(format!(
                "{}: {NAME}: the baked light-map does not match the scene ({} values)",
                cx.scene.source,
                baked.len()
            )));
        }
        let texels = &baked[2..2 + texel_floats];
        let mesh = crate::lighting::lightmap::mesh::Mesh::new(
            cx,
            &geometry,
            &baked[2 + texel_floats..],
            NAME,
            uncut.as_ref(),
        )?;
        let format = lightmap_format(config.settings.mode);
        let lightmap = upload_lightmap(cx, format, (w, h), texels)?;
        let pipeline = create_pipeline(cx, &config)?;
        let sampler = cx.gpu.sampler(SamplerDesc::LINEAR_CLAMP)?;
        Ok(Radiosity {
            pipeline,
            mesh,
            lightmap,
            sampler,
        })
    }
}

/// The light-map baked (or read from the cache): the atlas size, its texels, and each triangle
/// corner's light-map coordinate, in one list.
fn bake_lightmap(cx: &mut CreateContext<'_>, config: &Config, geometry: &StaticGeometry) -> Result<Vec<f32>> {
    let mut key = BakeKey::new("radiosity light-map")
        .with("version", BAKER_VERSION)
        .with(
            "config",
            Config {
                ambient_nz: false,
                ..*config
            },
        )
        .with("lights", &cx.scene.lights)
        .with_shaders("radiosity/");
    let geometry_bytes: Vec<f64> = geometry
        .triangles
        .iter()
        .flat_map(|t| {
            t.p.iter()
                .flat_map(|p| p.to_array())
                .chain(t.albedo.to_array())
                .chain(t.emission.to_array())
                .chain([t.object as f64, f64::from(u8::from(t.sky)), t.part as f64])
        })
        .collect();
    key = key.with_bytes("geometry", bytemuck::cast_slice(&geometry_bytes));
    let scene = cx.scene;
    let geo = geometry;
    let (gpu, shaders) = (&mut *cx.gpu, cx.shaders);
    // Baked: the atlas size, its texels, and each triangle corner's light-map coordinate.
    let baked: Vec<f32> = cx.bakes.bake(
        &format!("{NAME} light-map patch={}", config.patch_size),
        &key,
        |progress| {
            let on_gpu = config
                .on_gpu
                .unwrap_or(gpu.caps().device_type != vk::PhysicalDeviceType::CPU);
            let shooter = if on_gpu {
                bake::Shooter::Gpu(gpu, shaders)
            } else {
                bake::Shooter::Cpu
            };
            let (patches, atlas, texels, _report) = bake::bake(
                geo,
                scene,
                config.patch_size,
                &config.settings,
                config.content,
                shooter,
                progress,
            )?;
            let mut out = vec![atlas.width as f32, atlas.height as f32];
            out.extend(texels.iter().flatten());
            let uv = crate::lighting::lightmap::atlas::triangle_uvs(&geo.triangles, &patches, &atlas);
            out.extend(uv.iter().flatten());
            Ok(out)
        },
    )?;
    Ok(baked)
}

/// The light-map's texels as a sampled image of `format`.
fn upload_lightmap(
    cx: &mut CreateContext<'_>,
    format: vk::Format,
    (w, h): (u32, u32),
    texels: &[f32],
) -> Result<ImageId> {
    let lightmap = cx.gpu.create_image(
        &ImageDesc::new_2d("radiosity light-map", format, w, h)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    match format {
        vk::Format::R8G8B8A8_UNORM => {
            cx.gpu
                .upload_image(lightmap, 0, &crate::lighting::lightmap::atlas::to_rgb8(texels))?
        }
        _ => cx.gpu.upload_image(lightmap, 0, bytemuck::cast_slice(texels))?,
    }
    cx.states.set_image(
        cx.gpu,
        lightmap,
        Access::SampledRead {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
        },
    )?;
    Ok(lightmap)
}

/// The light-mapped surfaces' pipeline.
fn create_pipeline(cx: &mut CreateContext<'_>, config: &Config) -> Result<PipelineId> {
    let mut desc =
        crate::lighting::lightmap::mesh::Mesh::pipeline_desc(&format!("{NAME} light-map"), "radiosity/lightmap.frag");
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
    desc.depth_format = Some(cx.gpu.caps().depth_stencil_format);
    desc.specialization = vec![SpecConstant {
        id: 0,
        bits: u32::from(config.ambient_nz),
    }];
    let pipeline = cx.gpu.create_graphics_pipeline(&desc, cx.shaders)?;
    Ok(pipeline)
}

impl LightingMethod for Radiosity {
    fn name(&self) -> &'static str {
        NAME
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        if !frame.terms.has(Term::Base) {
            return Ok(());
        }
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let pass =
            graph
                .pass("light-map")
                .sample("lightmap", self.lightmap, SubresourceRange::mip(0), self.sampler, frag);
        self.mesh.draw(pass, frame, self.pipeline, Vec::new());
        self.mesh.add_depth_pass(graph, frame);
        Ok(())
    }
}
