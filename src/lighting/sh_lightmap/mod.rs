//! SH light-maps (the Ca3D-Engine thesis §5, CaSHL; digest §1.5–1.8): per light-map texel, the SH coefficients
//! of its transfer function (shadowed diffuse plus interreflections), so that a distant light of
//! any shape (sky, sun, an environment image) moves at run time for one dot product per texel.
//!
//! The bake ([`transfer`]) runs on the radiosity method's patches, visibility matrix, shooting
//! loop and border passes; it goes through the bake stage's cache. The coefficients are stored
//! natively (⌈n²/4⌉ layers: the seed's range-encoded RGBA8, or half/single floats) or compressed
//! by vector quantisation ([`vq`], [`storage`]: 16-bit indices and the seed's 256-row table),
//! drawn by glsl/sh_lightmap/ with the band count as a specialisation constant. The light
//! ([`light`]) is projected every frame.

pub mod config;
mod estimate;
pub mod gpu;
pub mod light;
pub mod measure;
pub mod normals;
pub mod samples;
pub mod storage;
pub mod transfer;
pub mod vq;

#[cfg(test)]
mod tests;

use crate::backend::{
    vk, BufferId, ColorTarget, ImageDesc, ImageId, PipelineId, SamplerDesc, SamplerId, SpecConstant, SubresourceRange,
};
use crate::bake::BakeKey;
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph};
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::{Mode, Occluders};
use crate::lighting::{CreateContext, FrameContext, LightingMethod, ReferenceKind, Term, RADIANCE_FORMAT};
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema, Scene};
use crate::util::progress::Progress;
use config::{Config, Storage, View};
use normals::{NormalImage, Surfaces};
use samples::SampleSet;

pub const NAME: &str = "sh_lightmap";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "bands",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "samples",
            kind: ParamKind::Int,
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
            name: "bounces",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "tone",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "reps",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "filter",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "storage",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "normal_samples",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "sun_speed",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "sky",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "cie_zenith",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "view",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "baker",
            kind: ParamKind::String,
        },
    ],
};

/// Bumped whenever the baker's output for the same inputs changes.
const BAKER_VERSION: u32 = 7;

/// The reference: every bounce when the transfer bounces, direct light otherwise.
pub fn reference(decl: &MethodDecl) -> ReferenceKind {
    match Config::from_decl(decl, None) {
        Ok(c) if !c.transfer.bounces => ReferenceKind::Direct,
        _ => ReferenceKind::Bounces(16),
    }
}

/// The chart's sweep: bands × compression (native, 4096 and 65536 representatives), and the
/// faithful mode.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d, None) {
            let label = format!(
                "sh_lightmap {:?} bands={} reps={}",
                c.transfer.solve.mode, c.transfer.bands, c.reps
            )
            .to_lowercase();
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    for bands in [2i64, 3, 4, 6] {
        for reps in [0i64, 4096] {
            push(decl.with("bands", bands.into()).with("reps", reps.into()));
        }
    }
    push(decl.with("mode", "faithful".into()));
    out
}

/// What the bake produced: the atlas and its texels' coefficients, and each triangle corner's
/// light-map coordinate.
pub struct Baked {
    pub width: u32,
    pub height: u32,
    pub bands: usize,
    /// `bands²` per texel, row-major.
    pub coeffs: Vec<f32>,
    pub uvs: Vec<f32>,
}

impl Baked {
    fn to_floats(&self) -> Vec<f32> {
        let mut out = vec![self.width as f32, self.height as f32, self.bands as f32];
        out.extend(&self.coeffs);
        out.extend(&self.uvs);
        out
    }

    fn from_floats(v: &[f32], triangles: usize) -> Option<Baked> {
        let (w, h, b) = (*v.first()? as u32, *v.get(1)? as u32, *v.get(2)? as usize);
        let n = (w as usize) * (h as usize) * b * b;
        (v.len() == 3 + n + 6 * triangles && w > 0 && h > 0 && (2..=8).contains(&b)).then(|| Baked {
            width: w,
            height: h,
            bands: b,
            coeffs: v[3..3 + n].to_vec(),
            uvs: v[3 + n..].to_vec(),
        })
    }
}

/// The patches an SH light-map gets when the scene sets no `patch_size`: each casts `samples`
/// rays and keeps a bit per ray, so it costs far more than a radiosity patch.
pub const PATCH_BUDGET: f64 = 2048.0;

