//! The height-field lighting passes on the GPU (the height-field thesis §5): height update, pyramid (or the
//! brute-force bounds), environment projection, environment pass, one pass per sphere light and
//! the accumulation, each a compute dispatch with its own timestamp scope. [`HeightfieldGpu`]
//! owns the images, tables and pipelines; [`HeightfieldGpu::add_compute_passes`] adds one frame's
//! passes to a graph, ending in [`HeightfieldGpu::shading`] (res², RGBA32F: the exit radiance
//! over ρ, i.e. L·(V•C) summed over the lights, clamped at 0).

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use super::pyramid;
use super::settings::{Decimation, Horizon, Mode, Settings, MAX_BANDS, MAX_LEVELS, MAX_LIGHTS, MAX_NPHI};
use super::wedge::{TableKind, WedgeTable};
use crate::backend::{
    vk, Bind, BufferDesc, BufferId, ComputePipelineDesc, Gpu, ImageDesc, ImageId, MemoryKind, PipelineId, SamplerDesc,
    SamplerId, SpecConstant, SubresourceRange,
};
use crate::bake::{BakeKey, Baker};
use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::scene::{Environment, HeightImage, HeightShape, HeightfieldSource, Light, MeshSource, Scene};
use crate::shaders::ShaderLibrary;

const COMPUTE: vk::PipelineStageFlags2 = vk::PipelineStageFlags2::COMPUTE_SHADER;
const R32F: vk::Format = vk::Format::R32_SFLOAT;
const RGBA32F: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Environment maps are box-filtered down to at most this width before projection.
const MAX_ENV_WIDTH: u32 = 256;

/// `HfGen` in `glsl/heightfield/generate.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GenParams {
    pub kind: [u32; 4],
    pub shape: [f32; 4],
    pub placement: [f32; 4],
    pub motion: [f32; 4],
    pub field: [f32; 4],
}

impl GenParams {
    /// The generator of `src` sampled at `res²` (image size `image` for image sources).
    pub fn new(src: &HeightfieldSource, res: u32, image: Option<(u32, u32)>) -> GenParams {
        let (count, seed, shape) = match &src.shape {
            HeightShape::Flat | HeightShape::Image { .. } => (0, 0, [0.0; 4]),
            HeightShape::Slope { slope_deg } => (0, 0, [slope_deg.to_radians().tan(), 0.0, 0.0, 0.0]),
            HeightShape::Step { position } => (0, 0, [*position, 0.0, 0.0, 0.0]),
            HeightShape::Sine { wavelength } | HeightShape::EggTray { wavelength } => {
                (0, 0, [*wavelength, 0.0, 0.0, 0.0])
            }
            HeightShape::Cones {
                count,
                radius,
                ring_radius,
                size_variation,
            } => (*count, 0, [0.0, *radius, *ring_radius, *size_variation]),
            HeightShape::Fbm {
                wavelength,
                octaves,
                seed,
            } => (*octaves, *seed, [*wavelength, 0.0, 0.0, 0.0]),
            HeightShape::City {
                wavelength,
                seed,
                street,
            } => (0, *seed, [*wavelength, 0.0, 0.0, *street]),
        };
        let (s, c) = src.pattern_rotate_deg.to_radians().sin_cos();
        let (iw, ih) = image.unwrap_or((1, 1));
        GenParams {
            kind: [src.shape.code(), count, seed, image.is_some() as u32],
            shape,
            placement: [src.height, src.taper, src.offset.x, src.offset.y],
            motion: [c, s, src.speed, 0.0],
            field: [src.size, res as f32, iw as f32, ih as f32],
        }
    }
}

/// A sphere light as the passes see it (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereLight {
    pub center: Vec3,
    pub radius: f32,
    pub radiance: Vec3,
}

/// `HfParams` in `glsl/heightfield/common.glsl` (std140), serialised by [`PassParams::bytes`].
#[derive(Clone, Debug)]
pub struct PassParams {
    pub dims: [i32; 4],
    pub cfg: [i32; 4],
    pub grid: [f32; 4],
    pub horizon: [f32; 4],
    pub light_pos: [f32; 4],
    pub light_radiance: [f32; 4],
    /// The transfer window's factor per band, bands 0–7.
    pub window: [[f32; 4]; 2],
    pub dirs: Vec<[f32; 4]>,
    pub rot: Vec<[f32; 4]>,
    pub samples: Vec<[f32; 4]>,
}

