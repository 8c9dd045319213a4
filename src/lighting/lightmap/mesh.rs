//! The static triangles with their light-map coordinates, drawn by every light-mapped base term
//! (radiosity's light-maps, SH light-maps) through glsl/lightmap/mesh.vert.

use glam::Vec3;

use crate::backend::{
    vk, Bind, BufferId, ColorTarget, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc, SubresourceRange,
    VertexAttribute, VertexLayout,
};
use crate::error::Result;
use crate::gpu_scene::DrawPush;
use crate::graph::{Access, PassBuilder, RenderGraph};
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::lighting::{CreateContext, FrameContext};

/// `LightmapVertex` of glsl/lightmap/mesh.vert (object space: the draw's model matrix is
/// pushed, so the depth is the one every other method computes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct LightmapVertex {
    position: [f32; 3],
    normal: [f32; 3],
    lightmap_uv: [f32; 2],
    uv: [f32; 2],
}

/// The static triangles with their light-map coordinates, and the entities without: what a
/// light-mapped base term draws (radiosity's light-maps and SH light-maps alike).
pub struct Mesh {
    vertices: BufferId,
    /// (scene draw, first vertex, vertex count).
    draws: Vec<(usize, u32, u32)>,
    /// Per entry of `draws`: an entity's animation (placed at the frame clock's time, as the
    /// direct methods place it).
    animations: Vec<Option<crate::scene::Animation>>,
    /// Where the light-map's triangles were cut along thin walls: the scene's own triangles,
    /// drawn into a cleared depth buffer after the shading, so that the depth the later terms
    /// test against is the one they compute (the cut pieces' differs from it by rounding, and
    /// a term drawn over it would lose those pixels).
    depth: Option<DepthLayer>,
}

/// The uncut triangles and the depth-only pipeline that draws them.
struct DepthLayer {
    vertices: BufferId,
    draws: Vec<(usize, u32, u32)>,
    animations: Vec<Option<crate::scene::Animation>>,
    pipeline: PipelineId,
}

impl Mesh {
    /// `uvs`: 6 floats per triangle of `geometry` (its corners' light-map coordinates).
    /// `uncut`: the geometry before the cut along thin walls, where there was one.
    pub fn new(
        cx: &mut CreateContext<'_>,
        geometry: &StaticGeometry,
        uvs: &[f32],
        method: &str,
        uncut: Option<&StaticGeometry>,
    ) -> Result<Mesh> {
        let (vertices, draws, animations) = upload(cx, geometry, uvs, &format!("{method} vertices"))?;
        let depth = match uncut.filter(|u| u.triangles.len() != geometry.triangles.len()) {
            Some(u) => {
                let none = vec![-1.0; 6 * u.triangles.len()];
                let (vertices, draws, animations) = upload(cx, u, &none, &format!("{method} depth vertices"))?;
                let mut desc = Mesh::pipeline_desc(&format!("{method} light-map depth"), "");
                desc.fragment = None;
                desc.raster.cull = vk::CullModeFlags::NONE;
                desc.color_targets = vec![ColorTarget {
                    write_mask: vk::ColorComponentFlags::empty(),
                    ..ColorTarget::new(crate::lighting::RADIANCE_FORMAT)
                }];
                desc.depth_format = Some(cx.gpu.caps().depth_stencil_format);
                let pipeline = cx.gpu.create_graphics_pipeline(&desc, cx.shaders)?;
                Some(DepthLayer {
                    vertices,
                    draws,
                    animations,
                    pipeline,
                })
            }
            None => None,
        };
        Ok(Mesh {
            vertices,
            draws,
            animations,
            depth,
        })
    }

    /// A pipeline drawing the mesh with `fragment` (and glsl/lightmap/mesh.vert) into the
    /// radiance target, depth tested and written.
    pub fn pipeline_desc(name: &str, fragment: &str) -> GraphicsPipelineDesc {
        let attr = |location, format, offset| VertexAttribute {
            location,
            binding: 0,
            format,
            offset,
        };
        let mut desc = GraphicsPipelineDesc::new(name, "lightmap/mesh.vert", Some(fragment));
        desc.vertex_layout = VertexLayout {
            buffers: vec![(0, std::mem::size_of::<LightmapVertex>() as u32)],
            attributes: vec![
                attr(0, vk::Format::R32G32B32_SFLOAT, 0),
                attr(1, vk::Format::R32G32B32_SFLOAT, 12),
                attr(2, vk::Format::R32G32_SFLOAT, 24),
                attr(3, vk::Format::R32G32_SFLOAT, 32),
            ],
        };
        desc
    }

