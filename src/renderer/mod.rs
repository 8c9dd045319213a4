//! Frame assembly: the scene on the GPU, the frame targets, the configuration's lighting methods
//! and the passes around them. Every frame the renderer clears the targets to the sky (to black
//! when no method supplies a base term, and then draws the scene's depth itself), lets the base
//! term draw over it, adds the direct and indirect terms, then what the output needs (readback for captures,
//! tone mapping for the window). One clock ([`FrameClock`]) drives every method's animation.

mod frame_passes;
mod output_passes;
pub mod wind;

use glam::Mat4;

use crate::backend::{
    vk, BufferDesc, BufferId, Frame, Gpu, ImageDesc, ImageId, MemoryKind, Overlay, PassTiming, PipelineId,
    ResourceScope, SamplerDesc,
};
use crate::bake::{BakeReport, Baker};
use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::gpu_scene::{GpuLight, SceneGpu};
use crate::graph::{ExecutionReport, RenderGraph, ResourceStates};
use crate::lighting::{
    registry, Configuration, CreateContext, FrameClock, FrameContext, FrameTargets, FrameUniforms, LightingMethod,
    Term, Terms, LIGHT_MASK_FORMAT, RADIANCE_FORMAT,
};
use crate::scene::{Camera, Scene};
use crate::shaders::ShaderLibrary;
use crate::util::image_io::HdrImage;
use crate::util::timing::TimingSummary;

/// Where a frame goes besides the radiance target.
pub enum FrameOutput<'o> {
    /// Nothing: profiling.
    None,
    /// Copy radiance into a host buffer and return it.
    Readback,
    /// Tone-map into a swapchain image and leave it ready to present. With `readback`, the
    /// presented pixels are also copied to a host buffer (a screenshot of exactly what the
    /// window shows); fetch them with [`Renderer::presented_pixels`] once the frame completed.
    ///
    /// With `radiance`, the frame's radiance is also copied to the host (fetch it with
    /// [`Renderer::radiance_pixels`] once the frame completed), and an `overlay` is drawn over the
    /// tone-mapped image before it is presented.
    Present {
        image: ImageId,
        exposure: f32,
        readback: bool,
        radiance: bool,
        overlay: Option<&'o mut Overlay>,
    },
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
    /// `scene_gpu.lights` as uploaded: the light board scales these each frame and the light
    /// motion turns them.
    static_lights: Vec<GpuLight>,
    /// The scene's wind, applied to the vertex buffer at each frame's time.
    wind: Option<wind::WindPass>,
    /// The scene's environment as loaded (once) for every consumer.
    pub environment: EnvironmentMap,
    /// What frames are drawn with, and its methods in frame order (one per part).
    pub configuration: Configuration,
    methods: Vec<Box<dyn LightingMethod>>,
    /// What the methods created, freed when the configuration changes.
    method_resources: ResourceScope,
    /// The bakes the methods ran (or read from the cache) when they were created.
    pub bakes: Vec<BakeReport>,
    pub states: ResourceStates,
    pub targets: FrameTargets,
    frames: Vec<Frame>,
    frame_index: usize,
    /// Frames rendered with the current configuration (the clock).
    clock_frame: u64,
    /// The clock stands still: every frame is drawn at the same animation time.
    pub clock_paused: bool,
    passes: frame_passes::FramePasses,
    readback: Option<BufferId>,
    present_readback: Option<BufferId>,
    tonemap: Option<(PipelineId, vk::Format)>,
}

/// Creates a configuration's methods inside a resource scope; on failure, frees what the partial
/// creation made.
fn create_methods(
    configuration: &Configuration,
    ctx: &mut CreateContext<'_>,
) -> Result<(Vec<Box<dyn LightingMethod>>, ResourceScope)> {
    ctx.gpu.begin_resource_scope();
    let created = registry::create(configuration, ctx);
    let scope = ctx.gpu.end_resource_scope();
    match created {
        Ok(methods) => Ok((methods, scope)),
        Err(e) => {
            ctx.gpu.destroy_scope(&scope)?;
            forget(ctx.states, &scope);
            Err(e)
        }
    }
}