/// Bytes the bake holds per patch at `config`: the patch, its visibility bits, its transfer
/// vector four times over (the solve's total, unshot and reflectance, the result) in f64 and
/// once in the atlas in f32; with VQ, the quantiser's copy and index.
fn bytes_per_patch(config: &Config) -> u64 {
    let dim = (config.transfer.bands * config.transfer.bands) as u64;
    let words = config.samples.div_ceil(32) as u64;
    let vq = if config.reps > 0 { dim * 8 + 4 } else { 0 };
    std::mem::size_of::<crate::lighting::lightmap::patches::Patch>() as u64 + 4 * words + dim * (4 * 8 + 4) + vq
}

/// `patch_size` from the scene's area and [`PATCH_BUDGET`] when unset; the bake (and its VQ
/// table) refused when it would not fit the memory budget.
pub fn plan(
    decl: &MethodDecl,
    facts: &crate::lighting::plan::Facts<'_>,
) -> Result<Vec<crate::lighting::plan::Derived>> {
    use crate::lighting::plan::Derived;
    let mut config = Config::from_decl(decl, Some(facts.scene))?;
    let mut derived = Vec::new();
    let area = facts.area(NAME)?;
    if decl.param("patch_size").is_none() && area > 0.0 {
        let (derived_size, why) = crate::lighting::plan::lightmap_patch_size(facts.triangles(NAME)?, PATCH_BUDGET);
        config.patch_size = derived_size;
        derived.push(Derived::new("patch_size", config.patch_size, why));
    }
    let size = config.patch_size;
    let patches = crate::lighting::lightmap::patches::count(facts.triangles(NAME)?, size);
    let dim = (config.transfer.bands * config.transfer.bands) as u64;
    let table = if config.reps > 0 {
        config.reps as u64 * dim * 8
    } else {
        0
    };
    let what = if config.reps > 0 {
        format!(
            "the light-map at patch_size = {size} ({patches} patches of {} rays) with its VQ table of {} representatives",
            config.samples, config.reps
        )
    } else {
        format!(
            "the light-map at patch_size = {size} ({patches} patches of {} rays)",
            config.samples
        )
    };
    let need = patches * bytes_per_patch(&config) + table;
    let budget = facts.budget().0;
    let advice = if table >= budget {
        "set fewer representatives (reps)".to_string()
    } else if need > budget {
        shrink_advice(&config, facts.triangles(NAME)?, patches, budget - table)
    } else {
        String::new()
    };
    facts.check(NAME, &what, need, &advice)?;
    Ok(derived)
}

/// What would bring a light-map of `patches` patches within `room` bytes: a larger patch_size,
/// unless the charts alone make too many patches at any size (a curved mesh has a chart per
/// triangle or two, each at least a texel and its border), and the samples that would fit.
fn shrink_advice(
    config: &Config,
    triangles: &[crate::lighting::lightmap::patches::Triangle],
    patches: u64,
    room: u64,
) -> String {
    use crate::lighting::lightmap::patches::{count_in, group_charts_within, CURVED_SAG};
    // At a patch the size of a kilometre every chart is one texel in its border frame.
    let charts = group_charts_within(triangles, 1000.0 * CURVED_SAG);
    let floor = count_in(&charts, triangles, 1000.0);
    let fixed = bytes_per_patch(&Config { samples: 0, ..*config });
    let samples_fitting = (room / patches.max(1)).saturating_sub(fixed) / 4 * 32;
    let samples = if samples_fitting >= 20 {
        format!("fewer samples ({samples_fitting} at most fit at this patch_size)")
    } else {
        "fewer samples".to_string()
    };
    if floor * bytes_per_patch(config) > room {
        format!(
            "its {} charts (groups of triangles on or near one plane) make at least {floor} patches at any patch_size, so a larger one cannot fit it: {samples}, or a scene of fewer, flatter charts",
            charts.len()
        )
    } else {
        format!("set a larger patch_size or {samples}")
    }
}

/// Where the visibility rays are cast.
pub enum Rays<'a> {
    Cpu,
    Gpu(&'a mut crate::backend::Gpu, &'a crate::shaders::ShaderLibrary),
}

