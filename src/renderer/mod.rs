//! Frame assembly: the scene on the GPU, the frame targets, the lighting method the scene asked
//! for, and the passes around it (readback for captures, tone mapping for the window).

pub mod environment;
mod scene_gpu;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use crate::backend::{
    vk, BufferDesc, BufferId, ColorTarget, Frame, Gpu, GraphicsPipelineDesc, ImageDesc, ImageId, MemoryKind, PassTiming, PipelineId, RenderTarget, RenderingDesc, SamplerDesc, SubresourceRange,
};
use crate::error::{Error, Result};
use crate::graph::{Access, ExecutionReport, RenderGraph, ResourceStates};
use crate::image_io::HdrImage;
use crate::methods::{self, FrameInputs, FrameTargets, LightingMethod};
use crate::scene::{Camera, Scene};
use crate::shaders::ShaderLibrary;
pub use scene_gpu::{punctual_lights, raster_lights, DrawItem, GpuLight, GpuMaterial, MaterialMaps, SceneGpu, Vertex, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_QUAD_FAR, LIGHT_SPOT};

/// Linear radiance: 32-bit float so captures read back exactly what the shaders computed.
pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Matches `FrameUniforms` in glsl/common/frame.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [f32; 16],
    pub camera_pos: [f32; 4],
    pub ambient: [f32; 4],
    pub counts: [u32; 4],
    /// Environment irradiance, 3-band SH (see `environment::EnvironmentLighting`).
    pub env_irradiance: [[f32; 4]; 9],
}

/// Push constants of raster draws (`Draw` in glsl/forward/forward.vert); 68 bytes are pushed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DrawPush {
    pub model: [f32; 16],
    pub material: u32,
    pub _pad: [u32; 3],
}

/// Where a frame goes besides the radiance target.
pub enum FrameOutput {
    /// Nothing: profiling.
    None,
    /// Copy radiance into a host buffer and return it.
    Readback,
    /// Tone-map into a swapchain image and leave it ready to present. With `readback`, the
    /// presented pixels are also copied to a host buffer (a screenshot of exactly what the
    /// window shows); fetch them with [`Renderer::presented_pixels`] once the frame completed.
    Present { image: ImageId, exposure: f32, readback: bool },
}

pub struct FrameResult {
    pub report: ExecutionReport,
    pub image: Option<HdrImage>,
}

pub struct Renderer {
    pub gpu: Gpu,
    pub shaders: ShaderLibrary,
    pub scene: Scene,
    pub scene_gpu: SceneGpu,
    pub method: Box<dyn LightingMethod>,
    pub states: ResourceStates,
    pub targets: FrameTargets,
    frames: Vec<Frame>,
    frame_index: usize,
    readback: Option<BufferId>,
    present_readback: Option<BufferId>,
    tonemap: Option<(PipelineId, vk::Format)>,
}

impl Renderer {
    /// Uploads the scene and creates the method (`method`: one of the scene's, default its first).
    pub fn new(mut gpu: Gpu, scene: Scene, method: Option<&str>, size: (u32, u32), frames_in_flight: usize) -> Result<Renderer> {
        scene.check_methods(&methods::schemas())?;
        let decl = match method {
            Some(m) => scene.methods.iter().find(|d| d.name == m).ok_or_else(|| {
                let names: Vec<&str> = scene.methods.iter().map(|d| d.name.as_str()).collect();
                let known: Vec<&str> = methods::schemas().iter().map(|s| s.name).collect();
                if known.contains(&m) {
                    Error::Usage(format!("{}: method `{m}` is not enabled by the scene (it enables: {})", scene.source, names.join(", ")))
                } else {
                    Error::Usage(format!("--method {m}: unknown method; known methods: {}", known.join(", ")))
                }
            })?,
            None => scene.methods.first().ok_or_else(|| Error::Usage(format!("{}: the scene enables no method", scene.source)))?,
        }
        .clone();
        let shaders = ShaderLibrary::Embedded;
        let mut states = ResourceStates::default();
        let scene_gpu = SceneGpu::upload(&mut gpu, &mut states, &scene)?;
        let method = methods::create(&decl, &mut gpu, &shaders, &mut states, &scene)?;
        let targets = create_targets(&mut gpu, size)?;
        let frames = (0..frames_in_flight.max(1)).map(|_| gpu.create_frame()).collect::<std::result::Result<Vec<_>, _>>()?;
        Ok(Renderer { gpu, shaders, scene, scene_gpu, method, states, targets, frames, frame_index: 0, readback: None, present_readback: None, tonemap: None })
    }