fn forget(states: &mut ResourceStates, scope: &ResourceScope) {
    for &b in &scope.buffers {
        states.forget_buffer(b);
    }
    for &i in &scope.images {
        states.forget_image(i);
    }
}

impl Renderer {
    /// Uploads the scene and creates the configuration called `name` (a method or a
    /// combination; default the scene's first method). Bakes are cached in
    /// [`Baker::default_dir`].
    pub fn new(
        gpu: Gpu,
        scene: Scene,
        name: Option<&str>,
        size: (u32, u32),
        frames_in_flight: usize,
    ) -> Result<Renderer> {
        let configuration = registry::configuration(&scene, name)?;
        Renderer::with_configuration(
            gpu,
            scene,
            configuration,
            size,
            frames_in_flight,
            Baker::new(Some(Baker::default_dir())),
        )
    }

    /// Uploads the scene and creates `configuration`'s methods, baking through `bakes`.
    pub fn with_configuration(
        gpu: Gpu,
        scene: Scene,
        configuration: Configuration,
        size: (u32, u32),
        frames_in_flight: usize,
        bakes: Baker,
    ) -> Result<Renderer> {
        Renderer::build(gpu, scene, configuration, size, frames_in_flight, bakes, 0)
    }

    /// [`Renderer::with_configuration`] with one frame in flight, for a run of `frames` frames: a
    /// method that estimates its frames warns on stderr before its large allocations when the
    /// run would pass a minute ([`crate::lighting::CreateContext::warn_cost`]).
    pub fn for_run(
        gpu: Gpu,
        scene: Scene,
        configuration: Configuration,
        size: (u32, u32),
        bakes: Baker,
        frames: usize,
    ) -> Result<Renderer> {
        Renderer::build(gpu, scene, configuration, size, 1, bakes, frames.max(1))
    }

    fn build(
        mut gpu: Gpu,
        scene: Scene,
        configuration: Configuration,
        size: (u32, u32),
        frames_in_flight: usize,
        mut bakes: Baker,
        frames: usize,
    ) -> Result<Renderer> {
        scene.check_methods(&registry::schemas())?;
        let shaders = ShaderLibrary::Embedded;
        let mut states = ResourceStates::default();
        let environment = EnvironmentMap::of_scene(&scene)?;
        let scene_gpu = SceneGpu::upload(&mut gpu, &mut states, &scene, &environment)?;
        let wind = wind::WindPass::new(&mut gpu, &mut states, &shaders, &scene, &scene_gpu)?;
        let (methods, method_resources) = {
            let mut ctx = CreateContext {
                gpu: &mut gpu,
                shaders: &shaders,
                states: &mut states,
                scene: &scene,
                scene_gpu: &scene_gpu,
                environment: &environment,
                bakes: &mut bakes,
                terms: Terms::NONE,
                frames,
            };
            create_methods(&configuration, &mut ctx)?
        };
        let passes = frame_passes::FramePasses::new(&mut gpu, &shaders)?;
        let mask = methods.iter().any(|m| m.uses_light_mask());
        let targets = create_targets(&mut gpu, size, mask)?;
        let frames = (0..frames_in_flight.max(1))
            .map(|_| gpu.create_frame())
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let static_lights = scene_gpu.lights.clone();
        Ok(Renderer {
            gpu,
            shaders,
            scene,
            scene_gpu,
            static_lights,
            wind,
            environment,
            configuration,
            methods,
            method_resources,
            bakes: bakes.take_reports(),
            states,
            targets,
            frames,
            frame_index: 0,
            clock_frame: 0,
            clock_paused: false,
            passes,
            readback: None,
            present_readback: None,
            tonemap: None,
        })
    }

    /// Switches to another of the scene's configurations (the demo's method key): the new
    /// methods are created and the clock restarts.
    pub fn set_configuration(&mut self, configuration: Configuration) -> Result<()> {
        self.set_configuration_with(configuration, &mut Baker::new(Some(Baker::default_dir())))
    }

