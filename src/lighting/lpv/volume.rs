//! The volume on the GPU: its placement, the uniform block every LPV pass reads, the sets (two
//! wavefronts ping-ponged and the accumulation), the fixed-point injection sums and the
//! geometry volume; the resolve and propagation passes, one compute dispatch per iteration; and
//! reading a set back for tests.

use bytemuck::{Pod, Zeroable};
use glam::{IVec3, Vec3};

use super::config::Config;
use super::grid::{self, Grid};
use crate::backend::{vk, Bind, BufferId, ComputePipelineDesc, Gpu, PipelineId, SpecConstant};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::shaders::ShaderLibrary;

/// Matches `VolumeBlock` in glsl/lpv/volume.glsl (std140: every member 16-byte aligned).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct VolumeBlock {
    pub size: [i32; 4],
    pub origin: [f32; 4],
    pub units: [f32; 4],
    pub rsm: [i32; 4],
    pub light_view_proj: [f32; 16],
    pub light: [f32; 4],
    pub light_pos: [f32; 4],
    pub light_intensity: [f32; 4],
    pub light_cone: [f32; 4],
    /// x: what a set stores per W/sr of a cell's SH coefficient, y: its inverse. The corrected
    /// mode stores them over the cell's area (1/cell²), so that the values are those of
    /// irradiance at any scale of the scene: W/sr alone grows as the square of the scene's
    /// size, and a model in millimetres or centimetres left the fp16 sets' range (its indirect
    /// light rounded to nothing). The document's mode stores its own display-like values (1).
    pub scale: [f32; 4],
}

/// Fixed-point units per unit of blocking potential: range ±2048 per corner.
pub const BLOCKING_UNITS: f32 = (1 << 20) as f32;

/// Where the volume lies: `n`³ cubic cells of side `cell` from the corner `origin`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub origin: Vec3,
    pub cell: f32,
    pub n: u32,
}

impl Placement {
    /// The cube over the box `min`–`max` with a cell of margin on each side, its corner on the
    /// lattice of its cells (so it does not move while the box does not).
    pub fn fit(min: Vec3, max: Vec3, n: u32) -> Placement {
        let extent = (max - min).max_element().max(1e-3);
        let cell = extent / (n as f32 - 2.0).max(1.0);
        let centre = 0.5 * (min + max);
        let origin = ((centre - Vec3::splat(0.5 * n as f32 * cell)) / cell).floor() * cell;
        Placement { origin, cell, n }
    }

    /// The cube of side `side` around `centre`, its corner snapped to the lattice of its cells
    /// (a cascade following the camera moves in whole cells).
    pub fn around(centre: Vec3, side: f32, n: u32) -> Placement {
        let cell = side / n as f32;
        let origin = ((centre - Vec3::splat(0.5 * side)) / cell).round() * cell;
        Placement { origin, cell, n }
    }

    pub fn centre(&self) -> Vec3 {
        self.origin + Vec3::splat(0.5 * self.n as f32 * self.cell)
    }

    /// The cell holding world point `p` (may be outside).
    pub fn cell_of(&self, p: Vec3) -> IVec3 {
        ((p - self.origin) / self.cell).floor().as_ivec3()
    }
}

/// Bytes of one set: 3 channels × 4 coefficients per cell at 2 or 4 bytes.
pub fn set_bytes(n: u32, half: bool) -> u64 {
    (n as u64).pow(3) * 3 * if half { 8 } else { 16 }
}

/// A set's words from three channels' grids.
pub fn encode(channels: &[Grid; 3], half: bool) -> Vec<u32> {
    let cells = channels[0].cells.len();
    let mut out = Vec::with_capacity(cells * 3 * if half { 2 } else { 4 });
    for i in 0..cells {
        for ch in channels {
            let c = ch.cells[i].map(|x| x as f32);
            if half {
                out.push(pack_half(c[0], c[1]));
                out.push(pack_half(c[2], c[3]));
            } else {
                out.extend(c.map(f32::to_bits));
            }
        }
    }
    out
}

