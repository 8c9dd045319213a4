//! The frame's passes: entity silhouettes, then per round (opaque, then translucent) the ambient
//! pass and, per light, its stencil volumes and its lighting.

use std::rc::Rc;

use bytemuck::Zeroable;
use glam::Vec4;

use super::plan::{self, FramePlan, LightPlan};
use super::{record_surface, LightBlock, ShadowVolumes, SilhouetteBuffers, SilhouettePush, VolumePush};
use crate::backend::{vk, Bind, RenderTarget, RenderingDesc, SubresourceRange};
use crate::gpu_scene::SceneGpu;
use crate::graph::{Access, RenderGraph};
use crate::lighting::FrameContext;
use crate::world::FaceId;

impl ShadowVolumes {
    /// Light `lp`'s silhouettes of its caster entities, compacted into the one volume buffer,
    /// which its volume pass then draws: one light at a time, so the buffer does not grow with
    /// the lights.
    pub(super) fn add_silhouettes<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        s: &'a SilhouetteBuffers,
        plan: &Rc<FramePlan>,
        lp: &LightPlan,
        scene: &SceneGpu,
        translucent: bool,
    ) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let light: Vec4 = self.homogeneous_light(lp.light, scene);
        let prefix = if translucent { "translucent " } else { "" };
        let (commands, caps_base) = (s.commands, s.caps_base);
        // Two VkDrawIndirectCommand (vertex count, instances, first vertex, first instance).
        graph
            .pass(&format!("light {} {prefix}silhouette counts", lp.light))
            .buffer(commands, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.update_buffer(commands, &[0, 1, 0, 0, 0, 1, caps_base, 0]));
        // The triangles (their facings and caps), then the edges (their sides from those
        // facings): two passes, so the edges read what the triangles wrote.
        for edges_phase in [false, true] {
            let (casters, p) = (lp.caster_entities.clone(), plan.clone());
            let name = if edges_phase { "silhouette edges" } else { "silhouettes" };
            let facings = if edges_phase {
                Access::StorageRead { stages: compute }
            } else {
                Access::StorageWrite { stages: compute }
            };
            graph
                .pass(&format!("light {} {prefix}{name}", lp.light))
                .buffer(s.positions, Access::StorageRead { stages: compute }, Some("positions"))
                .buffer(s.triangles, Access::StorageRead { stages: compute }, Some("triangles"))
                .buffer(s.edges, Access::StorageRead { stages: compute }, Some("edges"))
                .buffer(s.volumes, Access::StorageWrite { stages: compute }, Some("volumes"))
                .buffer(commands, Access::StorageWrite { stages: compute }, Some("commands"))
                .buffer(s.facings, facings, Some("facings"))
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(self.silhouette)?;
                    ctx.bind(&[("light_positions", Bind::StorageData(bytemuck::bytes_of(&light)))])?;
                    for &e in &casters {
                        let (topo, slot) = (&self.setup.entities[e].topology, &s.slots[e]);
                        let items = if edges_phase {
                            topo.edges.len()
                        } else {
                            topo.triangles.len()
                        };
                        if items == 0 {
                            continue;
                        }
                        let push = SilhouettePush {
                            model: p.entity_transforms[e].to_cols_array(),
                            vertex_offset: slot.vertex_offset,
                            triangle_offset: slot.triangle_offset,
                            triangle_count: topo.triangles.len() as u32,
                            edge_offset: slot.edge_offset,
                            edge_count: topo.edges.len() as u32,
                            caps_base,
                            closed: topo.closed as u32,
                            edges_phase: edges_phase as u32,
                        };
                        ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                        ctx.rec.dispatch([items as u32, 1, 1])?;
                    }
                    Ok(())
                });
        }
    }

    /// The ambient pass of a round: the opaque surfaces the camera sees, or the translucent
    /// entities back to front.
    pub(super) fn add_ambient<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        frame: &FrameContext<'a>,
        plan: &FramePlan,
        translucent: bool,
    ) {
        let (scene, t, uniforms) = (frame.scene, frame.targets, frame.uniforms);
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let sampler = scene.sampler;
        let whole = SubresourceRange::mip(0);
        let prefix = if translucent { "translucent " } else { "" };
        let ambient_calls = if translucent {
            self.draws_in_order(scene, plan, &[], &plan.translucent_entities)
        } else {
            self.draw_list(scene, plan, &plan.visible_faces, &plan.visible_entities)
        };
        let ambient_pipelines = if translucent {
            self.translucent_ambient
        } else {
            self.ambient
        };
        let ambient_block: [f32; 4] = self.setup.config.lightmap.extend(0.0).into();
        graph
            .pass(&format!("{prefix}ambient"))
            .color_attachment(t.radiance, whole, false)
            .depth_stencil_write(t.depth_stencil, false)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::load(t.radiance)],
                    depth_stencil: Some(RenderTarget::load(t.depth_stencil)),
                })?;
                let zero_light = LightBlock::zeroed();
                let ambient_bytes: &[u8] = bytemuck::cast_slice(&ambient_block);
                let extra = |albedo, normal, _specular| {
                    vec![
                        (
                            "albedo_map",
                            Bind::Sampled {
                                image: albedo,
                                range: whole,
                                sampler,
                            },
                        ),
                        (
                            "normal_map",
                            Bind::Sampled {
                                image: normal,
                                range: whole,
                                sampler,
                            },
                        ),
                        ("ambient", Bind::UniformData(ambient_bytes)),
                    ]
                };
                record_surface(
                    ctx,
                    self,
                    scene,
                    &ambient_calls,
                    |f| ambient_pipelines[f.normal_map as usize],
                    extra,
                    bytemuck::bytes_of(&uniforms),
                    bytemuck::bytes_of(&zero_light),
                )?;
                ctx.rec.end_rendering();
                Ok(())
            });
    }

    /// Light `li`'s shadow volumes into the stencil: the world's caster faces from the templates,
    /// the entities' from the silhouette pass's slot `li`.
    pub(super) fn add_volumes<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        frame: &FrameContext<'a>,
        lp: &LightPlan,
        translucent: bool,
    ) {
        let (t, uniforms) = (frame.targets, frame.uniforms);
        let prefix = if translucent { "translucent " } else { "" };
        let light_index = lp.light;
        let light = &self.setup.lights[light_index];
        let world_ranges = plan::merge_ranges(lp.caster_faces.iter().map(|&f| {
            (
                self.faces[f as usize].template_first,
                self.faces[f as usize].template_count,
            )
        }));
        // The silhouette pass wrote the caster entities' volumes for this light when it has any.
        let entity_volumes = self
            .silhouettes
            .as_ref()
            .filter(|_| !lp.caster_entities.is_empty())
            .map(|s| (s.volumes, s.commands));
        let light_pos = light.position;
        let nudge = self.nudge_far as u32;
        let mut pass = graph
            .pass(&format!("light {light_index} {prefix}volumes"))
            .depth_stencil_write(t.depth_stencil, false);
        if let Some(b) = self.templates {
            pass = pass.buffer(b, Access::VertexRead, None);
        }
        if let Some((volumes, commands)) = entity_volumes {
            pass = pass
                .buffer(volumes, Access::VertexRead, None)
                .buffer(commands, Access::IndirectRead, None);
        }
        let templates = self.templates;
        pass.record(move |ctx| {
            let extent = ctx.rec.begin_rendering(&RenderingDesc {
                colors: Vec::new(),
                depth_stencil: Some(RenderTarget::load(t.depth_stencil)),
            })?;
            ctx.rec.clear_stencil(extent, 0)?;
            ctx.rec.bind_pipeline(self.volume)?;
            ctx.bind(&[("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms)))])?;
            if let (Some(b), false) = (templates, world_ranges.is_empty()) {
                ctx.rec.bind_vertex_buffers(&[(b, 0)])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&VolumePush {
                    light: light_pos.extend(1.0).into(),
                    nudge_far: nudge,
                }))?;
                for &(first, count) in &world_ranges {
                    ctx.rec.draw_from(count, first)?;
                }
            }
            if let Some((volumes, commands)) = entity_volumes {
                ctx.rec.bind_vertex_buffers(&[(volumes, 0)])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&VolumePush {
                    light: light_pos.extend(0.0).into(),
                    nudge_far: nudge,
                }))?;
                // Sides, then caps (the order the saturating negative control relies on).
                let command = std::mem::size_of::<vk::DrawIndirectCommand>() as u64;
                ctx.rec.draw_indirect(commands, 0)?;
                ctx.rec.draw_indirect(commands, command)?;
            }
            ctx.rec.end_rendering();
            Ok(())
        });
    }

    /// Light `lp`'s lighting of its receivers where the stencil is clear.
    pub(super) fn add_lighting<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        frame: &FrameContext<'a>,
        plan: &FramePlan,
        lp: &LightPlan,
        translucent: bool,
    ) {
        let (scene, t, uniforms) = (frame.scene, frame.targets, frame.uniforms);
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let sampler = scene.sampler;
        let whole = SubresourceRange::mip(0);
        let prefix = if translucent { "translucent " } else { "" };
        let light_index = lp.light;
        let (receiver_faces, receiver_entities): (&[FaceId], &[usize]) = if translucent {
            (&[], &lp.translucent_receivers)
        } else {
            (&lp.receiver_faces, &lp.receiver_entities)
        };
        // Translucent receivers: the depth test (LESS_OR_EQUAL, no writes) passes only
        // where a layer's depth is the stored one, i.e. the nearest translucent layer;
        // light.frag scales the light by the material's opacity.
        let calls = if translucent {
            self.draws_in_order(scene, plan, receiver_faces, receiver_entities)
        } else {
            self.draw_list(scene, plan, receiver_faces, receiver_entities)
        };
        let block = self.light_block(light_index, scene);
        graph
            .pass(&format!("light {light_index} {prefix}lighting"))
            .color_attachment(t.radiance, whole, false)
            .depth_stencil_read(t.depth_stencil)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::load(t.radiance)],
                    depth_stencil: Some(RenderTarget {
                        read_only: true,
                        ..RenderTarget::load(t.depth_stencil)
                    }),
                })?;
                let extra = |albedo, normal, specular| {
                    vec![
                        (
                            "albedo_map",
                            Bind::Sampled {
                                image: albedo,
                                range: whole,
                                sampler,
                            },
                        ),
                        (
                            "normal_map",
                            Bind::Sampled {
                                image: normal,
                                range: whole,
                                sampler,
                            },
                        ),
                        (
                            "specular_map",
                            Bind::Sampled {
                                image: specular,
                                range: whole,
                                sampler,
                            },
                        ),
                    ]
                };
                record_surface(
                    ctx,
                    self,
                    scene,
                    &calls,
                    |f| self.light[f.normal_map as usize][f.specular as usize],
                    extra,
                    bytemuck::bytes_of(&uniforms),
                    bytemuck::bytes_of(&block),
                )?;
                ctx.rec.end_rendering();
                Ok(())
            });
    }
}