    /// [`Renderer::set_configuration`] baking through `bakes` (a cache-only baker: a switch
    /// that fails rather than bake).
    pub fn set_configuration_with(&mut self, configuration: Configuration, bakes: &mut Baker) -> Result<()> {
        self.gpu.wait_idle()?;
        let (methods, resources) = {
            let mut ctx = CreateContext {
                gpu: &mut self.gpu,
                shaders: &self.shaders,
                states: &mut self.states,
                scene: &self.scene,
                scene_gpu: &self.scene_gpu,
                environment: &self.environment,
                bakes,
                terms: Terms::NONE,
                frames: 0,
            };
            create_methods(&configuration, &mut ctx)?
        };
        // The old methods' objects go once nothing can use them (the device is idle, and the
        // methods holding their ids are dropped first).
        self.methods = methods;
        let old = std::mem::replace(&mut self.method_resources, resources);
        self.gpu.destroy_scope(&old)?;
        forget(&mut self.states, &old);
        self.configuration = configuration;
        self.bakes = bakes.take_reports();
        self.clock_frame = 0;
        self.keep_light_mask_for_methods()
    }

    /// The device memory of the methods' resources, as each method itemises it.
    pub fn method_memory(&self) -> Result<Vec<crate::lighting::MemoryItem>> {
        let mut out = Vec::new();
        for m in &self.methods {
            out.extend(m.memory(&self.gpu)?);
        }
        Ok(out)
    }

    /// What the methods left out of the last frame (see [`LightingMethod::warnings`]); call after
    /// that frame has finished.
    pub fn method_warnings(&mut self) -> Result<Vec<String>> {
        let mut out = Vec::new();
        for m in &self.methods {
            out.extend(m.warnings(&mut self.gpu)?);
        }
        Ok(out)
    }

    /// What the last frame did that its timings do not show (see
    /// [`LightingMethod::frame_notes`]); call after that frame has finished.
    pub fn method_frame_notes(&mut self) -> Result<Vec<String>> {
        let mut out = Vec::new();
        for m in &self.methods {
            out.extend(m.frame_notes(&mut self.gpu)?);
        }
        Ok(out)
    }

    /// One line per method whose `frames` frames are estimated past a minute (see
    /// [`LightingMethod::frame_cost`]), naming the scene: said before the first frame.
    pub fn cost_warnings(&self, frames: usize) -> Vec<String> {
        (self.methods.iter())
            .filter_map(|m| crate::lighting::cost_warning(&self.scene, m.name(), &m.frame_cost()?, frames))
            .collect()
    }

