//! Forward direct lighting: Lambert plus energy-normalised Blinn-Phong from point, spot and
//! directional lights, no shadows. One graphics pass writes linear radiance and depth.
//!
//! It is penumbra's first method and the baseline the others are measured against.

pub mod cpu;

use crate::backend::{vk, Bind, ColorTarget, DepthState, Gpu, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc, SamplerDesc, SamplerId, SubresourceRange, VertexAttribute, VertexLayout};
use crate::error::Result;
use crate::graph::{Access, RenderGraph};
use crate::methods::{FrameInputs, LightingMethod};
use crate::renderer::{DrawPush, Vertex, RADIANCE_FORMAT};
use crate::scene::{MethodDecl, MethodSchema};
use crate::shaders::ShaderLibrary;

pub const SCHEMA: MethodSchema = MethodSchema { name: "forward", params: &[] };

/// Forward has no quality settings: one configuration.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    vec![("forward".to_string(), decl.clone())]
}

pub struct Forward {
    pipeline: PipelineId,
    /// The environment behind the geometry.
    sky: PipelineId,
    sky_sampler: SamplerId,
}

/// The vertex layout of [`Vertex`], shared by raster methods.
pub fn vertex_layout() -> VertexLayout {
    let attr = |location, format, offset| VertexAttribute { location, binding: 0, format, offset };
    VertexLayout {
        buffers: vec![(0, std::mem::size_of::<Vertex>() as u32)],
        attributes: vec![attr(0, vk::Format::R32G32B32_SFLOAT, 0), attr(1, vk::Format::R32G32B32_SFLOAT, 12), attr(2, vk::Format::R32G32_SFLOAT, 24), attr(3, vk::Format::R32G32B32A32_SFLOAT, 32)],
    }
}

impl Forward {
    pub fn new(gpu: &mut Gpu, shaders: &ShaderLibrary, _decl: &MethodDecl) -> Result<Self> {
        let mut desc = GraphicsPipelineDesc::new("forward", "forward/forward.vert", Some("forward/forward.frag"));
        desc.vertex_layout = vertex_layout();
        // Thin surfaces (planes, leaves) are seen from both sides.
        desc.raster.cull = vk::CullModeFlags::NONE;
        desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        desc.depth_format = Some(gpu.caps().depth_stencil_format);
        let pipeline = gpu.create_graphics_pipeline(&desc, shaders)?;
        let mut sky = GraphicsPipelineDesc::new("sky", "forward/sky.vert", Some("forward/sky.frag"));
        sky.raster.cull = vk::CullModeFlags::NONE;
        sky.depth = DepthState { test: true, write: false, compare: vk::CompareOp::LESS_OR_EQUAL };
        sky.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        sky.depth_format = Some(gpu.caps().depth_stencil_format);
        let sky = gpu.create_graphics_pipeline(&sky, shaders)?;
        let sky_sampler = gpu.sampler(SamplerDesc::NEAREST_CLAMP)?;
        Ok(Forward { pipeline, sky, sky_sampler })
    }
}

impl LightingMethod for Forward {
    fn name(&self) -> &'static str {
        "forward"
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, inputs: &FrameInputs<'a>) -> Result<()> {
        let scene = inputs.scene;
        let t = inputs.targets;
        let uniforms = inputs.uniforms;
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        graph
            .pass("forward")
            .color_attachment(t.radiance, SubresourceRange::mip(0), true)
            .depth_stencil_write(t.depth_stencil, true)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                let _extent = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::clear_color(t.radiance, [0.0, 0.0, 0.0, 1.0])],
                    depth_stencil: Some(RenderTarget::clear_depth(t.depth_stencil, 1.0, 0)),
                })?;
                ctx.rec.bind_pipeline(self.pipeline)?;
                ctx.rec.bind_vertex_buffers(&[(scene.vertices, 0)])?;
                ctx.rec.bind_index_buffer(scene.indices, 0)?;
                let lights: &[u8] = if scene.lights.is_empty() { &[0u8; 64] } else { bytemuck::cast_slice(&scene.lights) };
                let uniform_bytes = bytemuck::bytes_of(&uniforms);
                let mut bound_material = None;
                for d in &scene.draws {
                    if bound_material != Some(d.material) {
                        let maps = scene.material_maps[d.material as usize];
                        let s = scene.sampler;
                        let whole = SubresourceRange::mip(0);
                        ctx.bind(&[
                            ("frame", Bind::UniformData(uniform_bytes)),
                            ("lights", Bind::StorageData(lights)),
                            ("albedo_map", Bind::Sampled { image: maps.albedo, range: whole, sampler: s }),
                            ("normal_map", Bind::Sampled { image: maps.normal, range: whole, sampler: s }),
                            ("specular_map", Bind::Sampled { image: maps.specular, range: whole, sampler: s }),
                        ])?;
                        bound_material = Some(d.material);
                    }
                    let push = DrawPush { model: d.model.to_cols_array(), material: d.material, _pad: [0; 3] };
                    ctx.rec.push_constants(&bytemuck::bytes_of(&push)[..68])?;
                    ctx.rec.draw_indexed(d.index_count, d.first_index, d.vertex_offset)?;
                }
                // The sky last, on the far plane: it covers only pixels no geometry reached.
                ctx.rec.bind_pipeline(self.sky)?;
                ctx.rec.bind(&[("environment_map", Bind::Sampled { image: scene.environment.map, range: SubresourceRange::mip(0), sampler: self.sky_sampler })])?;
                let inverse = glam::Mat4::from_cols_array(&uniforms.view_proj).inverse();
                let mut push = [0u8; 68];
                push[..64].copy_from_slice(bytemuck::bytes_of(&inverse.to_cols_array()));
                push[64..].copy_from_slice(&(scene.environment.cube as u32).to_le_bytes());
                ctx.rec.push_constants(&push)?;
                ctx.rec.draw(3, 1)?;
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }
}
