//! The reflective shadow map and the injection (digest §2.4–2.5): the light's camera, the
//! RSM's four layers, and the scatter (corrected) or gather (the document's) into the volume.

use glam::{Mat4, Vec3};

use super::config::{Config, Injection, Mode};
use super::volume::{Placement, VolumeBlock, VolumeGpu, BLOCKING_UNITS};
use crate::backend::{
    vk, Bind, BufferId, ColorTarget, ComputePipelineDesc, Gpu, GraphicsPipelineDesc, ImageDesc, ImageId, PipelineId,
    RenderTarget, RenderingDesc, SamplerDesc, SamplerId, SpecConstant, SubresourceRange,
};
use crate::error::{Error, Result};
use crate::gpu_scene::{record_draws, vertex_layout, DrawCall, GpuLight, SceneGpu};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::lighting::RADIANCE_FORMAT;
use crate::shaders::ShaderLibrary;

const LIGHT_SPOT: f32 = 1.0;
const LIGHT_DIRECTIONAL: f32 = 2.0;

/// The G-buffer pass's name (its timestamp in `profile`).
pub const GBUFFER_PASS: &str = "lpv gbuffer";

/// The light's camera over the volume and what the RSM's texels mean.
#[derive(Clone, Copy, Debug)]
pub struct LightCamera {
    pub view_proj: Mat4,
    pub spot: bool,
    /// The direction light travels (the spot light's axis).
    pub direction: Vec3,
    pub position: Vec3,
    pub intensity: Vec3,
    /// Directional: a texel's area (m²); spot: tan of the half field of view.
    pub texel: f32,
    /// cos inner, cos outer (spot).
    pub cone: [f32; 2],
    /// The RSM's clip depth per metre along the light (for the gather's depth window).
    pub depth_per_metre: f32,
    /// A bound on the flux the RSM can hold (fixed-point range).
    pub flux_bound: f32,
}

impl LightCamera {
    /// The camera of the scene's light `light` (a punctual light as uploaded) over `placement`,
    /// the RSM `size` texels per side, its window snapped to whole texels when `snap`.
    pub fn new(light: &GpuLight, placement: &Placement, size: u32, snap: bool) -> Result<LightCamera> {
        let kind = light.position[3];
        let direction = Vec3::from_slice(&light.direction[..3]).normalize_or_zero();
        let intensity = Vec3::from_slice(&light.intensity[..3]);
        let position = Vec3::from_slice(&light.position[..3]);
        let centre = placement.centre();
        let radius = 0.5 * 3f32.sqrt() * placement.n as f32 * placement.cell * 1.02;
        let up_hint = if direction.y.abs() < 0.99 { Vec3::Y } else { Vec3::X };
        if kind == LIGHT_DIRECTIONAL {
            let right = direction.cross(up_hint).normalize();
            let up = right.cross(direction);
            let texel = 2.0 * radius / size as f32;
            // Snap the window's centre to whole texels across the light so a moving volume
            // does not make the RSM's texels crawl.
            let snap = |x: f32| if snap { (x / texel).round() * texel } else { x };
            let depth = 2.0 * radius + 2.0 * placement.cell;
            let eye = right * snap(centre.dot(right))
                + up * snap(centre.dot(up))
                + direction * (centre.dot(direction) - 0.5 * depth);
            let view = Mat4::look_to_rh(eye, direction, up);
            let proj = Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.0, depth);
            Ok(LightCamera {
                view_proj: proj * view,
                spot: false,
                direction,
                position: eye,
                intensity,
                texel: texel * texel,
                cone: [1.0, 1.0],
                depth_per_metre: 1.0 / depth,
                flux_bound: intensity.max_element() * (2.0 * radius).powi(2),
            })
        } else if kind == LIGHT_SPOT {
            let cos_outer = light.cone[1].clamp(0.05, 1.0);
            let half = cos_outer.acos().max(1e-3);
            let far = (position - centre).length() + 2.0 * radius;
            let near = (0.01 * placement.cell).max(1e-4);
            let view = Mat4::look_to_rh(position, direction, up_hint);
            let proj = Mat4::perspective_rh(2.0 * half, 1.0, near, far);
            let z = (position - centre).length().max(near);
            Ok(LightCamera {
                view_proj: proj * view,
                spot: true,
                direction,
                position,
                intensity,
                texel: half.tan(),
                cone: [light.cone[0], light.cone[1]],
                depth_per_metre: far * near / ((far - near) * z * z),
                flux_bound: intensity.max_element() * 2.0 * std::f32::consts::PI,
            })
        } else {
            Err(Error::Usage(
                "lpv: a point light would need a cube RSM; light the volume with a spot or directional light".into(),
            ))
        }
    }

    /// The block every LPV pass reads.
    pub fn block(&self, placement: &Placement, config: &Config) -> VolumeBlock {
        self.block_sharing(placement, config, self.flux_bound)
    }

    /// [`LightCamera::block`] with fixed-point units that cover `flux` (at least this light's
    /// bound): the lights that inject into one volume share units over their summed bounds, so
    /// that their sums add.
    pub fn block_sharing(&self, placement: &Placement, config: &Config, flux: f32) -> VolumeBlock {
        let n = placement.n as i32;
        // Each coefficient of a cell sums at most 0.33 of the flux (COS1/π): 2³⁰ units cover it.
        let units = (1u64 << 30) as f32 / (0.34 * flux.max(self.flux_bound).max(1e-12));
        VolumeBlock {
            size: [n, n, n, n * n * n],
            origin: placement.origin.extend(placement.cell).into(),
            units: [units, 1.0 / units, BLOCKING_UNITS, 1.0 / BLOCKING_UNITS],
            rsm: [config.rsm as i32, config.samples as i32, config.transform_bug as i32, 0],
            light_view_proj: self.view_proj.to_cols_array(),
            light: self.direction.extend(if self.spot { 1.0 } else { 0.0 }).into(),
            light_pos: self.position.extend(self.depth_per_metre).into(),
            light_intensity: self.intensity.extend(self.texel).into(),
            light_cone: [
                self.cone[0],
                self.cone[1],
                if config.mode == Mode::Faithful { 1.0 } else { 0.0 },
                0.0,
            ],
            scale: if config.mode == Mode::Faithful {
                [1.0, 1.0, 0.0, 0.0]
            } else {
                let area = placement.cell * placement.cell;
                [1.0 / area, area, 0.0, 0.0]
            },
        }
    }
}

