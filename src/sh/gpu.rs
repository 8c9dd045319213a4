//! The SH projection of environment images as a compute pass: [`ShProjector`] adds two
//! dispatches to a frame graph — per-workgroup partial sums of `L(ω_t)·Ω_t·y_i(ω_t)` over the
//! texels (`glsl/sh/project_equirect.comp` or `project_cube.comp`), then a reduction of the
//! partial sums in a fixed order (`glsl/sh/project_reduce.comp`). Same directions, exact texel
//! solid angles and SH frame as [`project_equirect`](super::project_equirect) and
//! [`project_cubemap`](super::project_cubemap), which are its CPU twins.

use crate::backend::{
    vk, BufferDesc, BufferId, ComputePipelineDesc, Gpu, ImageId, MemoryKind, PipelineId, SamplerDesc, SamplerId,
    SubresourceRange,
};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph};
use crate::shaders::ShaderLibrary;

/// Most bands the GPU projection evaluates (`SH_MAX_BANDS` in `glsl/common/sh.glsl`).
pub const GPU_PROJECTION_MAX_BANDS: u32 = super::GLSL_MAX_BANDS as u32;
/// Most workgroups of the first dispatch: the partial-sum buffer holds this many × 64 vec4s.
const MAX_GROUPS: u32 = 256;
/// Texels a workgroup sums (16 per thread) unless that would need more than [`MAX_GROUPS`].
const TEXELS_PER_GROUP: u32 = 1024;
/// Threads per workgroup of every projection shader; also the partial-sum stride.
const GROUP_SIZE: u32 = 64;
/// Largest image the projection takes, texels (keeps every index in the shaders' `int`).
const MAX_TEXELS: u64 = 1 << 30;

const COMPUTE: vk::PipelineStageFlags2 = vk::PipelineStageFlags2::COMPUTE_SHADER;

/// How an environment image's texels map to directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvLayout {
    /// A 2D image in penumbra's equirectangular mapping (`scene::Environment::equirect_uv`).
    Equirect,
    /// A cube image (six layers in Vulkan face order, sampled through a cube view).
    Cube,
}

/// An environment image to project: its layout and mip-0 size (cube: the face size, twice).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnvImage {
    pub image: ImageId,
    pub layout: EnvLayout,
    pub width: u32,
    pub height: u32,
}

impl EnvImage {
    /// The layout from the image itself: a cube image (6 layers) is a cube map, a one-layer 2D
    /// image an equirectangular map; anything else is an error.
    pub fn of(gpu: &Gpu, image: ImageId) -> Result<EnvImage> {
        let d = gpu.image_desc(image)?;
        let layout = match (d.cube, d.layers, d.is_3d()) {
            (true, 6, false) => EnvLayout::Cube,
            (false, 1, false) => EnvLayout::Equirect,
            _ => {
                return Err(Error::Usage(format!(
                    "SH projection of `{}`: needs a 2D equirectangular image or a cube image, not {} layer(s){}",
                    d.name,
                    d.layers,
                    if d.is_3d() { " of a 3D image" } else { "" }
                )))
            }
        };
        let e = d.mip_extent(0);
        Ok(EnvImage {
            image,
            layout,
            width: e.width,
            height: e.height,
        })
    }

    fn texels(&self) -> u64 {
        let n = self.width as u64 * self.height as u64;
        match self.layout {
            EnvLayout::Equirect => n,
            EnvLayout::Cube => 6 * n,
        }
    }
}

/// The projection's pipelines, sampler and partial-sum buffer; one per user (the buffer is
/// written by every projection it records, so two projections in one graph are serialised by
/// the graph's barriers, not corrupted).
pub struct ShProjector {
    equirect: PipelineId,
    cube: PipelineId,
    reduce: PipelineId,
    nearest: SamplerId,
    partials: BufferId,
}

impl ShProjector {
    pub fn new(gpu: &mut Gpu, shaders: &ShaderLibrary, name: &str) -> Result<ShProjector> {
        let mut pipeline = |suffix: &str, shader: &str| {
            gpu.create_compute_pipeline(
                &ComputePipelineDesc {
                    name: format!("{name} {suffix}"),
                    shader: shader.into(),
                    specialization: vec![],
                },
                shaders,
            )
        };
        let equirect = pipeline("equirect", "sh/project_equirect.comp")?;
        let cube = pipeline("cube", "sh/project_cube.comp")?;
        let reduce = pipeline("reduce", "sh/project_reduce.comp")?;
        let nearest = gpu.sampler(SamplerDesc::NEAREST_CLAMP)?;
        let partials = gpu.create_buffer(&BufferDesc {
            name: format!("{name} partial sums"),
            size: MAX_GROUPS as u64 * GROUP_SIZE as u64 * 16,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuOnly,
        })?;
        Ok(ShProjector {
            equirect,
            cube,
            reduce,
            nearest,
            partials,
        })
    }

    /// Adds the passes `name` (partial sums) and `"{name} reduce"` that project mip 0 of `env`
    /// onto `bands` bands and write `out[k] = (r, g, b, 0)` for k < bands² (the coefficient
    /// `∫ L y_k dω` in the SH frame); `out` needs room for bands² vec4s and storage usage.
    pub fn add_passes<'a>(
        &self,
        graph: &mut RenderGraph<'a>,
        name: &str,
        env: EnvImage,
        bands: u32,
        out: BufferId,
    ) -> Result<()> {
        if !(1..=GPU_PROJECTION_MAX_BANDS).contains(&bands) {
            return Err(Error::Usage(format!(
                "SH projection `{name}`: {bands} bands is outside 1..={GPU_PROJECTION_MAX_BANDS}"
            )));
        }
        let texels = env.texels();
        if env.width == 0
            || env.height == 0
            || texels > MAX_TEXELS
            || (env.layout == EnvLayout::Cube && env.width != env.height)
        {
            return Err(Error::Usage(format!("SH projection `{name}`: a {}x{} {:?} image cannot be projected (non-empty, square cube faces, at most 2^30 texels)", env.width, env.height, env.layout)));
        }
        let per_group = (texels.div_ceil(MAX_GROUPS as u64) as u32).max(TEXELS_PER_GROUP);
        let groups = texels.div_ceil(per_group as u64) as u32;
        let push: [i32; 4] = [env.width as i32, env.height as i32, bands as i32, per_group as i32];
        let (pipeline, range) = match env.layout {
            EnvLayout::Equirect => (self.equirect, SubresourceRange::mip(0)),
            EnvLayout::Cube => (self.cube, SubresourceRange::new(0, 1, 0, 6)),
        };
        let partials = self.partials;
        graph
            .pass(name)
            .sample("env_image", env.image, range, self.nearest, COMPUTE)
            .buffer(partials, Access::StorageWrite { stages: COMPUTE }, Some("partials"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::cast_slice(&push))?;
                ctx.rec.dispatch([groups * GROUP_SIZE, 1, 1])
            });
        let reduce = self.reduce;
        let push: [i32; 4] = [groups as i32, bands as i32, 0, 0];
        graph
            .pass(&format!("{name} reduce"))
            .buffer(partials, Access::StorageRead { stages: COMPUTE }, Some("partials"))
            .buffer(out, Access::StorageWrite { stages: COMPUTE }, Some("sh_out"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(reduce)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::cast_slice(&push))?;
                ctx.rec.dispatch([GROUP_SIZE, 1, 1])
            });
        Ok(())
    }
}
