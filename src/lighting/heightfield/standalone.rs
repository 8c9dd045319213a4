//! The height-field passes without a camera: run them for one time step and read back the
//! shading image, a light's unclamped radiance, or the horizons. Used by the tests and by
//! `measure`; everything runs through the frame graph exactly as in a frame.

use crate::backend::{vk, BufferDesc, BufferId, Frame, Gpu, ImageId, MemoryKind, PassTiming, SubresourceRange};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::scene::{MethodDecl, Scene};
use crate::shaders::ShaderLibrary;

use super::gpu::{FieldInputs, HeightfieldGpu};
use super::settings::{Horizon, Settings};

pub struct Standalone {
    pub gpu: Gpu,
    pub core: HeightfieldGpu,
    states: ResourceStates,
    frame: Frame,
    readback: BufferId,
}

impl Standalone {
    /// `decl` names `heightfield_pyramid` or `heightfield_bruteforce` with its parameters.
    pub fn new(mut gpu: Gpu, scene: &Scene, decl: &MethodDecl) -> Result<Standalone> {
        scene
            .refuse_translucency(&format!("the {} method", decl.name))
            .map_err(Error::Usage)?;
        let horizon = if decl.name == super::BRUTE_FORCE {
            Horizon::BruteForce
        } else {
            Horizon::Pyramid
        };
        let settings = Settings::from_decl(decl, horizon)?;
        let env = crate::environment::EnvironmentMap::of_scene(scene)?;
        let inputs = FieldInputs::from_scene(scene, &env, &decl.name)?;
        let mut states = ResourceStates::default();
        let mut bakes = crate::bake::Baker::new(Some(crate::bake::Baker::default_dir()));
        let core = HeightfieldGpu::new(
            &mut gpu,
            &ShaderLibrary::Embedded,
            &mut states,
            &mut bakes,
            settings,
            inputs,
        )?;
        let frame = gpu.create_frame()?;
        let bytes = core.res as u64 * core.res as u64 * 16;
        let readback = gpu.create_buffer(&BufferDesc {
            name: "hf readback".into(),
            size: bytes,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuToCpu,
        })?;
        Ok(Standalone {
            gpu,
            core,
            states,
            frame,
            readback,
        })
    }