    /// The names of the configuration's methods, in frame order.
    pub fn method_names(&self) -> Vec<&'static str> {
        self.methods.iter().map(|m| m.name()).collect()
    }

    /// Recreates the size-dependent targets.
    pub fn resize(&mut self, size: (u32, u32)) -> Result<()> {
        if (self.targets.width, self.targets.height) == size {
            return Ok(());
        }
        self.gpu.wait_idle()?;
        let mask = self.targets.light_mask.is_some();
        let images = [self.targets.radiance, self.targets.depth_stencil];
        for id in images.into_iter().chain(self.targets.light_mask) {
            self.gpu.destroy_image(id);
            self.states.forget_image(id);
        }
        if let Some(b) = self.readback.take() {
            self.gpu.destroy_buffer(b);
            self.states.forget_buffer(b);
        }
        self.targets = create_targets(&mut self.gpu, size, mask)?;
        Ok(())
    }

    /// Creates or drops the light mask as the methods now ask (after a switch of configuration).
    fn keep_light_mask_for_methods(&mut self) -> Result<()> {
        let wanted = self.methods.iter().any(|m| m.uses_light_mask());
        match (wanted, self.targets.light_mask) {
            (true, None) => {
                let size = (self.targets.width, self.targets.height);
                self.targets.light_mask = Some(create_light_mask(&mut self.gpu, size)?);
            }
            (false, Some(id)) => {
                self.gpu.destroy_image(id);
                self.states.forget_image(id);
                self.targets.light_mask = None;
            }
            _ => {}
        }
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
    pub fn render(&mut self, camera: &Camera, mut output: FrameOutput<'_>) -> Result<FrameResult> {
        let uniforms = self.uniforms(camera);
        self.prepare_output(&output)?;
        let display_sampler = self.gpu.sampler(SamplerDesc::NEAREST_CLAMP)?;
        let frame = self.frames[self.frame_index % self.frames.len()];
        self.frame_index += 1;
        let clock = FrameClock::at(self.clock_frame);
        if !self.clock_paused {
            self.clock_frame += 1;
        }
        self.animate_lights(clock.time_s);
        let terms: Vec<Terms> = self.configuration.parts.iter().map(|p| p.terms).collect();
        self.prepare_methods(uniforms, clock, &terms)?;

        // The graph borrows the renderer's parts field by field, so that executing it can update
        // `states` while they are borrowed.
        let mut graph = RenderGraph::new();
        let scene = ScenePasses {
            gpu: &self.gpu,
            scene_gpu: &self.scene_gpu,
            wind: self.wind.as_ref(),
            passes: &self.passes,
            methods: &self.methods,
            targets: self.targets,
            uniforms,
            clock,
        };
        scene.add(&mut graph, &terms)?;
        let outputs = output_passes::OutputResources {
            readback: self.readback,
            present_readback: self.present_readback,
            tonemap: self.tonemap.map(|(pipeline, _)| pipeline),
            display_sampler,
        };
        outputs.add(&mut graph, self.targets, &mut output)?;
        let report = execute_frame(&self.gpu, frame, graph, &mut self.states)?;
        let image = match output {
            FrameOutput::Readback => self.wait_for_radiance(frame)?,
            _ => None,
        };
        Ok(FrameResult { report, image })
    }

    /// Creates what `output` copies or draws into, on its first use or when its size or format
    /// changed: the radiance read-back buffer, the presented-pixels buffer, the tone-map pipeline.
    fn prepare_output(&mut self, output: &FrameOutput<'_>) -> Result<()> {
        let radiance_readback = match output {
            FrameOutput::Readback => true,
            FrameOutput::Present { radiance, .. } => *radiance,
            FrameOutput::None => false,
        };
        if radiance_readback && self.readback.is_none() {
            let size = self.targets.width as u64 * self.targets.height as u64 * 16;
            self.readback = Some(self.gpu.create_buffer(&BufferDesc {
                name: "radiance readback".into(),
                size,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                memory: MemoryKind::GpuToCpu,
            })?);
        }
        if let FrameOutput::Present { image, readback, .. } = output {
            let d = self.gpu.image_desc(*image)?;
            let (format, bytes) = (d.format, d.extent.width as u64 * d.extent.height as u64 * 4);
            if *readback {
                self.prepare_present_readback(bytes)?;
            }
            if self.tonemap.map(|t| t.1) != Some(format) {
                let pipeline = output_passes::create_tonemap(&mut self.gpu, &self.shaders, format)?;
                self.tonemap = Some((pipeline, format));
            }
        }
        Ok(())
    }

    /// (Re)creates the presented-pixels buffer unless it already holds `bytes`.
    fn prepare_present_readback(&mut self, bytes: u64) -> Result<()> {
        let current = self
            .present_readback
            .map(|b| self.gpu.buffer_desc(b).map(|d| d.size).unwrap_or(0));
        if current == Some(bytes) {
            return Ok(());
        }
        if let Some(old) = self.present_readback.take() {
            self.gpu.destroy_buffer(old);
            self.states.forget_buffer(old);
        }
        self.present_readback = Some(self.gpu.create_buffer(&BufferDesc {
            name: "presented pixels".into(),
            size: bytes,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuToCpu,
        })?);
        Ok(())
    }

    /// Sets the uploaded lights to their state at `time_s`: the light board's intensities and the
    /// light motion's direction. Runs before the methods' `prepare`, so every method that reads
    /// the lights per frame sees this frame's lights.
    fn animate_lights(&mut self, time_s: f32) {
        if self.scene.light_board.is_some() {
            // `raster_lights` keeps one entry per scene light, in order.
            let factors = self.scene.light_factors(time_s);
            for ((light, base), f) in self.scene_gpu.lights.iter_mut().zip(&self.static_lights).zip(factors) {
                light.intensity = [
                    base.intensity[0] * f,
                    base.intensity[1] * f,
                    base.intensity[2] * f,
                    base.intensity[3],
                ];
            }
        }
        if let Some(m) = &self.scene.light_motion {
            if let (Some(light), Some(base)) = (self.scene_gpu.lights.get_mut(m.light), self.static_lights.get(m.light))
            {
                let d = m.direction_at(glam::Vec3::from_slice(&base.direction[..3]), time_s);
                light.direction = d.extend(0.0).into();
            }
        }
    }

    /// Lets every method update its per-frame state before the frame's passes are recorded.
    fn prepare_methods(&mut self, uniforms: FrameUniforms, clock: FrameClock, terms: &[Terms]) -> Result<()> {
        for (method, &terms) in self.methods.iter_mut().zip(terms) {
            let ctx = FrameContext {
                gpu: &self.gpu,
                scene: &self.scene_gpu,
                targets: self.targets,
                uniforms,
                clock,
                terms,
            };
            method.prepare(&ctx)?;
        }
        Ok(())
    }

    /// Submits `frame`, waits for it and reads the radiance it copied to the host (`None` when the
    /// bytes do not make an image of the target's size).
    fn wait_for_radiance(&self, frame: Frame) -> Result<Option<HdrImage>> {
        self.gpu.submit_and_wait(frame)?;
        let rb = self
            .readback
            .ok_or_else(|| Error::Internal("readback buffer missing".into()))?;
        let bytes = self.gpu.read_buffer(rb)?;
        Ok(HdrImage::from_rgba32f_bytes(
            self.targets.width,
            self.targets.height,
            &bytes,
        ))
    }

    /// The pixels of the last frame rendered with `Present { readback: true }`, as 8-bit RGBA
    /// (display-encoded, as the window shows them). Call after that frame has completed.
    pub fn presented_pixels(&self, image: ImageId) -> Result<image::RgbaImage> {
        let rb = self
            .present_readback
            .ok_or_else(|| Error::Internal("no frame was presented with readback".into()))?;
        let d = self.gpu.image_desc(image)?;
        let mut bytes = self.gpu.read_buffer(rb)?;
        if matches!(d.format, vk::Format::B8G8R8A8_SRGB | vk::Format::B8G8R8A8_UNORM) {
            for px in bytes.chunks_exact_mut(4) {
                px.swap(0, 2);
            }
        }
        image::RgbaImage::from_raw(d.extent.width, d.extent.height, bytes)
            .ok_or_else(|| Error::Internal("presented pixels do not match the image size".into()))
    }

    /// The radiance of the last frame rendered with `Present { radiance: true }` (or
    /// `Readback`). Call after that frame has completed.
    pub fn radiance_pixels(&self) -> Result<HdrImage> {
        let rb = self
            .readback
            .ok_or_else(|| Error::Usage("no frame was rendered with a radiance readback".into()))?;
        let bytes = self.gpu.read_buffer(rb)?;
        HdrImage::from_rgba32f_bytes(self.targets.width, self.targets.height, &bytes)
            .ok_or_else(|| Error::Usage("radiance readback does not match the target size".into()))
    }

    /// Frames rendered with the current configuration: the clock's frame, what animation has
    /// moved the scene to.
    pub fn clock_frame(&self) -> u64 {
        self.clock_frame
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
        self.profile_each(camera, frames, |t| out.push(t))?;
        Ok(out)
    }

    /// Renders `frames` frames as [`Renderer::profile`] does, handing each frame's timings to
    /// `summary` instead of keeping them: memory that does not grow with the frames' names.
    pub fn profile_into(&mut self, camera: &Camera, frames: usize, summary: &mut TimingSummary) -> Result<()> {
        self.profile_each(camera, frames, |t| summary.add(&t))
    }

    fn profile_each(&mut self, camera: &Camera, frames: usize, mut each: impl FnMut(Vec<PassTiming>)) -> Result<()> {
        for _ in 0..frames {
            self.render(camera, FrameOutput::None)?;
            let f = self.last_frame();
            self.gpu.submit_and_wait(f)?;
            if let Some(t) = self.gpu.frame_timings(f)? {
                each(t);
            }
        }
        Ok(())
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

/// What the scene part of a frame draws with: the renderer's passes around the methods, and the
/// methods' own.
struct ScenePasses<'a> {
    gpu: &'a Gpu,
    scene_gpu: &'a SceneGpu,
    wind: Option<&'a wind::WindPass>,
    passes: &'a frame_passes::FramePasses,
    methods: &'a [Box<dyn LightingMethod>],
    targets: FrameTargets,
    uniforms: FrameUniforms,
    clock: FrameClock,
}

impl<'a> ScenePasses<'a> {
    /// The wind, the background (targets cleared and, under a base term, the sky everywhere: the
    /// base then draws over it, so the sky stays where no geometry is), the scene's depth when no
    /// method draws a base term, then each method's passes for its `terms`.
    fn add(&self, graph: &mut RenderGraph<'a>, terms: &[Terms]) -> Result<()> {
        if let Some(w) = self.wind {
            w.add(graph, self.scene_gpu, self.clock.time_s);
        }
        let has_base = terms.iter().any(|t| t.has(Term::Base));
        self.passes
            .add_background(graph, self.scene_gpu, self.targets, &self.uniforms, has_base);
        if !has_base {
            self.passes
                .add_depth(graph, self.scene_gpu, self.targets, &self.uniforms);
        }
        for (method, &terms) in self.methods.iter().zip(terms) {
            let ctx = FrameContext {
                gpu: self.gpu,
                scene: self.scene_gpu,
                targets: self.targets,
                uniforms: self.uniforms,
                clock: self.clock,
                terms,
            };
            method.add_passes(graph, &ctx)?;
        }
        Ok(())
    }
}

/// Records `graph` into `frame`'s command buffer (not yet submitted).
fn execute_frame(
    gpu: &Gpu,
    frame: Frame,
    graph: RenderGraph<'_>,
    states: &mut ResourceStates,
) -> Result<ExecutionReport> {
    let mut rec = gpu.begin_frame(frame)?;
    rec.begin_scope("frame");
    let report = graph.execute(&mut rec, states)?;
    rec.end_scope();
    rec.finish()?;
    Ok(report)
}

/// The frame's targets; `light_mask`: with the light mask a method asks for.
fn create_targets(gpu: &mut Gpu, (width, height): (u32, u32), light_mask: bool) -> Result<FrameTargets> {
    if width == 0 || height == 0 {
        return Err(Error::Usage(format!("image size {width}x{height} is empty")));
    }
    let radiance = gpu.create_image(&ImageDesc::new_2d("radiance", RADIANCE_FORMAT, width, height).usage(
        vk::ImageUsageFlags::COLOR_ATTACHMENT
            | vk::ImageUsageFlags::SAMPLED
            | vk::ImageUsageFlags::TRANSFER_SRC
            | vk::ImageUsageFlags::STORAGE,
    ))?;
    let ds_format = gpu.caps().depth_stencil_format;
    let depth_stencil = gpu.create_image(
        &ImageDesc::new_2d("depth-stencil", ds_format, width, height)
            .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
    )?;
    let light_mask = match light_mask {
        true => Some(create_light_mask(gpu, (width, height))?),
        false => None,
    };
    Ok(FrameTargets {
        radiance,
        depth_stencil,
        light_mask,
        width,
        height,
    })
}

fn create_light_mask(gpu: &mut Gpu, (width, height): (u32, u32)) -> Result<ImageId> {
    let desc = ImageDesc::new_2d("light mask", LIGHT_MASK_FORMAT, width, height)
        .usage(vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED);
    Ok(gpu.create_image(&desc)?)
}
