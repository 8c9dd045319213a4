//! The frame's passes: entity silhouettes, then per round (opaque, then translucent) the ambient
//! pass and, per light, its stencil volumes and its lighting.

use std::rc::Rc;

use bytemuck::Zeroable;
use glam::Vec4;

use super::plan::{self, FramePlan, LightPlan};
use super::SILHOUETTE_COMMAND_WORDS;
use super::{near_clip, record_surface, LightBlock, ShadowVolumes, SilhouetteBuffers, SilhouettePush, VolumePush};
use crate::backend::{
    vk, BackendResult, Bind, ImageId, Recorder, RenderTarget, RenderingDesc, SamplerId, SubresourceRange,
};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{FrameContext, FrameTargets};
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
        frame: &FrameContext<'a>,
        translucent: bool,
    ) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let light: Vec4 = self.homogeneous_light(lp.light, frame.scene);
        // The light, then the hull its triangles are tested against for z-pass (none: z-fail).
        let hull = match self.volume_zpass {
            Some(_) => near_clip::near_clip(&frame.uniforms.view_proj, light),
            None => None,
        };
        let light_data = hull.map_or([light; 10], |h| h.with_light(light));
        let near_test = hull.is_some() as u32;
        let prefix = if translucent { "translucent " } else { "" };
        let (commands, near, caps_base) = (s.commands, s.near, s.caps_base);
        // Three VkDrawIndirectCommand (vertex count, instances, first vertex, first instance):
        // sides for z-fail, caps, sides for z-pass. Every entity counts by z-fail when no test
        // is made.
        let reset: [u32; SILHOUETTE_COMMAND_WORDS] = [0, 1, 0, 0, 0, 1, caps_base, 0, 0, 1, 0, 0];
        graph
            .pass(&format!("light {} {prefix}silhouette counts", lp.light))
            .buffer(commands, Access::TransferWrite, None)
            .buffer(near, Access::TransferWrite, None)
            .record(move |ctx| {
                ctx.rec.update_buffer(commands, &reset)?;
                ctx.rec.fill_buffer(near, 1 - near_test)
            });
        // The triangles (their facings, and whether a volume reaches the near plane), then the
        // caps and the edges (the sides from those facings), then, with the near-plane test,
        // one invocation that sets where the z-pass sides start: passes, so that each reads what
        // the one before wrote.
        let phases = if near_test != 0 { 3 } else { 2 };
        for phase in 0..phases {
            let (casters, p) = (lp.caster_entities.clone(), plan.clone());
            let name = ["silhouettes", "silhouette edges", "silhouette draws"][phase as usize];
            let facings = if phase == 0 {
                Access::StorageWrite { stages: compute }
            } else {
                Access::StorageRead { stages: compute }
            };
            graph
                .pass(&format!("light {} {prefix}{name}", lp.light))
                .buffer(s.positions, Access::StorageRead { stages: compute }, Some("positions"))
                .buffer(s.triangles, Access::StorageRead { stages: compute }, Some("triangles"))
                .buffer(s.edges, Access::StorageRead { stages: compute }, Some("edges"))
                .buffer(s.volumes, Access::StorageWrite { stages: compute }, Some("volumes"))
                .buffer(commands, Access::StorageWrite { stages: compute }, Some("commands"))
                .buffer(s.facings, facings, Some("facings"))
                // Declared written throughout, so that the next light's reset waits on the
                // writes of the first dispatch, not only on the reads since.
                .buffer(near, Access::StorageWrite { stages: compute }, Some("near_plane"))
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(self.silhouette)?;
                    ctx.bind(&[("light_positions", Bind::StorageData(bytemuck::cast_slice(&light_data)))])?;
                    for &e in &casters {
                        let (topo, slot) = (&self.setup.entities[e].topology, &s.slots[e]);
                        let items = match phase {
                            0 => topo.triangles.len(),
                            1 => topo.edges.len().max(topo.triangles.len()),
                            _ => 1,
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
                            edges_phase: phase,
                            near_test,
                            index: e as u32,
                        };
                        ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                        ctx.rec.dispatch([items as u32, 1, 1])?;
                        if phase == 2 {
                            break;
                        }
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
        let (templates, zpass) = (self.templates, self.volume_zpass);
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
                // Sides, then caps (the order the saturating negative control relies on); the
                // silhouette pass left one of the two ways empty.
                let command = std::mem::size_of::<vk::DrawIndirectCommand>() as u64;
                ctx.rec.draw_indirect(commands, 0)?;
                ctx.rec.draw_indirect(commands, command)?;
                if let Some(zpass) = zpass {
                    ctx.rec.bind_pipeline(zpass)?;
                    ctx.rec.draw_indirect(commands, 2 * command)?;
                }
            }
            ctx.rec.end_rendering();
            Ok(())
        });
        if let (Some((_, commands)), Some(s)) = (entity_volumes, &self.silhouettes) {
            let bytes = (SILHOUETTE_COMMAND_WORDS * 4) as u64;
            let slot = (translucent as usize * self.setup.lights.len() + light_index) as u64;
            let tally = s.tally;
            graph
                .pass(&format!("light {light_index} {prefix}volume tally"))
                .buffer(commands, Access::TransferRead, None)
                .buffer(tally, Access::TransferWrite, None)
                .record(move |ctx| ctx.rec.copy_buffer_to(commands, tally, slot * bytes, bytes));
            // Read back after the frame (`frame_notes`), by nothing in it.
            graph.output_buffer(tally);
        }
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
                begin_light_rendering(ctx.rec, t)?;
                let extra = |albedo, normal, specular| light_maps([albedo, normal, specular], sampler);
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

/// Begins a pass that adds light into the radiance where the depth (and the stencil) the passes
/// before left allow: both are tested, neither written.
pub(super) fn begin_light_rendering(rec: &mut Recorder<'_>, t: FrameTargets) -> BackendResult<()> {
    let _ = rec.begin_rendering(&RenderingDesc {
        colors: vec![RenderTarget::load(t.radiance)],
        depth_stencil: Some(RenderTarget {
            read_only: true,
            ..RenderTarget::load(t.depth_stencil)
        }),
    })?;
    Ok(())
}

/// A light pass's material maps (albedo, normal, specular), each sampled whole.
pub(super) fn light_maps<'b>(maps: [ImageId; 3], sampler: SamplerId) -> Vec<(&'static str, Bind<'b>)> {
    let names = ["albedo_map", "normal_map", "specular_map"];
    names
        .into_iter()
        .zip(maps)
        .map(|(name, image)| {
            let range = SubresourceRange::mip(0);
            (name, Bind::Sampled { image, range, sampler })
        })
        .collect()
}
