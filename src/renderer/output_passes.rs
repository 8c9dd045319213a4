//! The passes after the scene, for where the frame goes: a copy of the radiance to the host, or
//! tone mapping into a swapchain image with its overlay, screenshot copy and presentation.

use crate::backend::{
    vk, BufferId, ColorTarget, DepthState, Gpu, GraphicsPipelineDesc, ImageId, PipelineId, RenderTarget, RenderingDesc,
    SamplerId, SubresourceRange,
};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph};
use crate::lighting::FrameTargets;
use crate::shaders::ShaderLibrary;

use super::FrameOutput;

/// The tone-map pipeline for swapchain images of `format`.
pub(super) fn create_tonemap(gpu: &mut Gpu, shaders: &ShaderLibrary, format: vk::Format) -> Result<PipelineId> {
    let mut desc = GraphicsPipelineDesc::new("tonemap", "post/fullscreen.vert", Some("post/tonemap.frag"));
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.depth = DepthState {
        test: false,
        write: false,
        compare: vk::CompareOp::ALWAYS,
    };
    desc.color_targets = vec![ColorTarget::new(format)];
    Ok(gpu.create_graphics_pipeline(&desc, shaders)?)
}

/// What the output passes copy into and draw with, as the renderer prepared them for this
/// frame's output.
pub(super) struct OutputResources {
    pub readback: Option<BufferId>,
    pub present_readback: Option<BufferId>,
    pub tonemap: Option<PipelineId>,
    pub display_sampler: SamplerId,
}

impl OutputResources {
    /// Adds the passes `output` asks for after the scene's. The overlay, if any, is taken out of
    /// `output` and recorded by the graph.
    pub fn add<'a, 'o: 'a>(
        &self,
        graph: &mut RenderGraph<'a>,
        t: FrameTargets,
        output: &mut FrameOutput<'o>,
    ) -> Result<()> {
        match output {
            FrameOutput::None => graph.output_image(t.radiance),
            FrameOutput::Readback => {
                let rb = self.radiance_buffer()?;
                add_host_copy(graph, t.radiance, rb, ["readback", "host visibility"]);
            }
            FrameOutput::Present {
                image,
                exposure,
                readback,
                radiance,
                overlay,
            } => {
                if *radiance {
                    let rb = self.radiance_buffer()?;
                    add_host_copy(graph, t.radiance, rb, ["radiance readback", "radiance host visibility"]);
                }
                self.add_tonemap(graph, t, *image, *exposure)?;
                if let Some(overlay) = overlay.take() {
                    let image = *image;
                    graph
                        .pass("overlay")
                        .color_attachment(image, SubresourceRange::mip(0), false)
                        .record(move |ctx| overlay.record(ctx.rec, image));
                }
                if let Some(rb) = self.present_readback.filter(|_| *readback) {
                    add_host_copy(graph, *image, rb, ["screenshot readback", "screenshot host visibility"]);
                }
                graph.pass("present").present(*image).record(|_| Ok(()));
            }
        }
        Ok(())
    }

    fn radiance_buffer(&self) -> Result<BufferId> {
        self.readback
            .ok_or_else(|| Error::Internal("readback buffer missing".into()))
    }

    /// Tone-maps the radiance into `image` with `exposure`.
    fn add_tonemap(&self, graph: &mut RenderGraph<'_>, t: FrameTargets, image: ImageId, exposure: f32) -> Result<()> {
        let pipeline = self
            .tonemap
            .ok_or_else(|| Error::Internal("tonemap pipeline missing".into()))?;
        graph
            .pass("tonemap")
            .sample(
                "hdr",
                t.radiance,
                SubresourceRange::mip(0),
                self.display_sampler,
                vk::PipelineStageFlags2::FRAGMENT_SHADER,
            )
            .color_attachment(image, SubresourceRange::mip(0), true)
            .record(move |ctx| {
                let _extent = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::clear_color(image, [0.0; 4])],
                    depth_stencil: None,
                })?;
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(&exposure.to_le_bytes())?;
                ctx.rec.draw(3, 1)?;
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }
}

/// Copies `image`'s first mip into `buffer`, then makes the copy visible to the host once the
/// frame's fence has signalled. `names`: the copy pass's and the visibility pass's.
fn add_host_copy(graph: &mut RenderGraph<'_>, image: ImageId, buffer: BufferId, names: [&str; 2]) {
    graph
        .pass(names[0])
        .transfer_read(image, SubresourceRange::mip(0))
        .buffer(buffer, Access::TransferWrite, None)
        .record(move |ctx| ctx.rec.copy_image_to_buffer(image, 0, 0, buffer));
    graph
        .pass(names[1])
        .buffer(buffer, Access::HostRead, None)
        .record(|_| Ok(()));
}