/// Three channels' grids from a set's words.
pub fn decode(words: &[u32], n: u32, half: bool) -> [Grid; 3] {
    let mut out = [Grid::cube(n as usize), Grid::cube(n as usize), Grid::cube(n as usize)];
    let per = if half { 2 } else { 4 };
    for (i, cell) in words.chunks_exact(3 * per).enumerate().take(out[0].cells.len()) {
        for (ch, g) in out.iter_mut().enumerate() {
            let w = &cell[ch * per..(ch + 1) * per];
            let c = if half {
                let (a, b) = (unpack_half(w[0]), unpack_half(w[1]));
                [a.0, a.1, b.0, b.1]
            } else {
                [0, 1, 2, 3].map(|k| f32::from_bits(w[k]))
            };
            g.cells[i] = c.map(|x| x as f64);
        }
    }
    out
}

fn pack_half(a: f32, b: f32) -> u32 {
    half::f16::from_f32(a).to_bits() as u32 | (half::f16::from_f32(b).to_bits() as u32) << 16
}

fn unpack_half(w: u32) -> (f32, f32) {
    (
        half::f16::from_bits(w as u16).to_f32(),
        half::f16::from_bits((w >> 16) as u16).to_f32(),
    )
}

/// The volume's buffers and its compute pipelines.
pub struct VolumeGpu {
    /// Names its passes: "lpv", or "lpv cascade k".
    pub label: String,
    pub n: u32,
    pub half: bool,
    /// Wavefronts, ping-ponged by the propagation (the document's scheme: the whole volume).
    pub sets: [BufferId; 2],
    pub accumulation: BufferId,
    pub fixed_light: BufferId,
    pub fixed_blocking: BufferId,
    /// Blocking potential per cell corner (fp32 SH).
    pub blocking: BufferId,
    /// The blocking potential at each cell's three low faces.
    blocking_faces: BufferId,
    propagate: PipelineId,
    faces: PipelineId,
    occlusion: bool,
    resolve: PipelineId,
    iterations: u32,
    faithful: bool,
}

fn storage(gpu: &mut Gpu, states: &mut ResourceStates, name: &str, bytes: u64) -> Result<BufferId> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
    let id = gpu.create_buffer_init(name, usage, &vec![0u8; bytes as usize])?;
    states.forget_buffer(id);
    Ok(id)
}