/// Surfels drawn from a viewpoint: reflected flux (a: surfel area), transmitted flux (a: 1 −
/// mean τ), position (a: 1 where drawn), normal.
pub struct SurfelMap {
    pub size: u32,
    pub layers: [ImageId; 4],
    depth: ImageId,
}

impl SurfelMap {
    fn new(gpu: &mut Gpu, name: &str, size: u32) -> Result<SurfelMap> {
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED;
        let mut made = Vec::new();
        for layer in ["flux", "transmitted", "position", "normal"] {
            made.push(gpu.create_image(
                &ImageDesc::new_2d(&format!("{name} {layer}"), RADIANCE_FORMAT, size, size).usage(usage),
            )?);
        }
        let ds = gpu.caps().depth_stencil_format;
        let depth = gpu.create_image(
            &ImageDesc::new_2d(&format!("{name} depth"), ds, size, size)
                .usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        Ok(SurfelMap {
            size,
            layers: [made[0], made[1], made[2], made[3]],
            depth,
        })
    }
}

impl SurfelMap {
    /// Its device memory: (requested bytes of the four RGBA32F layers and the depth, allocated).
    pub fn memory(&self, gpu: &Gpu) -> Result<(u64, u64)> {
        let texels = u64::from(self.size) * u64::from(self.size);
        let depth = gpu.image_memory(self.depth)?;
        let mut allocated = depth;
        for l in self.layers {
            allocated += gpu.image_memory(l)?;
        }
        Ok((4 * 16 * texels + depth, allocated))
    }
}

/// The RSM's layers, pipelines and the injection.
pub struct Rsm {
    /// The RSM itself (the first light's, where several light the volume).
    pub map: SurfelMap,
    /// The other lights' RSMs, in order.
    pub others: Vec<SurfelMap>,
    /// The camera's G-buffer, whose surfels add to the geometry volume (`gbuffer`).
    pub gbuffer: Option<SurfelMap>,
    raster: PipelineId,
    inject: PipelineId,
    /// The G-buffer's injection: skips the surfels the RSM holds.
    inject_gbuffer: PipelineId,
    gather: PipelineId,
    nearest: SamplerId,
    /// The document's 64 sample offsets in [0, 1]³.
    offsets: BufferId,
    injection: Injection,
}

impl Rsm {
    /// The pipelines, and an RSM for each of `lights` lights.
    pub fn new(
        gpu: &mut Gpu,
        shaders: &ShaderLibrary,
        states: &mut ResourceStates,
        config: &Config,
        lights: usize,
    ) -> Result<Rsm> {
        let map = SurfelMap::new(gpu, "lpv rsm", config.rsm)?;
        let others = (1..lights)
            .map(|k| SurfelMap::new(gpu, &format!("lpv rsm {k}"), config.rsm))
            .collect::<Result<Vec<_>>>()?;
        let gbuffer = if config.gbuffer > 0 {
            Some(SurfelMap::new(gpu, "lpv gbuffer", config.gbuffer)?)
        } else {
            None
        };
        let ds = gpu.caps().depth_stencil_format;
        let mut desc = GraphicsPipelineDesc::new("lpv rsm", "lpv/rsm.vert", Some("lpv/rsm.frag"));
        desc.vertex_layout = vertex_layout();
        desc.raster.cull = vk::CullModeFlags::NONE;
        desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT); 4];
        desc.depth_format = Some(ds);
        let raster = gpu.create_graphics_pipeline(&desc, shaders)?;
        let half = SpecConstant {
            id: 10,
            bits: config.half as u32,
        };
        let inject = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "lpv inject".into(),
                shader: "lpv/inject.comp".into(),
                specialization: vec![half],
            },
            shaders,
        )?;
        let inject_gbuffer = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "lpv inject gbuffer".into(),
                shader: "lpv/inject_gbuffer.comp".into(),
                specialization: vec![half],
            },
            shaders,
        )?;
        let gather = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "lpv gather".into(),
                shader: "lpv/gather.comp".into(),
                specialization: vec![half],
            },
            shaders,
        )?;
        let nearest = gpu.sampler(SamplerDesc::NEAREST_CLAMP)?;
        let offsets: Vec<[f32; 4]> = offset_table().iter().map(|o| [o[0], o[1], o[2], 0.0]).collect();
        let offsets = gpu.create_storage_buffer("lpv gather offsets", bytemuck::cast_slice(&offsets))?;
        states.forget_buffer(offsets);
        Ok(Rsm {
            map,
            others,
            gbuffer,
            raster,
            inject,
            inject_gbuffer,
            gather,
            nearest,
            offsets,
            injection: config.injection,
        })
    }

    /// Every light's RSM, the first light's first.
    pub fn maps(&self) -> impl Iterator<Item = &SurfelMap> {
        std::iter::once(&self.map).chain(&self.others)
    }

    /// Draws each light's RSM (`blocks[k]`: light k's camera over the largest volume); the
    /// first is the pass `lpv rsm`, light k's `lpv rsm k`.
    pub fn add_raster<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        scene: &'a SceneGpu,
        calls: &'a [DrawCall],
        transmittance: BufferId,
        blocks: &'a [VolumeBlock],
    ) {
        for (k, (map, block)) in self.maps().zip(blocks).enumerate() {
            let name = if k == 0 {
                "lpv rsm".to_string()
            } else {
                format!("lpv rsm {k}")
            };
            self.add_surfels(graph, &name, map, scene, calls, transmittance, block);
        }
    }

    /// The G-buffer pass: the scene from the camera (`block`: the camera as the viewpoint, no
    /// light), each texel a surfel's position, normal, area and opacity over a depth buffer.
    pub fn add_gbuffer<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        scene: &'a SceneGpu,
        calls: &'a [DrawCall],
        transmittance: BufferId,
        block: &'a VolumeBlock,
    ) {
        if let Some(map) = &self.gbuffer {
            self.add_surfels(graph, GBUFFER_PASS, map, scene, calls, transmittance, block);
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn add_surfels<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        name: &str,
        map: &SurfelMap,
        scene: &'a SceneGpu,
        calls: &'a [DrawCall],
        transmittance: BufferId,
        block: &'a VolumeBlock,
    ) {
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let mip = SubresourceRange::mip(0);
        let (layers, depth) = (map.layers, map.depth);
        let mut pass = graph.pass(name);
        for l in layers {
            pass = pass.color_attachment(l, mip, true);
        }
        pass.depth_stencil_write(depth, true)
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .buffer(
                transmittance,
                Access::StorageRead { stages: frag },
                Some("transmittance"),
            )
            .record(move |ctx| {
                let colors = layers.iter().map(|&l| RenderTarget::clear_color(l, [0.0; 4])).collect();
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors,
                    depth_stencil: Some(RenderTarget::clear_depth(depth, 1.0, 0)),
                })?;
                ctx.rec.bind_pipeline(self.raster)?;
                record_draws(ctx, scene, calls, |ctx, material| {
                    let maps = scene.material_maps[material as usize];
                    ctx.bind(&[
                        ("volume", Bind::UniformData(bytemuck::bytes_of(block))),
                        (
                            "albedo_map",
                            Bind::Sampled {
                                image: maps.albedo,
                                range: mip,
                                sampler: scene.sampler,
                            },
                        ),
                    ])
                })?;
                ctx.rec.end_rendering();
                Ok(())
            });
    }

    /// Scatters the surfels of `map` into `volume`'s fixed-point sums; with `held` (the RSM), only
    /// those the RSM does not hold.
    fn add_scatter<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        name: &str,
        map: &SurfelMap,
        held: Option<&SurfelMap>,
        volume: &'a VolumeGpu,
        block: &'a VolumeBlock,
    ) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let (mip, s) = (SubresourceRange::mip(0), self.nearest);
        let write = Access::StorageWrite { stages: compute };
        let (layers, size) = (map.layers, map.size);
        let mut pass = graph
            .pass(name)
            .sample("rsm_flux", layers[0], mip, s, compute)
            .sample("rsm_transmitted", layers[1], mip, s, compute)
            .sample("rsm_position", layers[2], mip, s, compute)
            .sample("rsm_normal", layers[3], mip, s, compute);
        if let Some(held) = held {
            pass = pass.sample("held_position", held.layers[2], mip, s, compute).sample(
                "held_normal",
                held.layers[3],
                mip,
                s,
                compute,
            );
        }
        let pipeline = if held.is_some() {
            self.inject_gbuffer
        } else {
            self.inject
        };
        pass.buffer(volume.fixed_light, write, Some("fixed_light"))
            .buffer(volume.fixed_blocking, write, Some("fixed_blocking"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[("volume", Bind::UniformData(bytemuck::bytes_of(block)))])?;
                ctx.rec.dispatch([size, size, 1])
            });
    }

    /// Injects the RSMs into `volume` (`blocks[k]`: light k's block for it): each scattered into
    /// the fixed-point sums, the first light's surfels (and the G-buffer's, with
    /// `gbuffer_block`) also into the blocking, then resolved once; or the document's gather
    /// of the first light straight into the first wavefront.
    pub fn add_injection<'a>(
        &'a self,
        graph: &mut RenderGraph<'a>,
        volume: &'a VolumeGpu,
        blocks: &'a [VolumeBlock],
        gbuffer_block: &'a VolumeBlock,
    ) {
        let block = &blocks[0];
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let mip = SubresourceRange::mip(0);
        let layers = self.map.layers;
        let write = Access::StorageWrite { stages: compute };
        let s = self.nearest;
        match self.injection {
            Injection::Scatter => {
                for (k, (map, block)) in self.maps().zip(blocks).enumerate() {
                    let name = if k == 0 {
                        format!("{} inject", volume.label)
                    } else {
                        format!("{} inject {k}", volume.label)
                    };
                    self.add_scatter(graph, &name, map, None, volume, block);
                }
                if let Some(map) = &self.gbuffer {
                    // Only blocking: the G-buffer's surfels carry no flux.
                    self.add_scatter(
                        graph,
                        &format!("{} inject gbuffer", volume.label),
                        map,
                        Some(&self.map),
                        volume,
                        gbuffer_block,
                    );
                }
                volume.add_resolve(graph, block);
            }
            Injection::Gather => {
                let n = volume.n;
                graph
                    .pass(&format!("{} gather", volume.label))
                    .sample("rsm_flux", layers[0], mip, s, compute)
                    .sample("rsm_position", layers[2], mip, s, compute)
                    .sample("rsm_normal", layers[3], mip, s, compute)
                    .buffer(self.offsets, Access::StorageRead { stages: compute }, Some("offsets"))
                    .buffer(volume.sets[0], write, Some("wavefront"))
                    .record(move |ctx| {
                        ctx.rec.bind_pipeline(self.gather)?;
                        ctx.bind(&[("volume", Bind::UniformData(bytemuck::bytes_of(block)))])?;
                        ctx.rec.dispatch([n, n, n])
                    });
            }
        }
    }
}

