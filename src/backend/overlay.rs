//! The on-screen panel's renderer: egui's triangles drawn into a colour target by
//! `egui-ash-renderer`, inside the frame's command buffer (a graph pass draws it over the
//! tone-mapped image, so the pass declares the target and the graph derives its barriers).

use egui_ash_renderer::{DynamicRendering, Options, Renderer};

use super::device::vulkan_calls;
use super::error::{BackendError, BackendResult};
use super::recorder::{Recorder, RenderTarget, RenderingDesc};
use super::resources::ImageId;
use super::{vk, Gpu};

/// What egui tessellated for one frame: its triangles and texture changes.
pub struct OverlayFrame {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub textures: egui::TexturesDelta,
    pub pixels_per_point: f32,
}

/// egui's renderer on this device for one colour format.
pub struct Overlay {
    renderer: Renderer<egui_ash_renderer::allocator::DefaultAllocator>,
    pub format: vk::Format,
    pending: Option<OverlayFrame>,
    /// Textures egui no longer needs, freed once the frames that drew with them are done.
    to_free: Vec<egui::TextureId>,
}

fn overlay_error(e: egui_ash_renderer::RendererError) -> BackendError {
    BackendError::Unsupported(format!("overlay renderer: {e}"))
}

impl Overlay {
    /// A renderer drawing into `format` targets (an sRGB format gets linear output from the
    /// shader), with vertex buffers for `frames_in_flight` frames.
    pub fn new(gpu: &Gpu, format: vk::Format, frames_in_flight: usize) -> BackendResult<Overlay> {
        let _calls = vulkan_calls();
        let srgb = matches!(format, vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB);
        let renderer = Renderer::with_default_allocator(
            &gpu.instance,
            gpu.physical,
            gpu.device.clone(),
            egui_ash_renderer::RenderMode::DynamicRendering(DynamicRendering {
                color_attachment_format: format,
                depth_attachment_format: None,
                stencil_attachment_format: None,
            }),
            Options {
                in_flight_frames: frames_in_flight,
                srgb_framebuffer: srgb,
                ..Options::default()
            },
        )
        .map_err(overlay_error)?;
        Ok(Overlay {
            renderer,
            format,
            pending: None,
            to_free: Vec::new(),
        })
    }

    /// Takes the UI of the next frame: uploads its new textures now (waiting for the device
    /// first, since a replaced texture may still be read by a frame in flight) and keeps its
    /// triangles for [`Overlay::record`].
    pub fn prepare(&mut self, gpu: &Gpu, mut frame: OverlayFrame) -> BackendResult<()> {
        // Drained here: egui checks in debug builds that no delta is dropped unapplied.
        let set: Vec<_> = frame.textures.set.drain().collect();
        if !set.is_empty() || !self.to_free.is_empty() {
            gpu.wait_idle()?;
            let _calls = vulkan_calls();
            for id in std::mem::take(&mut self.to_free) {
                self.renderer.free_texture(id).map_err(overlay_error)?;
            }
            for (id, deltas) in set {
                for delta in deltas {
                    self.renderer
                        .set_texture(gpu.queue, gpu.command_pool, id, &delta)
                        .map_err(overlay_error)?;
                }
            }
        }
        self.to_free.extend(frame.textures.free.drain());
        self.pending = Some(frame);
        Ok(())
    }

    /// Draws the prepared UI over `target` (loaded, not cleared). Nothing prepared: nothing drawn.
    pub fn record(&mut self, rec: &mut Recorder<'_>, target: ImageId) -> BackendResult<()> {
        let Some(frame) = self.pending.take() else {
            return Ok(());
        };
        let extent = rec.begin_rendering(&RenderingDesc {
            colors: vec![RenderTarget::load(target)],
            depth_stencil: None,
        })?;
        // egui binds its own pipeline: the recorder's notion of the bound one is stale after.
        rec.forget_pipeline();
        let drawn = self
            .renderer
            .cmd_draw(rec.cb, extent, frame.pixels_per_point, &frame.primitives)
            .map_err(overlay_error);
        rec.end_rendering();
        drawn
    }
}