    /// Where the mesh is cut: a pass, after the shading, that clears depth and stencil (to the
    /// background's 1 and 0) and draws the uncut triangles into depth.
    pub fn add_depth_pass<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) {
        let Some(d) = &self.depth else { return };
        let (scene, t, uniforms, time) = (frame.scene, frame.targets, frame.uniforms, frame.clock.time_s);
        graph
            .pass("light-map depth")
            .color_attachment(t.radiance, SubresourceRange::mip(0), false)
            .depth_stencil_write(t.depth_stencil, true)
            .buffer(d.vertices, Access::VertexRead, None)
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::load(t.radiance)],
                    depth_stencil: Some(RenderTarget::clear_depth(t.depth_stencil, 1.0, 0)),
                })?;
                ctx.rec.bind_pipeline(d.pipeline)?;
                ctx.rec.bind_vertex_buffers(&[(d.vertices, 0)])?;
                for (&(draw, first, count), animation) in d.draws.iter().zip(&d.animations) {
                    let item = &scene.draws[draw];
                    let model = placed(item.model, animation.as_ref(), time);
                    ctx.bind(&[("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms)))])?;
                    ctx.rec.push_constants(DrawPush::new(model, item.material).bytes())?;
                    ctx.rec.draw_from(count, first)?;
                }
                ctx.rec.end_rendering();
                Ok(())
            });
    }

    /// Records `pass` (which declares the method's own images) drawing every draw with
    /// `pipeline`; `extra` is bound with each draw's frame, albedo and normal maps.
    pub fn draw<'a>(
        &'a self,
        pass: PassBuilder<'_, 'a>,
        frame: &FrameContext<'a>,
        pipeline: PipelineId,
        extra: Vec<(&'static str, Vec<u8>)>,
    ) {
        let (scene, t, uniforms, time) = (frame.scene, frame.targets, frame.uniforms, frame.clock.time_s);
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let pass = pass
            .color_attachment(t.radiance, SubresourceRange::mip(0), false)
            .depth_stencil_write(t.depth_stencil, false)
            .buffer(self.vertices, Access::VertexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"));
        pass.record(move |ctx| {
            let _ = ctx.rec.begin_rendering(&RenderingDesc {
                colors: vec![RenderTarget::load(t.radiance)],
                depth_stencil: Some(RenderTarget::load(t.depth_stencil)),
            })?;
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.rec.bind_vertex_buffers(&[(self.vertices, 0)])?;
            for (&(d, first, count), animation) in self.draws.iter().zip(&self.animations) {
                let item = &scene.draws[d];
                let model = placed(item.model, animation.as_ref(), time);
                let maps = scene.material_maps[item.material as usize];
                let mut binds = vec![
                    ("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms))),
                    (
                        "albedo_map",
                        Bind::Sampled {
                            image: maps.albedo,
                            range: SubresourceRange::mip(0),
                            sampler: scene.sampler,
                        },
                    ),
                    (
                        "normal_map",
                        Bind::Sampled {
                            image: maps.normal,
                            range: SubresourceRange::mip(0),
                            sampler: scene.sampler,
                        },
                    ),
                ];
                binds.extend(extra.iter().map(|(name, bytes)| (*name, Bind::UniformData(bytes))));
                ctx.bind(&binds)?;
                ctx.rec.push_constants(DrawPush::new(model, item.material).bytes())?;
                ctx.rec.draw_from(count, first)?;
            }
            ctx.rec.end_rendering();
            Ok(())
        });
    }
}

/// A draw's model matrix at time `time`: its animation's placement, if it has one.
fn placed(model: glam::Mat4, animation: Option<&crate::scene::Animation>, time: f32) -> glam::Mat4 {
    animation.map_or(model, |a| a.transform_at(model, time))
}

/// A vertex buffer, (scene draw, first vertex, count) per draw, and each draw's animation.
type Uploaded = (BufferId, Vec<(usize, u32, u32)>, Vec<Option<crate::scene::Animation>>);

/// The draws' vertices of `geometry` (light-map coordinates `uvs`, 6 per triangle) and of the
/// scene's entities, in a vertex buffer named `name`.
fn upload(cx: &mut CreateContext<'_>, geometry: &StaticGeometry, uvs: &[f32], name: &str) -> Result<Uploaded> {
    // Vertices grouped by scene draw (static_geometry emits them in draw order).
    let mut vertices = Vec::with_capacity(3 * geometry.triangles.len());
    let mut draws: Vec<(usize, u32, u32)> = Vec::new();
    for t in 0..geometry.triangles.len() {
        let d = geometry.draw[t];
        match draws.last_mut() {
            Some(last) if last.0 == d => last.2 += 3,
            _ => draws.push((d, vertices.len() as u32, 3)),
        }
        let o = geometry.object_space[t].map(Vec3::from);
        let n = (o[1] - o[0]).cross(o[2] - o[0]).normalize_or_zero().to_array();
        for k in 0..3 {
            vertices.push(LightmapVertex {
                position: o[k].to_array(),
                normal: n,
                lightmap_uv: [uvs[6 * t + 2 * k], uvs[6 * t + 2 * k + 1]],
                uv: geometry.uvs[t][k],
            });
        }
    }
    // Entities: their mesh as it is, outside the light-map (a negative coordinate reads as
    // no light-map light).
    for &d in &geometry.entities {
        let mesh = &cx.scene_gpu.meshes[d];
        let first = vertices.len() as u32;
        for t in mesh.indices.chunks_exact(3) {
            let o = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
            let n = (o[1] - o[0]).cross(o[2] - o[0]).normalize_or_zero().to_array();
            for (k, p) in o.iter().enumerate() {
                vertices.push(LightmapVertex {
                    position: p.to_array(),
                    normal: n,
                    lightmap_uv: [-1.0, -1.0],
                    uv: mesh.uvs.get(t[k] as usize).map_or([0.0; 2], |v| v.to_array()),
                });
            }
        }
        draws.push((d, first, vertices.len() as u32 - first));
    }
    let animations = draws
        .iter()
        .map(|&(d, _, _)| cx.scene_gpu.draws[d].object.and_then(|o| cx.scene.objects[o].animation))
        .collect();
    let vertices = cx.gpu.create_buffer_init(
        name,
        vk::BufferUsageFlags::VERTEX_BUFFER,
        bytemuck::cast_slice(&vertices),
    )?;
    cx.states.forget_buffer(vertices);
    Ok((vertices, draws, animations))
}