impl VolumeGpu {
    pub fn new(
        gpu: &mut Gpu,
        shaders: &ShaderLibrary,
        states: &mut ResourceStates,
        config: &Config,
        label: &str,
    ) -> Result<VolumeGpu> {
        let n = config.grid;
        let cells = (n as u64).pow(3);
        let bytes = set_bytes(n, config.half);
        let sets = [
            storage(gpu, states, "lpv wavefront a", bytes)?,
            storage(gpu, states, "lpv wavefront b", bytes)?,
        ];
        let accumulation = storage(gpu, states, "lpv accumulation", bytes)?;
        let fixed_light = storage(gpu, states, "lpv injection sums", cells * 12 * 4)?;
        let fixed_blocking = storage(gpu, states, "lpv blocking sums", cells * 4 * 4)?;
        let blocking = storage(gpu, states, "lpv geometry volume", cells * 16)?;
        let blocking_faces = storage(gpu, states, "lpv geometry volume faces", cells * 3 * 16)?;
        let half = SpecConstant {
            id: 10,
            bits: config.half as u32,
        };
        let side = if config.published_omega {
            grid::OMEGA_SIDE_PUBLISHED
        } else {
            grid::omega_side()
        };
        let propagate = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "lpv propagate".into(),
                shader: "lpv/propagate.comp".into(),
                specialization: vec![
                    SpecConstant {
                        id: 0,
                        bits: config.faithful_propagation() as u32,
                    },
                    SpecConstant {
                        id: 1,
                        bits: config.clamp as u32,
                    },
                    SpecConstant {
                        id: 2,
                        bits: config.occlusion as u32,
                    },
                    SpecConstant {
                        id: 3,
                        bits: (grid::omega_front() as f32).to_bits(),
                    },
                    SpecConstant {
                        id: 4,
                        bits: (side as f32).to_bits(),
                    },
                    half,
                ],
            },
            shaders,
        )?;
        let resolve = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "lpv resolve".into(),
                shader: "lpv/resolve.comp".into(),
                specialization: vec![half],
            },
            shaders,
        )?;
        let faces = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "lpv blocking faces".into(),
                shader: "lpv/blocking_faces.comp".into(),
                specialization: vec![half],
            },
            shaders,
        )?;
        Ok(VolumeGpu {
            label: label.to_string(),
            n,
            half: config.half,
            sets,
            accumulation,
            fixed_light,
            fixed_blocking,
            blocking,
            blocking_faces,
            propagate,
            faces,
            occlusion: config.occlusion && !config.faithful_propagation(),
            resolve,
            iterations: config.iterations,
            faithful: config.faithful_propagation(),
        })
    }

    /// Device memory per group of buffers: (group, requested bytes, allocated bytes).
    pub fn memory(&self, gpu: &Gpu) -> Result<Vec<(String, u64, u64)>> {
        let groups = [
            (
                "sets (2 wavefronts + accumulation)",
                vec![self.sets[0], self.sets[1], self.accumulation],
            ),
            ("injection sums", vec![self.fixed_light]),
            (
                "geometry volume (sums, corners, faces)",
                vec![self.fixed_blocking, self.blocking, self.blocking_faces],
            ),
        ];
        let mut out = Vec::new();
        for (name, ids) in groups {
            let (mut requested, mut allocated) = (0, 0);
            for id in ids {
                requested += gpu.buffer_desc(id)?.size;
                allocated += gpu.buffer_memory(id)?;
            }
            out.push((format!("{} {name}", self.label), requested, allocated));
        }
        Ok(out)
    }

    /// The set the look-up reads: the accumulation, or the document's last iteration.
    pub fn result(&self) -> BufferId {
        if self.faithful {
            self.sets[(self.iterations % 2) as usize]
        } else {
            self.accumulation
        }
    }

    /// The injection sums made the first wavefront, the accumulation and the geometry volume.
    pub fn add_resolve<'a>(&'a self, graph: &mut RenderGraph<'a>, block: &'a VolumeBlock) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let write = Access::StorageWrite { stages: compute };
        let cells = self.n.pow(3);
        graph
            .pass(&format!("{} resolve", self.label))
            .buffer(self.fixed_light, write, Some("fixed_light"))
            .buffer(self.fixed_blocking, write, Some("fixed_blocking"))
            .buffer(self.sets[0], write, Some("wavefront"))
            .buffer(self.accumulation, write, Some("accumulation"))
            .buffer(self.blocking, write, Some("blocking"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(self.resolve)?;
                ctx.bind(&[("volume", Bind::UniformData(bytemuck::bytes_of(block)))])?;
                ctx.rec.dispatch([cells, 1, 1])
            });
    }

    /// The configured iterations, one dispatch each, from `sets[0]`.
    pub fn add_propagation<'a>(&'a self, graph: &mut RenderGraph<'a>, block: &'a VolumeBlock) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let (read, write) = (
            Access::StorageRead { stages: compute },
            Access::StorageWrite { stages: compute },
        );
        let n = self.n;
        if self.occlusion && self.iterations > 0 {
            graph
                .pass(&format!("{} blocking faces", self.label))
                .buffer(self.blocking, read, Some("blocking"))
                .buffer(self.blocking_faces, write, Some("faces"))
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(self.faces)?;
                    ctx.bind(&[("volume", Bind::UniformData(bytemuck::bytes_of(block)))])?;
                    ctx.rec.dispatch([n, n, n])
                });
        }
        for k in 0..self.iterations {
            self.add_step(graph, block, k, &format!("{} propagate {}", self.label, k + 1));
        }
    }

    /// Propagation step `k` (from `sets[k % 2]`) over the cells `block` spans.
    pub fn add_step<'a>(&'a self, graph: &mut RenderGraph<'a>, block: &'a VolumeBlock, k: u32, name: &str) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let (read, write) = (
            Access::StorageRead { stages: compute },
            Access::StorageWrite { stages: compute },
        );
        let n = block.size[0] as u32;
        let (src, dst) = (self.sets[(k % 2) as usize], self.sets[((k + 1) % 2) as usize]);
        graph
            .pass(name)
            .buffer(src, read, Some("source"))
            .buffer(dst, write, Some("destination"))
            .buffer(self.accumulation, write, Some("accumulation"))
            .buffer(self.blocking_faces, read, Some("faces"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(self.propagate)?;
                ctx.bind(&[("volume", Bind::UniformData(bytemuck::bytes_of(block)))])?;
                ctx.rec.dispatch([n, n, n])
            });
    }

    /// Sets `buffer` (a set, or the geometry volume when `blocking`) to `words` before anything
    /// else runs (tests and the standalone propagation).
    pub fn upload(&self, gpu: &mut Gpu, buffer: BufferId, words: &[u32]) -> Result<()> {
        Ok(gpu.upload_buffer(buffer, 0, bytemuck::cast_slice(words))?)
    }

    /// Reads a buffer of the volume back to the host (after the frames that wrote it finished).
    pub fn read_words(&self, gpu: &mut Gpu, buffer: BufferId) -> Result<Vec<u32>> {
        let bytes = crate::graph::read_back_buffer(gpu, buffer, "lpv")?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// The three channels of a set.
    /// The set `buffer` in W/sr (what the shaders store, times `block.scale[1]`).
    pub fn read_set(&self, gpu: &mut Gpu, buffer: BufferId, block: &VolumeBlock) -> Result<[Grid; 3]> {
        let mut grids = decode(&self.read_words(gpu, buffer)?, self.n, self.half);
        let per_stored = f64::from(block.scale[1]);
        for c in grids.iter_mut().flat_map(|g| g.cells.iter_mut()) {
            *c = c.map(|x| x * per_stored);
        }
        Ok(grids)
    }
}