/// Bakes `geometry`'s SH light-map: patches, normal-mapped normals, visibility, transfer, atlas;
/// and the bounces' report. Where `world` is a BSP world with a PVS, the bounces' visibility
/// matrix starts from its leaf PVS, as radiosity's does: patch pairs whose leaves cannot see each
/// other cast no rays.
pub fn bake(
    geometry: &StaticGeometry,
    surfaces: Option<&Surfaces<'_>>,
    config: &Config,
    rays: Rays<'_>,
    world: Option<&Scene>,
    progress: &mut Progress,
) -> Result<(Baked, crate::lighting::lightmap::solve::Report)> {
    let mut p = Patches::build(&geometry.triangles, config.patch_size);
    let mut occluders = Occluders::new(&geometry.triangles);
    let mode = config.transfer.solve.mode;
    let samples = SampleSet::new(config.samples, config.transfer.bands)?;
    // Before any long work, once over a minute: the CPU visibility dominates a bake of fine
    // patches or many samples (hours at 2 cm on a courtyard); the bounces, shot on the CPU
    // whichever baker casts the rays, grow as patches × shots.
    let visibility = match rays {
        Rays::Cpu => transfer::visibility_estimate(&p, &occluders, &samples, mode),
        Rays::Gpu(..) => None,
    };
    let inside = p.patches.iter().filter(|q| q.inside()).count();
    let bounces = estimate::bounces(
        geometry,
        &config.transfer,
        config.samples,
        config.patch_size,
        inside,
        progress,
    );
    if let Some(e) = estimate::sum(visibility, bounces) {
        progress.warn_before(&e);
    }
    if mode == Mode::Corrected {
        // As radiosity's corrected bake does: a patch half under a wall standing on its floor
        // takes its transfer from the part that can be seen, not from a centre inside the wall.
        let cancel = progress.cancellation();
        let buried = progress.stage("buried patch parts", || {
            crate::lighting::lightmap::buried::exclude(&mut p, &occluders, cancel.as_ref())
        });
        if buried.is_none() {
            return Err(Error::Cancelled("sh light-map buried patch parts".into()));
        }
    }
    if let (Some(s), true) = (surfaces, config.normal_samples > 0) {
        normals::perturb(&mut p, &geometry.triangles, s, config.normal_samples);
    }
    if let Some(scene) = world {
        occluders.pvs = crate::lighting::lightmap::visibility::scene_chart_pvs(scene, &p, &geometry.triangles)?;
    }
    let bits = match rays {
        Rays::Cpu => transfer::visibility_cpu(&p, &occluders, &samples, mode, progress),
        Rays::Gpu(gpu, shaders) => {
            gpu::visibility_gpu(gpu, shaders, &p, &geometry.triangles, &samples, mode, progress)?
        }
    };
    crate::bake::check_cancelled(progress, "sh light-map visibility")?;
    // The bounces' own line: the visibility's rate says nothing of the shooting's time.
    let t = transfer::bake(
        &p,
        &occluders,
        &samples,
        &bits,
        &config.transfer,
        &mut Progress::new(&format!("{NAME} bounces ({} patches)", p.patches.len())),
    );
    let atlas = crate::lighting::lightmap::atlas::pack(&p);
    let dim = samples.dim();
    let mut coeffs = vec![0.0f32; (atlas.width * atlas.height) as usize * dim];
    for (ci, c) in p.charts.iter().enumerate() {
        let (ox, oy) = atlas.offsets[ci];
        for j in 0..c.height {
            for i in 0..c.width {
                let k = c.first + j * c.width + i;
                let texel = ((oy + j as u32) * atlas.width + ox + i as u32) as usize;
                for d in 0..dim {
                    coeffs[texel * dim + d] = t.coeffs[k * dim + d] as f32;
                }
            }
        }
    }
    let uvs = crate::lighting::lightmap::atlas::triangle_uvs(&geometry.triangles, &p, &atlas)
        .into_iter()
        .flatten()
        .collect();
    let baked = Baked {
        width: atlas.width,
        height: atlas.height,
        bands: samples.bands,
        coeffs,
        uvs,
    };
    Ok((baked, t.report))
}