    /// Recreates the size-dependent targets.
    pub fn resize(&mut self, size: (u32, u32)) -> Result<()> {
        if (self.targets.width, self.targets.height) == size {
            return Ok(());
        }
        self.gpu.wait_idle()?;
        for id in [self.targets.radiance, self.targets.depth_stencil] {
            self.gpu.destroy_image(id);
            self.states.forget_image(id);
        }
        if let Some(b) = self.readback.take() {
            self.gpu.destroy_buffer(b);
            self.states.forget_buffer(b);
        }
        self.targets = create_targets(&mut self.gpu, size)?;
        Ok(())
    }

    pub fn uniforms(&self, camera: &Camera) -> FrameUniforms {
        let aspect = self.targets.width as f32 / self.targets.height as f32;
        let vp: Mat4 = camera.projection(aspect) * camera.view_matrix();
        FrameUniforms {
            view_proj: vp.to_cols_array(),
            camera_pos: camera.position.extend(1.0).into(),
            // A constant environment seen by an unoccluded Lambertian surface reflects ρ·L; the
            // forward method has no visibility, so this is its whole environment term.
            ambient: match &self.scene.environment {
                Some(crate::scene::Environment::Constant { radiance }) => radiance.extend(0.0).into(),
                _ => [0.0; 4],
            },
            counts: [self.scene_gpu.lights.len() as u32, 0, 0, 0],
            env_irradiance: self.scene_gpu.environment.irradiance_sh,
        }
    }

    /// Renders one frame and waits for it when the output is a readback.
    pub fn render(&mut self, camera: &Camera, output: FrameOutput) -> Result<FrameResult> {
        let uniforms = self.uniforms(camera);
        if matches!(output, FrameOutput::Readback) && self.readback.is_none() {
            let size = self.targets.width as u64 * self.targets.height as u64 * 16;
            self.readback = Some(self.gpu.create_buffer(&BufferDesc { name: "radiance readback".into(), size, usage: vk::BufferUsageFlags::TRANSFER_DST, memory: MemoryKind::GpuToCpu })?);
        }
        if let FrameOutput::Present { image, readback, .. } = &output {
            let d = self.gpu.image_desc(*image)?;
            let format = d.format;
            let bytes = d.extent.width as u64 * d.extent.height as u64 * 4;
            if *readback && self.present_readback.map(|b| self.gpu.buffer_desc(b).map(|d| d.size).unwrap_or(0)) != Some(bytes) {
                if let Some(old) = self.present_readback.take() {
                    self.gpu.destroy_buffer(old);
                    self.states.forget_buffer(old);
                }
                self.present_readback =
                    Some(self.gpu.create_buffer(&BufferDesc { name: "presented pixels".into(), size: bytes, usage: vk::BufferUsageFlags::TRANSFER_DST, memory: MemoryKind::GpuToCpu })?);
            }
            if self.tonemap.map(|t| t.1) != Some(format) {
                let mut desc = GraphicsPipelineDesc::new("tonemap", "post/fullscreen.vert", Some("post/tonemap.frag"));
                desc.raster.cull = vk::CullModeFlags::NONE;
                desc.depth = crate::backend::DepthState { test: false, write: false, compare: vk::CompareOp::ALWAYS };
                desc.color_targets = vec![ColorTarget::new(format)];
                self.tonemap = Some((self.gpu.create_graphics_pipeline(&desc, &self.shaders)?, format));
            }
        }
        let display_sampler = self.gpu.sampler(SamplerDesc::NEAREST_CLAMP)?;
        let frame = self.frames[self.frame_index % self.frames.len()];
        self.frame_index += 1;

        let gpu = &self.gpu;
        let inputs = FrameInputs { gpu, scene: &self.scene_gpu, targets: self.targets, uniforms };
        let mut graph = RenderGraph::new();
        self.method.add_passes(&mut graph, &inputs)?;
        let t = self.targets;
        match &output {
            FrameOutput::None => graph.output_image(t.radiance),
            FrameOutput::Readback => {
                let rb = self.readback.ok_or_else(|| Error::Usage("readback buffer missing".into()))?;
                graph
                    .pass("readback")
                    .transfer_read(t.radiance, SubresourceRange::mip(0))
                    .buffer(rb, Access::TransferWrite, None)
                    .record(move |ctx| ctx.rec.copy_image_to_buffer(t.radiance, 0, 0, rb));
                // Makes the copy visible to the host once the frame's fence has signalled.
                graph.pass("host visibility").buffer(rb, Access::HostRead, None).record(|_| Ok(()));
            }
            FrameOutput::Present { image, exposure, readback } => {
                let (pipeline, _) = self.tonemap.ok_or_else(|| Error::Usage("tonemap pipeline missing".into()))?;
                let (image, exposure) = (*image, *exposure);
                let present_readback = if *readback { self.present_readback } else { None };
                graph
                    .pass("tonemap")
                    .sample("hdr", t.radiance, SubresourceRange::mip(0), display_sampler, vk::PipelineStageFlags2::FRAGMENT_SHADER)
                    .color_attachment(image, SubresourceRange::mip(0), true)
                    .record(move |ctx| {
                        let _extent = ctx.rec.begin_rendering(&RenderingDesc { colors: vec![RenderTarget::clear_color(image, [0.0; 4])], depth_stencil: None })?;
                        ctx.rec.bind_pipeline(pipeline)?;
                        ctx.bind(&[])?;
                        ctx.rec.push_constants(&exposure.to_le_bytes())?;
                        ctx.rec.draw(3, 1)?;
                        ctx.rec.end_rendering();
                        Ok(())
                    });
                if let Some(rb) = present_readback {
                    graph
                        .pass("screenshot readback")
                        .transfer_read(image, SubresourceRange::mip(0))
                        .buffer(rb, Access::TransferWrite, None)
                        .record(move |ctx| ctx.rec.copy_image_to_buffer(image, 0, 0, rb));
                    graph.pass("screenshot host visibility").buffer(rb, Access::HostRead, None).record(|_| Ok(()));
                }
                graph.pass("present").present(image).record(|_| Ok(()));
            }
        }
        let mut rec = gpu.begin_frame(frame)?;
        rec.begin_scope("frame");
        let report = graph.execute(&mut rec, &mut self.states)?;
        rec.end_scope();
        rec.finish()?;
        Ok(FrameResult { report, image: None }).and_then(|mut r| {
            if matches!(output, FrameOutput::Readback) {
                gpu.submit_and_wait(frame)?;
                let rb = self.readback.ok_or_else(|| Error::Usage("readback buffer missing".into()))?;
                let bytes = gpu.read_buffer(rb)?;
                r.image = HdrImage::from_rgba32f_bytes(t.width, t.height, &bytes);
            }
            Ok(r)
        })
    }

