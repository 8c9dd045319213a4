//! The wind pass (Dickson et al. 2011, digest §6.1): before any method draws a frame, each windy object's
//! vertices in the scene's vertex buffer are recomputed from its rest pose at the frame's time
//! (`glsl/frame/wind.comp`; the formula and its CPU twin, which the reference path tracer uses, in
//! `src/scene/motion.rs`). Every pass that draws the scene's vertex buffer — every method's
//! surfaces, the LPV's RSM and surfels, the renderer's depth — then sees the same moved geometry.

use bytemuck::{Pod, Zeroable};

use crate::backend::{vk, BufferId, ComputePipelineDesc, Gpu, PipelineId};
use crate::error::{Error, Result};
use crate::gpu_scene::{vertices_of, SceneGpu};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::scene::motion::{wind_weights, Wind};
use crate::scene::Scene;
use crate::shaders::ShaderLibrary;

/// `Wind` push constants of glsl/frame/wind.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct WindPush {
    time: f32,
    amplitude: f32,
    rate: f32,
    unit: f32,
    first: u32,
    count: u32,
}

struct WindObject {
    /// The rest pose's vertices (12 floats each) and their weights.
    rest: BufferId,
    weights: BufferId,
    first: u32,
    count: u32,
    wind: Wind,
}

pub struct WindPass {
    pipeline: PipelineId,
    objects: Vec<WindObject>,
}

impl WindPass {
    /// `None` when no object has wind.
    pub fn new(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        shaders: &ShaderLibrary,
        scene: &Scene,
        scene_gpu: &SceneGpu,
    ) -> Result<Option<WindPass>> {
        let mut objects = Vec::new();
        for (item, mesh) in scene_gpu.draws.iter().zip(&scene_gpu.meshes) {
            let Some(object) = item.object.and_then(|o| scene.objects.get(o)) else {
                continue;
            };
            let Some(wind) = object.wind else { continue };
            if mesh.positions.is_empty() {
                continue;
            }
            let map = scene.material_of(object).and_then(|m| m.albedo_map.as_deref());
            let weights = wind_weights(mesh, map).map_err(|e| {
                Error::Usage(format!(
                    "{}: object {:?}: wind: albedo_map: {e}",
                    scene.source, object.name
                ))
            })?;
            let rest = gpu.create_storage_buffer(
                &format!("{} rest pose", object.name),
                bytemuck::cast_slice(&vertices_of(mesh)),
            )?;
            let weights =
                gpu.create_storage_buffer(&format!("{} wind weights", object.name), bytemuck::cast_slice(&weights))?;
            states.forget_buffer(rest);
            states.forget_buffer(weights);
            objects.push(WindObject {
                rest,
                weights,
                first: item.vertex_offset as u32,
                count: mesh.positions.len() as u32,
                wind,
            });
        }
        if objects.is_empty() {
            return Ok(None);
        }
        let pipeline = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "wind".into(),
                shader: "frame/wind.comp".into(),
                specialization: Vec::new(),
            },
            shaders,
        )?;
        Ok(Some(WindPass { pipeline, objects }))
    }

    /// One dispatch per windy object, writing the scene's vertex buffer at `time_s`.
    pub fn add<'a>(&'a self, graph: &mut RenderGraph<'a>, scene: &'a SceneGpu, time_s: f32) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        for (k, o) in self.objects.iter().enumerate() {
            let push = WindPush {
                time: time_s,
                amplitude: o.wind.amplitude,
                rate: o.wind.rate,
                unit: o.wind.unit,
                first: o.first,
                count: o.count,
            };
            graph
                .pass(&format!("wind {k}"))
                .buffer(o.rest, Access::StorageRead { stages: compute }, Some("rest"))
                .buffer(o.weights, Access::StorageRead { stages: compute }, Some("weights"))
                .buffer(
                    scene.vertices,
                    Access::StorageWrite { stages: compute },
                    Some("vertices"),
                )
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(self.pipeline)?;
                    ctx.bind(&[])?;
                    ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                    ctx.rec.dispatch([push.count, 1, 1])
                });
        }
    }
}