/// The scene's normal maps, decoded, per material.
fn load_normal_maps(scene: &Scene) -> Result<Vec<Option<NormalImage>>> {
    scene
        .materials
        .iter()
        .map(|m| match &m.normal_map {
            None => Ok(None),
            Some(path) => {
                let img = crate::util::image_io::open_image(path)
                    .map_err(|e| {
                        Error::Usage(format!(
                            "{}: material {:?}: normal_map: cannot load {}: {e}",
                            scene.source,
                            m.name,
                            path.display()
                        ))
                    })?
                    .to_rgb8();
                Ok(Some(NormalImage::from_rgb8(
                    img.width() as usize,
                    img.height() as usize,
                    img.as_raw(),
                )))
            }
        })
        .collect()
}

/// An environment image projected to SH on the device every frame (the SH core's pass,
/// [`crate::sh::ShProjector`]), into `coeffs`: bands² RGB vec4s in the SH frame, zero past them.
pub struct EnvProjection {
    projector: crate::sh::ShProjector,
    image: crate::sh::EnvImage,
    bands: u32,
}

impl EnvProjection {
    fn new(cx: &mut CreateContext<'_>, bands: usize) -> Result<EnvProjection> {
        let env = cx.environment;
        // Box-filtered to at most 256 texels wide: an SH projection of ≤ 8 bands needs no more.
        let (w, texels) = env.reduced(256);
        let rgba32f = vk::Format::R32G32B32A32_SFLOAT;
        let desc = if env.cube {
            ImageDesc::new_cube("SH light-map environment", rgba32f, w)
        } else {
            ImageDesc::new_2d("SH light-map environment", rgba32f, w, texels.len() as u32 / w)
        };
        let image = cx
            .gpu
            .create_image(&desc.usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST))?;
        cx.gpu.upload_image(image, 0, bytemuck::cast_slice(&texels))?;
        cx.states.set_image(
            cx.gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )?;
        let image = crate::sh::EnvImage::of(cx.gpu, image)?;
        Ok(EnvProjection {
            projector: crate::sh::ShProjector::new(cx.gpu, cx.shaders, "SH light-map environment")?,
            image,
            bands: bands as u32,
        })
    }
}