/// Propagates `injected` on the GPU with `config`'s scheme (and `blocking`, corner SH, when the
/// geometry volume is on): the CPU reference's twin for tests. Returns the result set.
pub fn propagate_standalone(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    config: &Config,
    injected: &[Grid; 3],
    blocking: Option<&Grid>,
) -> Result<[Grid; 3]> {
    if injected.iter().any(|g| g.size != [config.grid as usize; 3]) {
        return Err(Error::Internal(format!(
            "lpv: the injected grids are not {}³",
            config.grid
        )));
    }
    let mut states = ResourceStates::default();
    let volume = VolumeGpu::new(gpu, shaders, &mut states, config, "lpv")?;
    let words = encode(injected, config.half);
    volume.upload(gpu, volume.sets[0], &words)?;
    volume.upload(gpu, volume.accumulation, &words)?;
    if let Some(b) = blocking {
        let floats: Vec<u32> = b.cells.iter().flat_map(|c| c.map(|x| (x as f32).to_bits())).collect();
        volume.upload(gpu, volume.blocking, &floats)?;
    }
    let n = config.grid as i32;
    let block = VolumeBlock {
        size: [n, n, n, n * n * n],
        origin: [0.0, 0.0, 0.0, 1.0],
        scale: [1.0, 1.0, 0.0, 0.0],
        ..Default::default()
    };
    let frame = gpu.create_frame()?;
    let mut graph = RenderGraph::new();
    volume.add_propagation(&mut graph, &block);
    graph.output_buffer(volume.result());
    graph.run_and_wait(gpu, frame, &mut states, "LPV propagation")?;
    gpu.destroy_frame(frame)?;
    volume.read_set(gpu, volume.result(), &block)
}
