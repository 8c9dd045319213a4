//! The passes the renderer owns around the methods: the background (targets cleared, the sky)
//! and, for configurations without a base term, the scene's depth.

use crate::backend::{
    vk, Bind, ColorTarget, DepthState, Gpu, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc, SamplerDesc,
    SamplerId, SubresourceRange,
};
use crate::error::Result;
use crate::gpu_scene::{record_draws, vertex_layout, DrawCall, SceneGpu};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{FrameTargets, FrameUniforms, RADIANCE_FORMAT};
use crate::shaders::ShaderLibrary;

pub struct FramePasses {
    sky: PipelineId,
    sky_sampler: SamplerId,
    depth: PipelineId,
}

impl FramePasses {
    pub fn new(gpu: &mut Gpu, shaders: &ShaderLibrary) -> Result<FramePasses> {
        let ds_format = gpu.caps().depth_stencil_format;
        let mut sky = GraphicsPipelineDesc::new("sky", "frame/sky.vert", Some("frame/sky.frag"));
        sky.raster.cull = vk::CullModeFlags::NONE;
        sky.depth = DepthState {
            test: true,
            write: false,
            compare: vk::CompareOp::LESS_OR_EQUAL,
        };
        sky.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        sky.depth_format = Some(ds_format);
        let sky = gpu.create_graphics_pipeline(&sky, shaders)?;
        let mut depth = GraphicsPipelineDesc::new("scene depth", "frame/depth.vert", None);
        depth.vertex_layout = vertex_layout();
        // Thin surfaces (planes, leaves) are seen from both sides, as every method draws them.
        depth.raster.cull = vk::CullModeFlags::NONE;
        depth.depth_format = Some(ds_format);
        let depth = gpu.create_graphics_pipeline(&depth, shaders)?;
        Ok(FramePasses {
            sky,
            sky_sampler: gpu.sampler(SamplerDesc::NEAREST_CLAMP)?,
            depth,
        })
    }

    /// Clears radiance to black, depth to 1 and stencil to 0; with `sky`, draws the environment
    /// over the whole target (nearest texel, as the reference looks it up).
    pub fn add_background<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        scene: &'a SceneGpu,
        t: FrameTargets,
        uniforms: &FrameUniforms,
        sky: bool,
    ) {
        let env = scene.environment.map;
        let cube = scene.environment.cube as u32;
        let inverse = glam::Mat4::from_cols_array(&uniforms.view_proj).inverse();
        let mut pass = graph
            .pass("background")
            .color_attachment(t.radiance, SubresourceRange::mip(0), true)
            .depth_stencil_write(t.depth_stencil, true);
        if sky {
            pass = pass.sample(
                "environment_map",
                env,
                SubresourceRange::mip(0),
                self.sky_sampler,
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
            );
        }
        pass.record(move |ctx| {
            let _ = ctx.rec.begin_rendering(&RenderingDesc {
                colors: vec![RenderTarget::clear_color(t.radiance, [0.0, 0.0, 0.0, 1.0])],
                depth_stencil: Some(RenderTarget::clear_depth(t.depth_stencil, 1.0, 0)),
            })?;
            if sky {
                ctx.rec.bind_pipeline(self.sky)?;
                ctx.bind(&[])?;
                let mut push = [0u8; 68];
                push[..64].copy_from_slice(bytemuck::bytes_of(&inverse.to_cols_array()));
                push[64..].copy_from_slice(&cube.to_le_bytes());
                ctx.rec.push_constants(&push)?;
                ctx.rec.draw(3, 1)?;
            }
            ctx.rec.end_rendering();
            Ok(())
        });
    }

    /// Every scene draw into the depth buffer, at its placement.
    pub fn add_depth<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        scene: &'a SceneGpu,
        t: FrameTargets,
        uniforms: &FrameUniforms,
    ) {
        let uniforms = *uniforms;
        graph
            .pass("scene depth")
            .depth_stencil_write(t.depth_stencil, false)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: Vec::new(),
                    depth_stencil: Some(RenderTarget::load(t.depth_stencil)),
                })?;
                ctx.rec.bind_pipeline(self.depth)?;
                let calls: Vec<DrawCall> = scene.draws.iter().map(DrawCall::whole).collect();
                record_draws(ctx, scene, &calls, |ctx, _| {
                    ctx.bind(&[("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms)))])
                })?;
                ctx.rec.end_rendering();
                Ok(())
            });
    }
}