    fn copy_out<'a>(graph: &mut RenderGraph<'a>, image: ImageId, layer: u32, rb: BufferId) {
        graph
            .pass("hf read back")
            .transfer_read(image, SubresourceRange::mip_layer(0, layer))
            .buffer(rb, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.copy_image_to_buffer(image, 0, layer, rb));
        graph
            .pass("hf host")
            .buffer(rb, Access::HostRead, None)
            .record(|_| Ok(()));
    }

    fn pixels(&self) -> Result<Vec<[f32; 4]>> {
        let bytes = self.gpu.read_buffer(self.readback)?;
        Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec())
    }

    /// Runs every pass at time `t` and returns the shading image (res², row-major, rgba):
    /// exit radiance over albedo.
    pub fn shading(&mut self, t: f32) -> Result<Vec<[f32; 4]>> {
        self.image_after_frame(t, None)
    }

    /// Runs every pass at time `t` and returns light `k`'s radiance before accumulation
    /// (unclamped).
    pub fn light_radiance(&mut self, t: f32, k: usize) -> Result<Vec<[f32; 4]>> {
        if k >= self.core.inputs.lights.len() {
            return Err(Error::Usage(format!(
                "the scene has {} sphere light(s), no light {k}",
                self.core.inputs.lights.len()
            )));
        }
        self.image_after_frame(t, Some(k))
    }

    /// Runs every pass at time `t` and returns every light's radiance before accumulation
    /// (unclamped), one image per light.
    pub fn lights_radiance(&mut self, t: f32) -> Result<Vec<Vec<[f32; 4]>>> {
        let n = self.core.inputs.lights.len();
        let res = self.core.res as u64;
        let bytes = res * res * 16;
        let buffers = (0..n)
            .map(|k| {
                self.gpu.create_buffer(&BufferDesc {
                    name: format!("hf light {k} readback"),
                    size: bytes,
                    usage: vk::BufferUsageFlags::TRANSFER_DST,
                    memory: MemoryKind::GpuToCpu,
                })
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let result = (|| {
            let core = &self.core;
            let mut graph = RenderGraph::new();
            core.add_compute_passes(&mut graph, t)?;
            for (k, &rb) in buffers.iter().enumerate() {
                let image = core.light_radiance;
                graph
                    .pass("hf read back")
                    .transfer_read(image, SubresourceRange::mip_layer(0, k as u32))
                    .buffer(rb, Access::TransferWrite, None)
                    .record(move |ctx| ctx.rec.copy_image_to_buffer(image, 0, k as u32, rb));
                graph
                    .pass("hf host")
                    .buffer(rb, Access::HostRead, None)
                    .record(|_| Ok(()));
            }
            run_graph(&self.gpu, &mut self.states, self.frame, graph)?;
            buffers
                .iter()
                .map(|&b| Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&self.gpu.read_buffer(b)?).to_vec()))
                .collect::<Result<Vec<_>>>()
        })();
        for b in buffers {
            self.gpu.destroy_buffer(b);
            self.states.forget_buffer(b);
        }
        result
    }

    fn image_after_frame(&mut self, t: f32, light: Option<usize>) -> Result<Vec<[f32; 4]>> {
        let core = &self.core;
        let rb = self.readback;
        let mut graph = RenderGraph::new();
        core.add_compute_passes(&mut graph, t)?;
        match light {
            None => Self::copy_out(&mut graph, core.shading, 0, rb),
            Some(k) => Self::copy_out(&mut graph, core.light_radiance, k as u32, rb),
        }
        run_graph(&self.gpu, &mut self.states, self.frame, graph)?;
        self.pixels()
    }

    /// Runs every pass at time `t` and returns the level-0 heights the passes used (res²,
    /// row-major, metres).
    pub fn heights(&mut self, t: f32) -> Result<Vec<f32>> {
        let core = &self.core;
        let rb = self.readback;
        let mut graph = RenderGraph::new();
        core.add_compute_passes(&mut graph, t)?;
        Self::copy_out(&mut graph, core.heights, 0, rb);
        run_graph(&self.gpu, &mut self.states, self.frame, graph)?;
        let n = (core.res * core.res) as usize;
        let bytes = self.gpu.read_buffer(rb)?;
        Ok(bytemuck::cast_slice::<u8, f32>(&bytes)[..n].to_vec())
    }

    /// The horizons (radians) at time `t`: `nphi` blocks of res² values, direction-major; the
    /// environment's, or light `k`'s (truncated at its planar distance).
    pub fn horizons(&mut self, t: f32, light: Option<usize>) -> Result<Vec<f32>> {
        Ok(self.horizons_timed(t, light)?.0)
    }

    /// `horizons`, with that frame's GPU pass timings (the horizon kernel is "hf horizons"; empty
    /// where the device cannot time passes).
    pub fn horizons_timed(&mut self, t: f32, light: Option<usize>) -> Result<(Vec<f32>, Vec<PassTiming>)> {
        let res = self.core.res as u64;
        let n = self.core.settings.nphi as u64 * res * res;
        let out = self.gpu.create_buffer(&BufferDesc {
            name: "hf horizons".into(),
            size: 4 * n,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuToCpu,
        })?;
        let result = (|| {
            let core = &self.core;
            let mut graph = RenderGraph::new();
            core.add_compute_passes(&mut graph, t)?;
            core.add_horizon_pass(&mut graph, out, light);
            graph
                .pass("hf host")
                .buffer(out, Access::HostRead, None)
                .record(|_| Ok(()));
            run_graph(&self.gpu, &mut self.states, self.frame, graph)?;
            let timings = self.gpu.frame_timings(self.frame)?.unwrap_or_default();
            Ok((
                bytemuck::cast_slice::<u8, f32>(&self.gpu.read_buffer(out)?).to_vec(),
                timings,
            ))
        })();
        self.gpu.destroy_buffer(out);
        self.states.forget_buffer(out);
        result
    }

    /// Runs every pass at time `t` `frames` times and returns each frame's GPU pass timings.
    pub fn profile(&mut self, t: f32, frames: usize) -> Result<Vec<Vec<PassTiming>>> {
        let mut out = Vec::new();
        for _ in 0..frames {
            let mut graph = RenderGraph::new();
            self.core.add_compute_passes(&mut graph, t)?;
            graph.output_image(self.core.shading);
            run_graph(&self.gpu, &mut self.states, self.frame, graph)?;
            if let Some(timings) = self.gpu.frame_timings(self.frame)? {
                out.push(timings);
            }
        }
        Ok(out)
    }

    /// The validation messages produced so far (taken: a second call returns only new ones).
    pub fn validation_messages(&self) -> Vec<String> {
        self.gpu.validation_log().take()
    }
}

fn run_graph(gpu: &Gpu, states: &mut ResourceStates, frame: Frame, graph: RenderGraph<'_>) -> Result<()> {
    graph.run_and_wait(gpu, frame, states, "frame")?;
    Ok(())
}