/// The SH light-map base term.
pub struct ShLightmap {
    config: Config,
    pipeline: PipelineId,
    mesh: crate::lighting::lightmap::mesh::Mesh,
    /// Native: the coefficient layers. Compressed: the index map and the representative table.
    images: Vec<(&'static str, ImageId)>,
    sampler: SamplerId,
    lights: light::Lights,
    /// This frame's light uniform block.
    light: Vec<f32>,
    /// The environment image's projection (none for a constant or the CIE sky), and the buffer
    /// the shader adds to the light (zeros without one).
    env: Option<EnvProjection>,
    env_coeffs: BufferId,
}

/// The configuration the bake depends on: `config` with every run-time-only setting at its
/// default, so that those settings share one cache entry.
fn bake_config(config: &Config) -> Config {
    Config {
        view: View::Final,
        filter: false,
        storage: Storage::Single,
        reps: 0,
        sun_speed: 0.0,
        sky: config::Sky::Scene,
        cie_zenith: 0.0,
        on_gpu: None,
        ..*config
    }
}

/// What the bake depends on: its configuration, the static triangles, their light-map uvs, the
/// normal maps and the visibility shader.
fn bake_key(bake_config: &Config, geometry: &StaticGeometry, maps: &[Option<NormalImage>]) -> BakeKey {
    let mut key = BakeKey::new("SH light-map")
        .with("version", BAKER_VERSION)
        .with("config", bake_config);
    let geometry_bytes: Vec<f64> = geometry
        .triangles
        .iter()
        .flat_map(|t| {
            t.p.iter().flat_map(|p| p.to_array()).chain(t.albedo.to_array()).chain([
                t.object as f64,
                f64::from(u8::from(t.sky)),
                t.part as f64,
            ])
        })
        .collect();
    key = key.with_bytes("geometry", bytemuck::cast_slice(&geometry_bytes));
    let uv_bytes: Vec<f32> = geometry.uvs.iter().flatten().flatten().copied().collect();
    key = key.with_bytes("uvs", bytemuck::cast_slice(&uv_bytes));
    for (i, m) in maps.iter().enumerate() {
        if let Some(m) = m {
            let texels: Vec<f64> = m.texels.iter().flat_map(|t| t.to_array()).collect();
            key = key.with_bytes(&format!("normal map {i}"), bytemuck::cast_slice(&texels));
        }
    }
    // The GPU's rays give the CPU's bits but for a few seam rays (tests/methods/sh_lightmap_gpu.rs):
    // one cache entry serves both.
    key.with_shaders("sh_lightmap/visibility")
}

/// The shading pipeline for `bands` baked bands: the native or compressed fragment shader,
/// specialised for the storage, the solve's mode, the view and the filter.
fn shade_pipeline(cx: &mut CreateContext<'_>, config: &Config, bands: usize) -> Result<PipelineId> {
    let (fragment, encoded) = match config.reps {
        0 => ("sh_lightmap/native.frag", config.storage == Storage::Rgba8),
        _ => ("sh_lightmap/compressed.frag", config.storage == Storage::Rgba8),
    };
    let mut desc = crate::lighting::lightmap::mesh::Mesh::pipeline_desc(&format!("{NAME} bands={bands}"), fragment);
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
    desc.depth_format = Some(cx.gpu.caps().depth_stencil_format);
    let faithful = config.transfer.solve.mode == Mode::Faithful;
    desc.specialization = vec![
        SpecConstant {
            id: 0,
            bits: bands as u32,
        },
        SpecConstant {
            id: 1,
            bits: u32::from(encoded),
        },
        SpecConstant {
            id: 2,
            bits: u32::from(faithful),
        },
        SpecConstant {
            id: 3,
            bits: config.view as u32,
        },
        SpecConstant {
            id: 4,
            bits: u32::from(config.filter),
        },
    ];
    Ok(cx.gpu.create_graphics_pipeline(&desc, cx.shaders)?)
}

impl ShLightmap {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<ShLightmap> {
        let config = Config::from_decl(decl, Some(cx.scene))?;
        for w in crate::lighting::params::Params::new(decl, Some(cx.scene)).inert_warnings(&config.inert()) {
            crate::errln!("{w}");
        }
        if let Some(w) = crate::lighting::distant_only_warning(cx.scene, NAME) {
            crate::errln!("{w}");
        }
        let mut geometry = crate::lighting::lightmap::geometry::static_geometry(cx.scene, cx.scene_gpu, NAME)?;
        if let Some(w) = crate::lighting::lightmap::geometry::behind_warning(cx.scene, &geometry.triangles, NAME) {
            crate::errln!("{w}");
        }
        // The document's light-maps let texels straddle thin walls; the corrected mode cuts there.
        let uncut = (config.transfer.solve.mode == Mode::Corrected)
            .then(|| crate::lighting::lightmap::cut::cut_copy(&mut geometry, config.patch_size))
            .flatten();
        if geometry.triangles.is_empty() {
            return Err(Error::Usage(format!(
                "{}: {NAME}: the scene has no static geometry to light-map",
                cx.scene.source
            )));
        }
        let maps = load_normal_maps(cx.scene)?;
        let surfaces = Surfaces {
            uvs: &geometry.uvs,
            maps: geometry
                .material
                .iter()
                .map(|m| m.and_then(|m| maps.get(m).and_then(|x| x.as_ref())))
                .collect(),
        };
        let bake_config = bake_config(&config);
        let key = bake_key(&bake_config, &geometry, &maps);
        let (geo, surf, scene) = (&geometry, &surfaces, cx.scene);
        let (device, shaders) = (&mut *cx.gpu, cx.shaders);
        let floats: Vec<f32> = cx.bakes.bake(
            &format!("{NAME} bands={} patch={}", config.transfer.bands, config.patch_size),
            &key,
            |progress| {
                // Auto: the GPU, unless it is a CPU implementation (lavapipe), where the native rays
                // measured 5x faster (tests/methods/sh_lightmap_gpu.rs, ignored measurement).
                let on_gpu = config
                    .on_gpu
                    .unwrap_or(device.caps().device_type != vk::PhysicalDeviceType::CPU);
                let rays = if on_gpu { Rays::Gpu(device, shaders) } else { Rays::Cpu };
                Ok(bake(geo, Some(surf), &bake_config, rays, Some(scene), progress)?
                    .0
                    .to_floats())
            },
        )?;
        let baked = Baked::from_floats(&floats, geometry.triangles.len()).ok_or_else(|| {
            Error::Internal(format!(
                "{}: {NAME}: the baked SH light-map does not match the scene",
                cx.scene.source
            ))
        })?;
        let mesh = crate::lighting::lightmap::mesh::Mesh::new(cx, &geometry, &baked.uvs, NAME, uncut.as_ref())?;
        let images = if config.reps == 0 {
            upload_native(cx, &baked, config.storage)?
        } else {
            upload_compressed(cx, &baked, &config, &key)?
        };
        let pipeline = shade_pipeline(cx, &config, baked.bands)?;
        let faithful = config.transfer.solve.mode == Mode::Faithful;
        let sampler = cx.gpu.sampler(if config.reps == 0 {
            SamplerDesc::LINEAR_CLAMP
        } else {
            SamplerDesc::NEAREST_CLAMP
        })?;
        let lights = light::Lights::new(cx.scene, cx.environment, &config)?;
        let light = lights.uniform(0.0, faithful);
        let env = if config.sky == config::Sky::Scene && !light::is_constant(cx.environment) {
            Some(EnvProjection::new(cx, baked.bands)?)
        } else {
            None
        };
        // 64 vec4 (8 bands), zero where the projection writes nothing.
        let env_coeffs = cx.gpu.create_buffer_init(
            "SH light-map environment SH",
            vk::BufferUsageFlags::STORAGE_BUFFER,
            &[0u8; 16 * 64],
        )?;
        cx.states.forget_buffer(env_coeffs);
        Ok(ShLightmap {
            config,
            pipeline,
            mesh,
            images,
            sampler,
            lights,
            light,
            env,
            env_coeffs,
        })
    }
}

fn storage_error(e: impl std::fmt::Display) -> Error {
    Error::Usage(format!("{NAME}: {e}"))
}

fn upload_native(cx: &mut CreateContext<'_>, baked: &Baked, storage: Storage) -> Result<Vec<(&'static str, ImageId)>> {
    let (w, h, bands) = (baked.width, baked.height, baked.bands);
    let texels = (w * h) as usize;
    let (format, mut bytes, zero): (vk::Format, Vec<u8>, Vec<u8>) = match storage {
        // A zero coefficient encodes as 128 (the seed's range encoding has no exact zero).
        Storage::Rgba8 => (
            vk::Format::R8G8B8A8_UNORM,
            storage::pack_layers_rgba8(&baked.coeffs, bands, w, h).map_err(storage_error)?,
            vec![storage::encode_range(0.0); 4 * texels],
        ),
        Storage::Half => (
            vk::Format::R16G16B16A16_SFLOAT,
            bytemuck::cast_slice(&storage::pack_layers_f16(&baked.coeffs, bands, w, h).map_err(storage_error)?)
                .to_vec(),
            vec![0; 8 * texels],
        ),
        Storage::Single => (
            vk::Format::R32G32B32A32_SFLOAT,
            bytemuck::cast_slice(&storage::pack_layers_f32(&baked.coeffs, bands, w, h).map_err(storage_error)?)
                .to_vec(),
            vec![0; 16 * texels],
        ),
    };
    // At least two layers, so that the view is always an array (2 bands fill one).
    let layers = storage::layers(bands).max(2) as u32;
    if storage::layers(bands) < 2 {
        bytes.extend(zero);
    }
    let image = cx.gpu.create_image(
        &ImageDesc::new_2d("SH light-map layers", format, w, h)
            .layers(layers)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    cx.gpu.upload_image(image, 0, &bytes)?;
    cx.states.set_image(
        cx.gpu,
        image,
        Access::SampledRead {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
        },
    )?;
    Ok(vec![("layers", image)])
}

/// The VQ of a bake: the texels that hold a transfer are quantised (gap texels between charts,
/// all zero and never drawn, would only crowd the seed's strided initial picks with duplicates);
/// gap texels get index 0.
pub fn quantize(baked: &Baked, reps: usize, progress: &mut Progress) -> Result<vq::Quantized> {
    let dim = baked.bands * baked.bands;
    let used: Vec<usize> = (0..baked.coeffs.len() / dim)
        .filter(|&t| baked.coeffs[t * dim..(t + 1) * dim].iter().any(|&c| c != 0.0))
        .collect();
    let vectors: Vec<f32> = used
        .iter()
        .flat_map(|&t| baked.coeffs[t * dim..(t + 1) * dim].iter().copied())
        .collect();
    let settings = vq::VqSettings::new(reps);
    let mut q = vq::quantize(&vectors, dim, &settings, |iteration, max| {
        progress.set_detail(format!("VQ iteration {iteration}, max nearest distance² {max:.3e}"));
        progress.update(iteration as u64, settings.max_iterations as u64);
    })
    .map_err(storage_error)?;
    let mut indices = vec![0u16; baked.coeffs.len() / dim];
    for (&t, &i) in used.iter().zip(&q.indices) {
        indices[t] = i;
    }
    q.indices = indices;
    Ok(q)
}

fn upload_compressed(
    cx: &mut CreateContext<'_>,
    baked: &Baked,
    config: &Config,
    key: &BakeKey,
) -> Result<Vec<(&'static str, ImageId)>> {
    let dim = baked.bands * baked.bands;
    let key = key.clone().with("reps", config.reps);
    // The seed's world-size accounting (Table 4) in the bake's name, so `penumbra bake` reports it.
    let texels = (baked.width * baked.height) as usize;
    let size = match (
        storage::StorageReport::uncompressed(texels, baked.bands),
        storage::StorageReport::compressed(texels, baked.bands, config.reps),
    ) {
        (Ok(u), Ok(c)) => format!(
            "; {texels} texels, SH payload {:.0} kB against {:.0} kB native ({:.1}x)",
            c.payload_bytes_model as f64 / storage::KB as f64,
            u.payload_bytes_model as f64 / storage::KB as f64,
            storage::compression_ratio(&u, &c)
        ),
        _ => String::new(),
    };
    let floats: Vec<f32> = cx
        .bakes
        .bake(&format!("{NAME} VQ reps={}{size}", config.reps), &key, |progress| {
            let q = quantize(baked, config.reps, progress)?;
            let mut out: Vec<f32> = q.indices.iter().map(|&i| i as f32).collect();
            out.extend(&q.codebook);
            Ok(out)
        })?;
    if floats.len() < texels || !(floats.len() - texels).is_multiple_of(dim) {
        return Err(Error::Internal(format!(
            "{}: {NAME}: the cached VQ does not match the light-map",
            cx.scene.source
        )));
    }
    let indices: Vec<u16> = floats[..texels].iter().map(|&i| i as u16).collect();
    let codebook = &floats[texels..];
    let index_image = cx.gpu.create_image(
        &ImageDesc::new_2d(
            "SH light-map indices",
            vk::Format::R8G8B8A8_UINT,
            baked.width,
            baked.height,
        )
        .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    cx.gpu
        .upload_image(index_image, 0, &storage::pack_indices_rgba8(&indices))?;
    let (table_format, (tw, th, table_bytes)) = match config.storage {
        Storage::Rgba8 => (
            vk::Format::R8G8B8A8_UNORM,
            storage::pack_table_rgba8(codebook, baked.bands).map_err(storage_error)?,
        ),
        _ => {
            let (w, h, t) = storage::pack_table_f32(codebook, baked.bands).map_err(storage_error)?;
            (
                vk::Format::R32G32B32A32_SFLOAT,
                (w, h, bytemuck::cast_slice(&t).to_vec()),
            )
        }
    };
    let table = cx.gpu.create_image(
        &ImageDesc::new_2d("SH light-map representatives", table_format, tw, th)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    cx.gpu.upload_image(table, 0, &table_bytes)?;
    for image in [index_image, table] {
        cx.states.set_image(
            cx.gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )?;
    }
    Ok(vec![("indices", index_image), ("table", table)])
}

impl LightingMethod for ShLightmap {
    fn name(&self) -> &'static str {
        NAME
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        self.light = self.lights.uniform(
            frame.clock.time_s as f64,
            self.config.transfer.solve.mode == Mode::Faithful,
        );
        Ok(())
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        if !frame.terms.has(Term::Base) {
            return Ok(());
        }
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        if let Some(env) = &self.env {
            env.projector
                .add_passes(graph, "SH light-map environment", env.image, env.bands, self.env_coeffs)?;
        }
        let mut pass =
            graph
                .pass("SH light-map")
                .buffer(self.env_coeffs, Access::StorageRead { stages: frag }, Some("env_sh"));
        for &(name, image) in &self.images {
            pass = pass.sample(name, image, SubresourceRange::full(), self.sampler, frag);
        }
        self.mesh.draw(
            pass,
            frame,
            self.pipeline,
            vec![("light", bytemuck::cast_slice(&self.light).to_vec())],
        );
        self.mesh.add_depth_pass(graph, frame);
        Ok(())
    }
}