impl PassParams {
    pub fn bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(16 * (6 + MAX_NPHI as usize * 4 + MAX_LEVELS as usize));
        out.extend_from_slice(bytemuck::cast_slice(&self.dims));
        out.extend_from_slice(bytemuck::cast_slice(&self.cfg));
        for v in [
            self.grid,
            self.horizon,
            self.light_pos,
            self.light_radiance,
            self.window[0],
            self.window[1],
        ] {
            out.extend_from_slice(bytemuck::cast_slice(&v));
        }
        let mut push = |v: &[[f32; 4]], n: usize| {
            for i in 0..n {
                out.extend_from_slice(bytemuck::cast_slice(&v.get(i).copied().unwrap_or([0.0; 4])));
            }
        };
        push(&self.dirs, MAX_NPHI as usize);
        push(&self.rot, MAX_NPHI as usize * 3);
        push(&self.samples, MAX_LEVELS as usize);
        out
    }
}

/// The non-zero Γ_ijk (i, j, k < bands²) as the shader's packed list (the SH core's
/// `sh::product_terms`, which `sh_product` in glsl/common/sh.glsl consumes).
pub fn product_entries(bands: u32) -> Result<Vec<[u32; 2]>> {
    crate::sh::product_terms(bands as usize).map_err(|e| Error::Usage(format!("SH product: {e}")))
}

struct Pipelines {
    height: PipelineId,
    decimate: PipelineId,
    reconstruct: PipelineId,
    bounds: PipelineId,
    env_sh: PipelineId,
    /// The SH core's projection pass, for image environments.
    env_project: crate::sh::ShProjector,
    env: PipelineId,
    light: PipelineId,
    accumulate: PipelineId,
    horizon: PipelineId,
}

/// What the lighting passes light with, read from the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvInput {
    None,
    Constant(Vec3),
    /// An equirectangular map (already reduced), RGBA texels, rows from straight up.
    Map {
        width: u32,
        height: u32,
        texels: Vec<[f32; 4]>,
    },
    /// A cube map (already reduced): six `size`² faces in layer order (as [`crate::scene::CubeFaces`]).
    Cube {
        size: u32,
        texels: Vec<[f32; 4]>,
    },
}

/// The height field, its lights and environment, as the method takes them from a scene.
#[derive(Clone, Debug)]
pub struct FieldInputs {
    /// Index of the height-field object in `scene.objects`.
    pub object: usize,
    pub source: HeightfieldSource,
    pub translation: Vec3,
    /// Index of the field's material in `scene.materials` (and `SceneGpu::material_maps`).
    pub material: usize,
    pub albedo: Vec3,
    pub emission: Vec3,
    pub lights: Vec<SphereLight>,
    pub environment: EnvInput,
}

impl FieldInputs {
    /// The first `mesh = "heightfield"` object, the scene's sphere lights and its environment.
    /// Other light types are errors (the method lights with spheres and the environment only).
    /// `env`: the scene's environment as [`EnvironmentMap::of_scene`] loaded it.
    pub fn from_scene(scene: &Scene, env: &EnvironmentMap, method: &str) -> Result<FieldInputs> {
        let src = &scene.source;
        let (object, obj) = scene
            .objects
            .iter()
            .enumerate()
            .find(|(_, o)| matches!(o.mesh, MeshSource::Heightfield(_)))
            .ok_or_else(|| {
                Error::Usage(format!(
                    "{src}: methods: {method} needs an object with mesh = \"heightfield\""
                ))
            })?;
        let MeshSource::Heightfield(source) = &obj.mesh else {
            unreachable!("matched above")
        };
        let (scale, rotation, translation) = obj.transform.to_scale_rotation_translation();
        if (scale - Vec3::ONE).abs().max_element() > 1e-6 || rotation.angle_between(glam::Quat::IDENTITY) > 1e-6 {
            return Err(Error::Usage(format!(
                "{src}: objects[{object}] ({:?}): {method} needs the height field placed by translate only (no rotate_deg or scale; use size, height and pattern_rotate_deg)",
                obj.name
            )));
        }
        let material = scene
            .materials
            .get(obj.material)
            .ok_or_else(|| Error::Internal(format!("{src}: objects[{object}]: material index out of range")))?;
        // The shading comes from the field's own normals through the SH transfer, computed per
        // texel before any material is known, so a normal map cannot be honoured; refusing it
        // keeps the method from silently disagreeing with the reference, which applies it.
        if material.normal_map.is_some() {
            return Err(Error::Usage(format!(
                "{src}: materials[{}] ({:?}).normal_map: {method} cannot apply a normal map (it shades with the height field's own normals); used by the height field objects[{object}] ({:?})",
                obj.material, material.name, obj.name
            )));
        }
        let mut lights = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            match l {
                Light::Sphere {
                    center,
                    radius,
                    radiance,
                    ..
                } => lights.push(SphereLight {
                    center: *center,
                    radius: *radius,
                    radiance: *radiance,
                }),
                other => {
                    let kind = match other {
                        Light::Point { .. } => "point",
                        Light::Spot { .. } => "spot",
                        Light::Directional { .. } => "directional",
                        _ => "quad",
                    };
                    return Err(Error::Usage(format!("{src}: lights[{i}] ({:?}): {method} lights with sphere lights and the environment only, not a {kind} light", other.name())));
                }
            }
        }
        if lights.len() > MAX_LIGHTS {
            return Err(Error::Usage(format!(
                "{src}: lights: {method} takes at most {MAX_LIGHTS} sphere lights, the scene has {}",
                lights.len()
            )));
        }
        let environment = match &scene.environment {
            None => EnvInput::None,
            Some(Environment::Constant { radiance }) => EnvInput::Constant(*radiance),
            Some(Environment::Image { .. }) => {
                let (width, texels) = env.reduced(MAX_ENV_WIDTH);
                EnvInput::Map {
                    width,
                    height: texels.len() as u32 / width,
                    texels,
                }
            }
            Some(Environment::Cube { .. }) => {
                let (size, texels) = env.reduced(MAX_ENV_WIDTH);
                EnvInput::Cube { size, texels }
            }
        };
        Ok(FieldInputs {
            object,
            source: source.clone(),
            translation,
            material: obj.material,
            albedo: material.albedo,
            emission: material.emission,
            lights,
            environment,
        })
    }
}

