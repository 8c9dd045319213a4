//! Many lights in one pass over the receivers. The seed draws the receivers again for every
//! light, which on a large mesh costs the light's vertices, not its pixels (on a 269k-triangle
//! scene at 640×360 on lavapipe a light pass took as long at 64×36). A light whose receivers are
//! everything in view instead leaves, after its volumes, one bit in the frame's light mask where
//! the stencil is 0 (`light_mask.frag`), and one pass over the receivers per group of up to
//! [`LIGHTS_PER_GROUP`] lights adds each light where its bit is set (`light_group.frag`, which
//! shades with the light pass's own function). A light whose receivers the radius or the PVS
//! cut keeps its own pass: the mask alone would light what it does not reach.

use bytemuck::Zeroable;

use super::frame_passes::{begin_light_rendering, light_maps};
use super::plan::{FramePlan, LightPlan};
use super::{outside_every_volume, record_surface, spec, LightBlock, Mode, ShadowVolumes};
use crate::backend::{
    vk, Bind, BlendMode, ColorTarget, DepthState, Gpu, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc,
    SubresourceRange,
};
use crate::error::Result;
use crate::graph::{Access, RenderGraph};
use crate::lighting::{FrameContext, LIGHT_MASK_FORMAT, RADIANCE_FORMAT};
use crate::shaders::ShaderLibrary;

/// The lights one mask holds: 24 bits (exact sums of distinct powers of two in f32) in each of
/// four channels.
pub const LIGHTS_PER_GROUP: usize = 96;

/// The pipelines of the grouped path.
pub(super) struct GroupPipelines {
    /// Adds a light's bit where the stencil is 0.
    mask: PipelineId,
    /// The group's light pass, by (normal map, specular) as the light pass's.
    light: [[PipelineId; 2]; 2],
}

impl GroupPipelines {
    pub(super) fn new(gpu: &mut Gpu, shaders: &ShaderLibrary, c: &super::Config) -> Result<GroupPipelines> {
        let ds_format = gpu.caps().depth_stencil_format;
        let mut m = GraphicsPipelineDesc::new(
            &format!("{} light mask", super::NAME),
            "post/fullscreen.vert",
            Some("shadow_volumes/light_mask.frag"),
        );
        m.raster.cull = vk::CullModeFlags::NONE;
        m.color_targets = vec![ColorTarget {
            blend: BlendMode::Additive,
            ..ColorTarget::new(LIGHT_MASK_FORMAT)
        }];
        m.depth_format = Some(ds_format);
        m.depth = DepthState {
            test: false,
            write: false,
            compare: vk::CompareOp::ALWAYS,
        };
        m.stencil = Some(outside_every_volume());
        let mask = gpu.create_graphics_pipeline(&m, shaders)?;
        let mode = match c.mode {
            Mode::Faithful => 0,
            Mode::Physical => 1,
        };
        let mut light = [[mask; 2]; 2];
        for nm in [false, true] {
            for sp in [false, true] {
                let name = format!(
                    "{} grouped light{}{}",
                    super::NAME,
                    if nm { " normal-mapped" } else { "" },
                    if sp { " specular" } else { "" }
                );
                let mut d = GraphicsPipelineDesc::new(
                    &name,
                    "shadow_volumes/surface.vert",
                    Some("shadow_volumes/light_group.frag"),
                );
                d.vertex_layout = crate::gpu_scene::vertex_layout();
                d.raster.cull = vk::CullModeFlags::NONE;
                d.color_targets = vec![ColorTarget {
                    blend: BlendMode::Additive,
                    ..ColorTarget::new(RADIANCE_FORMAT)
                }];
                d.depth_format = Some(ds_format);
                // The light pass's depth test, without its stencil test: the mask has it.
                d.depth = DepthState {
                    test: true,
                    write: false,
                    compare: vk::CompareOp::LESS_OR_EQUAL,
                };
                d.specialization = vec![spec(0, mode), spec(1, nm as u32), spec(2, sp as u32), spec(4, c.atten)];
                light[nm as usize][sp as usize] = gpu.create_graphics_pipeline(&d, shaders)?;
            }
        }
        Ok(GroupPipelines { mask, light })
    }
}

/// Whether light `lp` can be lit with the group: its receivers are everything in view.
pub(super) fn groupable(plan: &FramePlan, lp: &LightPlan) -> bool {
    lp.receiver_faces == plan.visible_faces && lp.receiver_entities == plan.visible_entities
}