    /// The pixels of the last frame rendered with `Present { readback: true }`, as 8-bit RGBA
    /// (display-encoded, as the window shows them). Call after that frame has completed.
    pub fn presented_pixels(&self, image: ImageId) -> Result<image::RgbaImage> {
        let rb = self.present_readback.ok_or_else(|| Error::Usage("no frame was presented with readback".into()))?;
        let d = self.gpu.image_desc(image)?;
        let mut bytes = self.gpu.read_buffer(rb)?;
        if matches!(d.format, vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM) {
            for px in bytes.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        image::RgbaImage::from_raw(d.extent.width, d.extent.height, bytes).ok_or_else(|| Error::Usage("presented pixels do not match the image size".into()))
    }

    /// The frame slot the next [`Renderer::render`] records into (for presenting).
    pub fn current_frame(&self) -> Frame {
        self.frames[self.frame_index % self.frames.len()]
    }

    pub fn last_frame(&self) -> Frame {
        self.frames[(self.frame_index + self.frames.len() - 1) % self.frames.len()]
    }

    /// Renders `frames` frames (each submitted and waited for) and returns each frame's timings.
    pub fn profile(&mut self, camera: &Camera, frames: usize) -> Result<Vec<Vec<PassTiming>>> {
        let mut out = Vec::new();
        for _ in 0..frames {
            self.render(camera, FrameOutput::None)?;
            let f = self.last_frame();
            self.gpu.submit_and_wait(f)?;
            if let Some(t) = self.gpu.frame_timings(f)? {
                out.push(t);
            }
        }
        Ok(out)
    }

    /// Reloads every pipeline's shaders from `glsl/`. On a compile error the old pipelines stay.
    pub fn reload_shaders(&mut self) -> Result<usize> {
        let lib = ShaderLibrary::Directory(ShaderLibrary::source_dir());
        let ids = self.gpu.pipeline_ids();
        for id in &ids {
            self.gpu.reload_pipeline(*id, &lib)?;
        }
        Ok(ids.len())
    }
}

fn create_targets(gpu: &mut Gpu, (width, height): (u32, u32)) -> Result<FrameTargets> {
    if width == 0 || height == 0 {
        return Err(Error::Usage(format!("image size {width}x{height} is empty")));
    }
    let radiance = gpu.create_image(
        &ImageDesc::new_2d("radiance", RADIANCE_FORMAT, width, height)
            .usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::STORAGE),
    )?;
    let ds_format = gpu.caps().depth_stencil_format;
    let depth_stencil = gpu.create_image(&ImageDesc::new_2d("depth-stencil", ds_format, width, height).usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT))?;
    Ok(FrameTargets { radiance, depth_stencil, width, height })
}