/// The block that injects the G-buffer's `size`² surfels into the volume the light's `block`
/// places: the light's camera stays, to find the surfels the RSM (`block.rsm[0]`² texels) holds.
pub fn gbuffer_injection_block(block: &VolumeBlock, size: u32) -> VolumeBlock {
    VolumeBlock {
        rsm: [size as i32, block.rsm[0], 0, 0],
        ..*block
    }
}

/// The block that draws the G-buffer (`light.w` = 2: the area from the pixel's footprint, no
/// flux).
pub fn gbuffer_block(block: &VolumeBlock, view_proj: [f32; 16], eye: [f32; 4], size: u32) -> VolumeBlock {
    VolumeBlock {
        rsm: [size as i32, 0, 0, 0],
        light_view_proj: view_proj,
        light: [0.0, 0.0, 0.0, 2.0],
        light_pos: [eye[0], eye[1], eye[2], 0.0],
        light_intensity: [0.0; 4],
        light_cone: [0.0; 4],
        ..*block
    }
}

/// The document's 64-entry offset texture (its contents are not given): a fixed pseudo-random
/// sequence in [0, 1]³, the same for every cell as in the document.
pub fn offset_table() -> Vec<[f32; 3]> {
    let mut state = 0x2545_f491_u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    (0..64).map(|_| [next(), next(), next()]).collect()
}