/// Bumped whenever `wedge::exact_wedge` or the table layout changes: the bake key of CPU-built
/// tables has no shader to hash.
const WEDGE_TABLE_VERSION: u32 = 1;

/// A wedge table through the bake stage (a precomputed visibility table, keyed by its settings).
fn baked_wedge_table(
    bakes: &mut Baker,
    kind: TableKind,
    nphi: usize,
    nodes: usize,
    bands: usize,
) -> Result<WedgeTable> {
    let key = BakeKey::new("heightfield wedge table")
        .with("version", WEDGE_TABLE_VERSION)
        .with("kind", kind)
        .with("nphi", nphi)
        .with("nodes", nodes)
        .with("bands", bands);
    let name = format!("hf wedge table {kind:?} nphi={nphi} nodes={nodes} bands={bands}");
    let table_err = |e: crate::sh::ShError| Error::Usage(format!("wedge table: {e}"));
    let data: Vec<f64> = bakes.bake(&name, &key, |_| {
        Ok(WedgeTable::build(kind, nphi, nodes, bands).map_err(table_err)?.data)
    })?;
    let table = WedgeTable {
        kind,
        nphi,
        nodes: nodes.max(2),
        bands,
        data,
    };
    if table.data.len() != table.nodes * table.nodes * bands * bands {
        return Err(Error::Internal(format!(
            "{name}: the baked table has {} values, expected {}",
            table.data.len(),
            table.nodes * table.nodes * bands * bands
        )));
    }
    Ok(table)
}

/// Everything one instance of the method keeps on the GPU.
pub struct HeightfieldGpu {
    pub settings: Settings,
    pub inputs: FieldInputs,
    /// Samples per side.
    pub res: u32,
    /// Pyramid levels = horizon samples per direction (pyramid method).
    pub levels: u32,
    pub level_sizes: Vec<u32>,
    /// World x, z of sample (0, 0) and metres per sample.
    pub origin: Vec2,
    pub spacing: f32,
    pub heights: ImageId,
    source_image: ImageId,
    image_size: Option<(u32, u32)>,
    decimated: Option<ImageId>,
    pub pyramid: Option<ImageId>,
    /// The environment map as the SH projection takes it: its layout (equirect or cube) from the
    /// image itself.
    env_image: crate::sh::EnvImage,
    env_sh: BufferId,
    env_table: BufferId,
    local_table: BufferId,
    product: BufferId,
    product_count: u32,
    bounds: Option<BufferId>,
    pub env_radiance: ImageId,
    pub light_radiance: ImageId,
    pub shading: ImageId,
    pub nearest: SamplerId,
    pub linear: SamplerId,
    /// The sampler the lighting passes read heights and pyramid levels through.
    height_sampler: SamplerId,
    pipelines: Pipelines,
}

/// Loop iterations llvmpipe allows one shader invocation, all loops together (gallivm's
/// LP_MAX_TGSI_LOOP_ITERATIONS); beyond it loops end silently.
const LLVMPIPE_LOOP_BUDGET: f32 = 65535.0;

/// Layers of the per-light radiance image.
fn light_layers(lights: usize) -> u32 {
    lights.max(2) as u32
}

fn compute(gpu: &mut Gpu, shaders: &ShaderLibrary, name: &str, shader: &str) -> Result<PipelineId> {
    compute_spec(gpu, shaders, name, shader, vec![])
}

fn compute_spec(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    name: &str,
    shader: &str,
    specialization: Vec<SpecConstant>,
) -> Result<PipelineId> {
    Ok(gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: name.into(),
            shader: shader.into(),
            specialization,
        },
        shaders,
    )?)
}