/// The value light `slot` of a group adds to the mask: its bit, in its channel.
fn mask_bit(slot: usize) -> [f32; 4] {
    let mut bit = [0.0; 4];
    bit[slot / 24] = (1u32 << (slot % 24)) as f32;
    bit
}

impl ShadowVolumes {
    /// Light `lp`'s bit `slot` in the mask where its volumes left the stencil at 0; slot 0
    /// clears the mask first.
    pub(super) fn add_light_mask<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        frame: &FrameContext<'a>,
        lp: &LightPlan,
        slot: usize,
    ) -> Result<()> {
        let (t, group) = (frame.targets, self.group_pipelines()?);
        let mask = self.light_mask(frame)?;
        let bit = mask_bit(slot);
        graph
            .pass(&format!("light {} mask", lp.light))
            .color_attachment(mask, SubresourceRange::mip(0), slot == 0)
            .depth_stencil_read(t.depth_stencil)
            .record(move |ctx| {
                let target = match slot {
                    0 => RenderTarget::clear_color(mask, [0.0; 4]),
                    _ => RenderTarget::load(mask),
                };
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![target],
                    depth_stencil: Some(RenderTarget {
                        read_only: true,
                        ..RenderTarget::load(t.depth_stencil)
                    }),
                })?;
                ctx.rec.bind_pipeline(group.mask)?;
                ctx.rec.push_constants(bytemuck::cast_slice(&bit))?;
                ctx.rec.draw(3, 1)?;
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }

    /// The group's lights (`lights`, in slot order) added over everything in view where their
    /// bits are set.
    pub(super) fn add_group_lighting<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        frame: &FrameContext<'a>,
        plan: &FramePlan,
        lights: &[usize],
    ) -> Result<()> {
        let (scene, t, uniforms) = (frame.scene, frame.targets, frame.uniforms);
        let (group, mask) = (self.group_pipelines()?, self.light_mask(frame)?);
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let (sampler, whole) = (scene.sampler, SubresourceRange::mip(0));
        let calls = self.draw_list(scene, plan, &plan.visible_faces, &plan.visible_entities);
        let mut data: Vec<u8> = bytemuck::bytes_of(&[lights.len() as u32, 0, 0, 0]).to_vec();
        for &l in lights {
            data.extend_from_slice(bytemuck::bytes_of(&self.light_block(l, scene)));
        }
        let name = match lights {
            [first, .., last] => format!("lights {first}-{last} grouped lighting"),
            _ => format!("lights {lights:?} grouped lighting"),
        };
        graph
            .pass(&name)
            .color_attachment(t.radiance, whole, false)
            .depth_stencil_read(t.depth_stencil)
            .sample("light_mask", mask, whole, sampler, frag)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                begin_light_rendering(ctx.rec, t)?;
                let zero_light = LightBlock::zeroed();
                let data: &[u8] = &data;
                let extra = |albedo, normal, specular| {
                    let mut binds = light_maps([albedo, normal, specular], sampler);
                    binds.push(("group", Bind::StorageData(data)));
                    binds
                };
                record_surface(
                    ctx,
                    self,
                    scene,
                    &calls,
                    |f| group.light[f.normal_map as usize][f.specular as usize],
                    extra,
                    bytemuck::bytes_of(&uniforms),
                    bytemuck::bytes_of(&zero_light),
                )?;
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }

    fn group_pipelines(&self) -> Result<&GroupPipelines> {
        self.group
            .as_ref()
            .ok_or_else(|| crate::error::Error::Internal(format!("{}: no grouped-light pipelines", super::NAME)))
    }

    fn light_mask(&self, frame: &FrameContext<'_>) -> Result<crate::backend::ImageId> {
        frame
            .targets
            .light_mask
            .ok_or_else(|| crate::error::Error::Internal(format!("{}: the frame has no light mask", super::NAME)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_slot_of_a_group_has_its_own_exact_bit() {
        let mut sums = [0.0f32; 4];
        for slot in 0..LIGHTS_PER_GROUP {
            let bit = mask_bit(slot);
            assert_eq!(bit.iter().filter(|&&b| b != 0.0).count(), 1);
            for c in 0..4 {
                sums[c] += bit[c];
            }
        }
        // Every bit set: the sums are exact, and read back as 24 set bits per channel.
        for s in sums {
            assert_eq!(s as u32, (1 << 24) - 1);
        }
    }
}