fn storage_buffer(gpu: &mut Gpu, states: &mut ResourceStates, name: &str, bytes: &[u8]) -> Result<BufferId> {
    let b = gpu.create_buffer_init(name, vk::BufferUsageFlags::STORAGE_BUFFER, bytes)?;
    states.forget_buffer(b);
    Ok(b)
}

fn texture(
    gpu: &mut Gpu,
    states: &mut ResourceStates,
    name: &str,
    format: vk::Format,
    w: u32,
    h: u32,
    bytes: &[u8],
) -> Result<ImageId> {
    let id = gpu.create_image(
        &ImageDesc::new_2d(name, format, w, h).usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    gpu.upload_image(id, 0, bytes)?;
    states.set_image(
        gpu,
        id,
        Access::SampledRead {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
        },
    )?;
    Ok(id)
}

/// Refuses settings the shaders cannot run: too many pyramid levels, bands or directions, and on
/// llvmpipe a brute-force march longer than its loop budget.
fn check_settings(gpu: &Gpu, settings: &Settings, res: u32, levels: u32) -> Result<()> {
    if levels > MAX_LEVELS {
        return Err(Error::Usage(format!(
            "ls = {} at {res}² gives {levels} pyramid levels; at most {MAX_LEVELS} are supported",
            settings.ls
        )));
    }
    if settings.bands > MAX_BANDS || settings.nphi > MAX_NPHI {
        return Err(Error::Usage(format!(
            "bands ≤ {MAX_BANDS} and nphi ≤ {MAX_NPHI} are supported"
        )));
    }
    if settings.horizon == Horizon::BruteForce && gpu.caps().name.contains("llvmpipe") {
        // llvmpipe ends a shader invocation's loops after 65535 iterations in all (shared by
        // every loop), silently; the march takes 8 positions per iteration, over res texels
        // (environment) or up to 2·res (lights), in every direction.
        let reach = if settings.max_distance > 0.0 {
            settings.max_distance
        } else {
            2.0 * res as f32
        };
        // The march, then the visibility, product and basis loops (≤ 2907 product terms).
        let trips = settings.nphi as f32 * ((reach / settings.march_step / 8.0).ceil() + 66.0) + 3000.0;
        if trips > LLVMPIPE_LOOP_BUDGET {
            return Err(Error::Backend(crate::backend::BackendError::Unsupported(format!(
                "heightfield_bruteforce at {res}² with nphi = {} and march_step = {} needs about {trips:.0} loop iterations per texel; llvmpipe stops a shader's loops after {LLVMPIPE_LOOP_BUDGET:.0} (use a larger march_step or max_distance)",
                settings.nphi, settings.march_step
            ))));
        }
    }
    Ok(())
}

/// The height images: the field, its source image (a 1x1 stand-in without one), and the
/// horizon search's pyramid levels or, brute force, its bounds.
struct HeightImages {
    heights: ImageId,
    source_image: ImageId,
    image_size: Option<(u32, u32)>,
    decimated: Option<ImageId>,
    pyramid: Option<ImageId>,
    bounds: Option<BufferId>,
}

impl HeightImages {
    fn new(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        settings: &Settings,
        source: &HeightfieldSource,
        res: u32,
        levels: u32,
    ) -> Result<HeightImages> {
        let rw = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let heights = gpu.create_image(&ImageDesc::new_2d("hf heights", R32F, res, res).usage(rw))?;
        let (source_image, image_size) = match source.load_image()? {
            Some(HeightImage { width, height, values }) => (
                texture(
                    gpu,
                    states,
                    "hf height image",
                    R32F,
                    width,
                    height,
                    bytemuck::cast_slice(&values),
                )?,
                Some((width, height)),
            ),
            None => (
                texture(
                    gpu,
                    states,
                    "hf height image (none)",
                    R32F,
                    1,
                    1,
                    bytemuck::bytes_of(&0.0f32),
                )?,
                None,
            ),
        };
        let (decimated, pyramid_img, bounds) = match settings.horizon {
            Horizon::Pyramid => (
                Some(
                    gpu.create_image(
                        &ImageDesc::new_2d("hf decimated levels", R32F, res, res)
                            .layers(levels)
                            .usage(rw),
                    )?,
                ),
                Some(gpu.create_image(&ImageDesc::new_2d("hf pyramid", R32F, res, res).layers(levels).usage(rw))?),
                None,
            ),
            Horizon::BruteForce => {
                let b = gpu.create_buffer(&BufferDesc {
                    name: "hf bounds".into(),
                    size: 16,
                    usage: vk::BufferUsageFlags::STORAGE_BUFFER,
                    memory: MemoryKind::GpuOnly,
                })?;
                (None, None, Some(b))
            }
        };
        Ok(HeightImages {
            heights,
            source_image,
            image_size,
            decimated,
            pyramid: pyramid_img,
            bounds,
        })
    }
}

/// The environment as the lighting passes sample it: its map, its cube, or black.
fn environment_image(gpu: &mut Gpu, states: &mut ResourceStates, environment: &EnvInput) -> Result<ImageId> {
    Ok(match environment {
        EnvInput::Map { width, height, texels } => texture(
            gpu,
            states,
            "hf environment map",
            RGBA32F,
            *width,
            *height,
            bytemuck::cast_slice(texels),
        )?,
        EnvInput::Cube { size, texels } => {
            let id = gpu.create_image(
                &ImageDesc::new_cube("hf environment cube", RGBA32F, *size)
                    .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
            )?;
            gpu.upload_image(id, 0, bytemuck::cast_slice(texels))?;
            states.set_image(
                gpu,
                id,
                Access::SampledRead {
                    stages: vk::PipelineStageFlags2::ALL_COMMANDS,
                },
            )?;
            id
        }
        _ => texture(
            gpu,
            states,
            "hf environment map (none)",
            RGBA32F,
            1,
            1,
            bytemuck::cast_slice(&[0.0f32; 4]),
        )?,
    })
}

/// The compute pipelines, and whether the height fetches use the device's bilinear filter.
fn create_pipelines(gpu: &mut Gpu, shaders: &ShaderLibrary, settings: &Settings) -> Result<(Pipelines, bool)> {
    let (env_shader, light_shader, horizon_shader) = match settings.horizon {
        Horizon::Pyramid => (
            "heightfield/env_pyramid.comp",
            "heightfield/light_pyramid.comp",
            "heightfield/horizon_pyramid.comp",
        ),
        Horizon::BruteForce => (
            "heightfield/env_brute.comp",
            "heightfield/light_brute.comp",
            "heightfield/horizon_brute.comp",
        ),
    };
    // One filtered fetch per height sample where the device filters R32_SFLOAT.
    let hardware_bilinear = settings.hardware_bilinear
        && gpu
            .format_features(R32F)
            .contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
    let spec = vec![SpecConstant {
        id: 0,
        bits: hardware_bilinear as u32,
    }];
    let pipelines = Pipelines {
        height: compute(gpu, shaders, "hf height update", "heightfield/height_update.comp")?,
        decimate: compute(gpu, shaders, "hf decimate", "heightfield/decimate.comp")?,
        reconstruct: compute(gpu, shaders, "hf reconstruct", "heightfield/reconstruct.comp")?,
        bounds: compute(gpu, shaders, "hf bounds", "heightfield/bounds.comp")?,
        env_sh: compute(gpu, shaders, "hf environment SH", "heightfield/env_sh.comp")?,
        env_project: crate::sh::ShProjector::new(gpu, shaders, "hf environment SH")?,
        env: compute_spec(gpu, shaders, "hf environment", env_shader, spec.clone())?,
        light: compute_spec(gpu, shaders, "hf light", light_shader, spec.clone())?,
        accumulate: compute(gpu, shaders, "hf accumulate", "heightfield/accumulate.comp")?,
        horizon: compute_spec(gpu, shaders, "hf horizons", horizon_shader, spec)?,
    };
    Ok((pipelines, hardware_bilinear))
}

impl HeightfieldGpu {
    /// The wedge tables come through `bakes` (cached on disk when it has a directory).
    pub fn new(
        gpu: &mut Gpu,
        shaders: &ShaderLibrary,
        states: &mut ResourceStates,
        bakes: &mut Baker,
        settings: Settings,
        inputs: FieldInputs,
    ) -> Result<HeightfieldGpu> {
        let res = settings.resolution.unwrap_or(inputs.source.resolution);
        let levels = pyramid::level_count(res, settings.ls);
        check_settings(gpu, &settings, res, levels)?;
        let level_sizes: Vec<u32> = (0..levels).map(|k| pyramid::level_size(res, settings.ls, k)).collect();
        let spacing = inputs.source.size / res as f32;
        let origin = Vec2::new(
            inputs.translation.x - 0.5 * inputs.source.size + 0.5 * spacing,
            inputs.translation.z - 0.5 * inputs.source.size + 0.5 * spacing,
        );
        let h = HeightImages::new(gpu, states, &settings, &inputs.source, res, levels)?;
        let env_map = environment_image(gpu, states, &inputs.environment)?;
        let env_image = crate::sh::EnvImage::of(gpu, env_map)?;
        let env_sh = gpu.create_buffer(&BufferDesc {
            name: "hf environment SH".into(),
            size: 16 * 64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuOnly,
        })?;
        let (nphi, nodes, bands) = (
            settings.nphi as usize,
            settings.table_size as usize,
            settings.bands as usize,
        );
        let env_t = baked_wedge_table(bakes, TableKind::Environment, nphi, nodes, bands)?;
        let local_t = baked_wedge_table(bakes, TableKind::Local, nphi, nodes, bands)?;
        let env_table = storage_buffer(
            gpu,
            states,
            "hf environment wedge table",
            bytemuck::cast_slice(&env_t.to_f32()),
        )?;
        let local_table = storage_buffer(
            gpu,
            states,
            "hf local wedge table",
            bytemuck::cast_slice(&local_t.to_f32()),
        )?;
        let entries = product_entries(settings.bands)?;
        let product = storage_buffer(gpu, states, "hf SH product", bytemuck::cast_slice(&entries))?;
        let out = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let env_radiance =
            gpu.create_image(&ImageDesc::new_2d("hf environment radiance", RGBA32F, res, res).usage(out))?;
        // At least two layers, so that the accumulation's whole-image view is an array view.
        let light_radiance = gpu.create_image(
            &ImageDesc::new_2d("hf light radiance", RGBA32F, res, res)
                .layers(light_layers(inputs.lights.len()))
                .usage(out),
        )?;
        let shading = gpu.create_image(&ImageDesc::new_2d("hf shading", RGBA32F, res, res).usage(out))?;
        let (pipelines, hardware_bilinear) = create_pipelines(gpu, shaders, &settings)?;
        let nearest = gpu.sampler(SamplerDesc::NEAREST_CLAMP)?;
        let linear = gpu.sampler(SamplerDesc::LINEAR_CLAMP)?;
        Ok(HeightfieldGpu {
            settings,
            inputs,
            res,
            levels,
            level_sizes,
            origin,
            spacing,
            heights: h.heights,
            source_image: h.source_image,
            image_size: h.image_size,
            decimated: h.decimated,
            pyramid: h.pyramid,
            env_image,
            env_sh,
            env_table,
            local_table,
            product,
            product_count: entries.len() as u32,
            bounds: h.bounds,
            env_radiance,
            light_radiance,
            shading,
            nearest,
            linear,
            height_sampler: if hardware_bilinear { linear } else { nearest },
            pipelines,
        })
    }

    /// The generator's parameters at time `t`.
    pub fn gen_params(&self, t: f32) -> GenParams {
        let mut g = GenParams::new(&self.inputs.source, self.res, self.image_size);
        g.motion[3] = t;
        g
    }

    /// The lighting passes' uniform block, for `light` (or the environment).
    pub fn pass_params(&self, light: Option<&SphereLight>) -> PassParams {
        let s = &self.settings;
        let nphi = s.nphi as usize;
        let mut dirs = Vec::with_capacity(nphi);
        let mut rot = Vec::with_capacity(nphi * 3);
        for j in 0..nphi {
            let phi = std::f64::consts::TAU * j as f64 / nphi as f64;
            dirs.push([phi.cos() as f32, phi.sin() as f32, phi as f32, 0.0]);
            let cs = |m: f64| [(m * phi).cos() as f32, (m * phi).sin() as f32];
            let (a, b, c, d, e) = (cs(1.0), cs(2.0), cs(3.0), cs(4.0), cs(5.0));
            rot.push([a[0], a[1], b[0], b[1]]);
            rot.push([c[0], c[1], d[0], d[1]]);
            rot.push([e[0], e[1], 0.0, 0.0]);
        }
        let samples = (0..self.levels)
            .map(|i| {
                let d = pyramid::sample_distance(s.ls, i);
                [
                    d as f32,
                    (1.0 / d) as f32,
                    pyramid::sample_level(i, s.ls, s.lo, self.levels) as f32,
                    0.0,
                ]
            })
            .collect();
        let base = self.inputs.translation.y;
        let (light_pos, light_radiance) = match light {
            Some(l) => (l.center.extend(l.radius).into(), l.radiance.extend(base).into()),
            None => ([0.0; 4], [0.0, 0.0, 0.0, base]),
        };
        let mut window = [[1.0f32; 4]; 2];
        for (l, f) in s.window_factors().into_iter().enumerate().take(8) {
            window[l / 4][l % 4] = f;
        }
        PassParams {
            dims: [self.res as i32, self.levels as i32, s.nphi as i32, s.bands as i32],
            cfg: [
                s.table_size as i32,
                (s.mode == Mode::Corrected) as i32,
                self.product_count as i32,
                s.ls as i32,
            ],
            grid: [self.spacing, self.origin.x, self.origin.y, 1.0 / self.spacing],
            horizon: [s.lo, std::f32::consts::LN_2 / s.ls as f32, s.march_step, s.max_distance],
            light_pos,
            light_radiance,
            window,
            dirs,
            rot,
            samples,
        }
    }

    /// The passes that turn time `t` into [`HeightfieldGpu::shading`].
    // long: the frame's compute passes in their order, one graph recipe.
    pub fn add_compute_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, t: f32) -> Result<()> {
        let res = self.res;
        let p = &self.pipelines;
        let gen = self.gen_params(t);
        graph
            .pass("hf height update")
            .sample(
                "source_image",
                self.source_image,
                SubresourceRange::mip(0),
                self.nearest,
                COMPUTE,
            )
            .storage_write("heights_out", self.heights, SubresourceRange::mip(0), COMPUTE)
            .record(move |ctx| {
                ctx.rec.bind_pipeline(p.height)?;
                ctx.bind(&[("gen", Bind::UniformData(bytemuck::bytes_of(&gen)))])?;
                ctx.rec.dispatch([res, res, 1])
            });
        self.add_horizon_inputs(graph);
        let has_env = !matches!(self.inputs.environment, EnvInput::None);
        match &self.inputs.environment {
            EnvInput::None => {}
            EnvInput::Constant(c) => {
                // Exact and free: a constant sky is c_00 = 2√π·L alone, no quadrature.
                let mut push = [0u8; 20];
                push[..12].copy_from_slice(bytemuck::cast_slice(&c.to_array()));
                push[16..20].copy_from_slice(&(self.settings.bands as i32).to_le_bytes());
                graph
                    .pass("hf environment SH")
                    .buffer(self.env_sh, Access::StorageWrite { stages: COMPUTE }, Some("env_sh"))
                    .record(move |ctx| {
                        ctx.rec.bind_pipeline(p.env_sh)?;
                        ctx.bind(&[])?;
                        ctx.rec.push_constants(&push)?;
                        ctx.rec.dispatch([64, 1, 1])
                    });
            }
            EnvInput::Map { .. } | EnvInput::Cube { .. } => {
                p.env_project.add_passes(
                    graph,
                    "hf environment SH",
                    self.env_image,
                    self.settings.bands,
                    self.env_sh,
                )?;
            }
        }
        if has_env {
            let params = self.pass_params(None).bytes();
            let pass = self
                .lighting_pass(graph, "hf environment", Some(self.env_table))
                .buffer(self.env_sh, Access::StorageRead { stages: COMPUTE }, Some("env_sh"))
                .storage_write("out_radiance", self.env_radiance, SubresourceRange::mip(0), COMPUTE);
            pass.record(move |ctx| {
                ctx.rec.bind_pipeline(p.env)?;
                ctx.bind(&[("params", Bind::UniformData(&params))])?;
                ctx.rec.dispatch([res, res, 1])
            });
        }
        for (k, light) in self.inputs.lights.iter().enumerate() {
            let params = self.pass_params(Some(light)).bytes();
            let name = format!("hf light {}", k + 1);
            self.lighting_pass(graph, &name, Some(self.local_table))
                .storage_write(
                    "out_radiance",
                    self.light_radiance,
                    SubresourceRange::mip_layer(0, k as u32),
                    COMPUTE,
                )
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(p.light)?;
                    ctx.bind(&[("params", Bind::UniformData(&params))])?;
                    ctx.rec.dispatch([res, res, 1])
                });
        }
        let layers = light_layers(self.inputs.lights.len());
        let mut push = [0u8; 12];
        push[..4].copy_from_slice(&(res as i32).to_le_bytes());
        push[4..8].copy_from_slice(&(has_env as i32).to_le_bytes());
        push[8..12].copy_from_slice(&(self.inputs.lights.len() as i32).to_le_bytes());
        graph
            .pass("hf accumulate")
            .sample(
                "env_radiance",
                self.env_radiance,
                SubresourceRange::mip(0),
                self.nearest,
                COMPUTE,
            )
            .sample(
                "light_radiance",
                self.light_radiance,
                SubresourceRange::new(0, 1, 0, layers),
                self.nearest,
                COMPUTE,
            )
            .storage_write("shading", self.shading, SubresourceRange::mip(0), COMPUTE)
            .record(move |ctx| {
                ctx.rec.bind_pipeline(p.accumulate)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(&push)?;
                ctx.rec.dispatch([res, res, 1])
            });
        Ok(())
    }

    /// The pyramid (decimation + reconstruction) or the brute force's bounds.
    fn add_horizon_inputs<'a>(&'a self, graph: &mut RenderGraph<'a>) {
        let res = self.res;
        let p = &self.pipelines;
        let (Some(dec), Some(pyr)) = (self.decimated, self.pyramid) else {
            if let Some(bounds) = self.bounds {
                graph
                    .pass("hf bounds")
                    .sample("heights", self.heights, SubresourceRange::mip(0), self.nearest, COMPUTE)
                    .buffer(bounds, Access::StorageWrite { stages: COMPUTE }, Some("bounds"))
                    .record(move |ctx| {
                        ctx.rec.bind_pipeline(p.bounds)?;
                        ctx.bind(&[])?;
                        ctx.rec.dispatch([256, 1, 1])
                    });
            }
            return;
        };
        let filter = match self.settings.decimation {
            Decimation::Bilinear => 0i32,
            Decimation::Bicubic => 1,
        };
        for k in 0..self.levels {
            let (src, src_range, src_size, kind) = if k == 0 {
                (self.heights, SubresourceRange::mip(0), res, 2)
            } else {
                (
                    dec,
                    SubresourceRange::mip_layer(0, k - 1),
                    self.level_sizes[k as usize - 1],
                    filter,
                )
            };
            let dst_size = self.level_sizes[k as usize];
            let mut push = [0u8; 12];
            push[..4].copy_from_slice(&(src_size as i32).to_le_bytes());
            push[4..8].copy_from_slice(&(dst_size as i32).to_le_bytes());
            push[8..12].copy_from_slice(&kind.to_le_bytes());
            let name = if k == 0 {
                "hf pyramid level 0".to_string()
            } else {
                format!("hf pyramid decimate {k}")
            };
            graph
                .pass(&name)
                .sample("src", src, src_range, self.nearest, COMPUTE)
                .storage_write("dst", dec, SubresourceRange::mip_layer(0, k), COMPUTE)
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(p.decimate)?;
                    ctx.bind(&[])?;
                    ctx.rec.push_constants(&push)?;
                    ctx.rec.dispatch([dst_size, dst_size, 1])
                });
        }
        let levels = self.levels;
        let mut sizes = vec![0u8; 16 * MAX_LEVELS as usize];
        for (k, s) in self.level_sizes.iter().enumerate() {
            sizes[16 * k..16 * k + 4].copy_from_slice(&(*s as i32).to_le_bytes());
        }
        let mut push = [0u8; 12];
        push[..4].copy_from_slice(&(res as i32).to_le_bytes());
        push[4..8].copy_from_slice(&(levels as i32).to_le_bytes());
        push[8..12].copy_from_slice(&((self.settings.mode == Mode::Corrected) as i32).to_le_bytes());
        graph
            .pass("hf pyramid reconstruct")
            .sample(
                "levels",
                dec,
                SubresourceRange::new(0, 1, 0, levels),
                self.nearest,
                COMPUTE,
            )
            .storage_write("pyramid_out", pyr, SubresourceRange::new(0, 1, 0, levels), COMPUTE)
            .record(move |ctx| {
                ctx.rec.bind_pipeline(p.reconstruct)?;
                ctx.bind(&[("sizes", Bind::UniformData(&sizes))])?;
                ctx.rec.push_constants(&push)?;
                ctx.rec.dispatch([res, res, levels])
            });
    }

    /// A lighting pass (environment, light or horizon kernel) with the inputs every one reads.
    /// `table`: the wedge table (with the product list); `None` for the horizon kernel.
    fn lighting_pass<'g, 'a>(
        &'a self,
        graph: &'g mut RenderGraph<'a>,
        name: &str,
        table: Option<BufferId>,
    ) -> crate::graph::PassBuilder<'g, 'a> {
        let mut pass = graph.pass(name).sample(
            "heights",
            self.heights,
            SubresourceRange::mip(0),
            self.height_sampler,
            COMPUTE,
        );
        if let Some(table) = table {
            pass = pass
                .buffer(table, Access::StorageRead { stages: COMPUTE }, Some("wedge"))
                .buffer(self.product, Access::StorageRead { stages: COMPUTE }, Some("product"));
        }
        if let Some(pyr) = self.pyramid {
            pass = pass.sample(
                "pyramid",
                pyr,
                SubresourceRange::new(0, 1, 0, self.levels),
                self.height_sampler,
                COMPUTE,
            );
        }
        if let Some(b) = self.bounds {
            pass = pass.buffer(b, Access::StorageRead { stages: COMPUTE }, Some("bounds"));
        }
        pass
    }

    /// A pass writing every texel's horizon angles (radians) in every direction into `out`
    /// (`nphi·res²` floats, direction-major): the environment's, or `light`'s (truncated).
    pub fn add_horizon_pass<'a>(&'a self, graph: &mut RenderGraph<'a>, out: BufferId, light: Option<usize>) {
        let res = self.res;
        let p = &self.pipelines;
        let params = self.pass_params(light.and_then(|k| self.inputs.lights.get(k))).bytes();
        let flag = light.is_some() as i32;
        self.lighting_pass(graph, "hf horizons", None)
            .buffer(out, Access::StorageWrite { stages: COMPUTE }, Some("horizons"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(p.horizon)?;
                ctx.bind(&[("params", Bind::UniformData(&params))])?;
                ctx.rec.push_constants(&flag.to_le_bytes())?;
                ctx.rec.dispatch([res, res, 1])
            });
    }
}
