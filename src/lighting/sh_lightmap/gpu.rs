//! CaSHL's direct visibility on the GPU: the bits of [`transfer::visibility_cpu`] from a compute
//! pass (`glsl/sh_lightmap/visibility.comp`) over a BVH of the static triangles, the radiosity
//! shooter's (`radiosity::gpu`). Each invocation traces the samples of one 32-sample word (or,
//! where the device bounds an invocation's loop iterations and the BVH is deep, of a share of
//! it) from one inside patch. The work goes in chunks of words, one submission each, whose
//! output is read back and scattered into the patch-major bit rows between submissions (which
//! also drives the progress line).
//!
//! The rays are the CPU's in fp32 (the CPU BVH is fp32 too), with the direction tests in fp32
//! rather than fp64: bits may differ only where the last bit of the arithmetic decides, for rays
//! through the seam between two triangles and for grazing directions (tests/methods/sh_lightmap_gpu.rs:
//! measured 7.6e-6 of the bits on the open box, all rays into its corner edges).
//!
//! [`transfer::visibility_cpu`]: super::transfer::visibility_cpu

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::samples::SampleSet;
use crate::backend::{vk, BufferId, ComputePipelineDesc, Frame, Gpu, MemoryKind, PipelineId};
use crate::bake::gpu_loop::{cut_invocations, dvec4, loop_limit_error, status_buffer, BatchSizer};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::lighting::lightmap::patches::{Patches, Triangle};
use crate::lighting::lightmap::solve::Mode;
use crate::raytrace::bvh::Bvh;
use crate::raytrace::texel_table::GpuBvh;
use crate::raytrace::TracedTriangle;
use crate::shaders::ShaderLibrary;
use crate::util::progress::Progress;

/// `Patch` in glsl/sh_lightmap/visibility.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuPatch {
    origin: [f32; 4],
    plane: [f32; 4],
    normal: [f32; 4],
}

/// `Push`: the same for every dispatch of a bake (lavapipe compiles a shader per push-constant
/// set); the chunk's first word item and the lanes per word go through buffers.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    patch_count: u32,
    word_items: u32,
    sample_count: u32,
    triangle_count: u32,
    closest: u32,
    escape: u32,
}

/// Word items (one patch, 32 samples) per submission: the first (small, so that a device that
/// cuts loops short wastes little before the lanes grow), and the most.
const FIRST_CHUNK: usize = 256;
const MAX_CHUNK: usize = 1 << 20;
/// Invocations per dispatch at most: the guaranteed 65,535 workgroups of the shader's 64.
const MAX_INVOCATIONS: usize = 65_535 * 64;
/// Invocations per word at most: one sample each.
const MAX_LANES: u32 = 32;

/// Per inside patch, one bit per sample: the ray toward it reaches the sky, as
/// [`super::transfer::visibility_cpu`] lays them out (`⌈N/32⌉` words per patch, patch-major;
/// the rows of border patches stay 0). `triangles` are the occluders the CPU path builds its
/// [`Occluders`](crate::lighting::lightmap::solve::Occluders) from.
pub fn visibility_gpu(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    p: &Patches,
    triangles: &[Triangle],
    samples: &SampleSet,
    mode: Mode,
    progress: &mut Progress,
) -> Result<Vec<u32>> {
    // Every buffer, pipeline and frame of the pass is freed on every exit path.
    gpu.scoped(|gpu| run(gpu, shaders, p, triangles, samples, mode, progress))
}

#[allow(clippy::too_many_arguments)]
fn run(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    p: &Patches,
    triangles: &[Triangle],
    samples: &SampleSet,
    mode: Mode,
    progress: &mut Progress,
) -> Result<Vec<u32>> {
    let words = samples.len().div_ceil(32);
    let mut bits = vec![0u32; p.patches.len() * words];
    let inside: Vec<usize> = (0..p.patches.len()).filter(|&k| p.patches[k].inside()).collect();
    let total = inside.len() * words;
    if total == 0 {
        progress.finish();
        return Ok(bits);
    }
    if total > u32::MAX as usize {
        return Err(Error::Usage(format!(
            "SH light-map visibility: {} patches × {words} words are too many for one GPU bake",
            inside.len()
        )));
    }
    let occluders = SkyOccluders::new(triangles);
    let buffers = VisibilityBuffers::create(gpu, &gpu_patches(p, &inside), samples, &occluders.sky, total)?;
    let pipeline = gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: "sh visibility".into(),
            shader: "sh_lightmap/visibility.comp".into(),
            specialization: vec![],
        },
        shaders,
    )?;
    let frame = gpu.create_frame()?;
    let has_sky = triangles.iter().any(|t| t.sky);
    let push = Push {
        patch_count: inside.len() as u32,
        word_items: total as u32,
        sample_count: samples.len() as u32,
        triangle_count: occluders.traced.len() as u32,
        // Without sky surfaces any hit blocks; with them the first hit decides (in both modes: a
        // sky surface passes the ray, corrected mode's escaping rays pass too).
        closest: u32::from(has_sky),
        escape: u32::from(mode == Mode::Corrected || !has_sky),
    };
    let mut states = ResourceStates::default();
    let bvh = GpuBvh::upload(
        gpu,
        &mut states,
        "sh visibility",
        &occluders.bvh.nodes,
        &occluders.traced,
        Some(&occluders.bvh.skip_links()),
    )?;
    let bake = VisibilityBake {
        buffers,
        bvh,
        pipeline,
        push,
    };
    bake.trace_chunks(gpu, frame, &mut states, progress, |base, out| {
        for (i, b) in out.chunks_exact(4).enumerate() {
            let word_bits = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            let item = base + i;
            let (w, j) = (item / inside.len(), item % inside.len());
            bits[inside[j] * words + w] = word_bits;
        }
    })?;
    progress.finish();
    Ok(bits)
}

/// The inside patches as the shader reads them: the ray origin a hair in front of the chart's
/// plane, so that its own plane never occludes.
fn gpu_patches(p: &Patches, inside: &[usize]) -> Vec<GpuPatch> {
    let eps = 1e-4 * p.size;
    inside
        .iter()
        .map(|&k| {
            let q = &p.patches[k];
            let plane = p.charts[q.chart].normal;
            GpuPatch {
                origin: dvec4(q.centre + plane * eps, 0.0),
                plane: dvec4(plane, 0.0),
                normal: dvec4(q.normal, 0.0),
            }
        })
        .collect()
}

/// The occluders' BVH, its triangles in leaf order, and one bit per leaf slot: a sky surface.
struct SkyOccluders {
    bvh: Bvh,
    traced: Vec<TracedTriangle>,
    sky: Vec<u32>,
}

impl SkyOccluders {
    fn new(triangles: &[Triangle]) -> Self {
        let tris: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.p.map(|q| q.as_vec3())).collect();
        let bvh = Bvh::build(&tris);
        let traced = TracedTriangle::in_leaf_order(&bvh, &tris);
        let mut sky = vec![0u32; traced.len().div_ceil(32)];
        for (slot, &t) in bvh.order.iter().enumerate() {
            if triangles[t as usize].sky {
                sky[slot / 32] |= 1 << (slot % 32);
            }
        }
        SkyOccluders { bvh, traced, sky }
    }
}

/// The visibility bake's buffers.
struct VisibilityBuffers {
    patches: BufferId,
    samples: BufferId,
    sky: BufferId,
    /// One chunk's words, read by the host; `max_chunk` of them at most.
    out: BufferId,
    max_chunk: usize,
    status: BufferId,
    chunk: BufferId,
    lanes: BufferId,
}

impl VisibilityBuffers {
    fn create(
        gpu: &mut Gpu,
        patches: &[GpuPatch],
        samples: &SampleSet,
        sky: &[u32],
        total: usize,
    ) -> Result<VisibilityBuffers> {
        let dirs: Vec<[f32; 4]> = samples.dirs.iter().map(|&d| dvec4(d, 0.0)).collect();
        let patches = gpu.create_storage_buffer("sh visibility patches", bytemuck::cast_slice(patches))?;
        let samples = gpu.create_storage_buffer("sh visibility samples", bytemuck::cast_slice(&dirs))?;
        let sky = gpu.create_storage_buffer("sh visibility sky flags", bytemuck::cast_slice(sky))?;
        let max_chunk = MAX_CHUNK.min(total);
        Ok(VisibilityBuffers {
            patches,
            samples,
            sky,
            out: gpu.create_storage_output("sh visibility bits", 4 * max_chunk as u64, MemoryKind::GpuToCpu)?,
            max_chunk,
            status: status_buffer(gpu, "sh visibility")?,
            chunk: gpu.create_storage_output("sh visibility chunk", 4, MemoryKind::GpuOnly)?,
            lanes: gpu.create_storage_output("sh visibility lanes", 4, MemoryKind::GpuOnly)?,
        })
    }
}

/// Everything a chunk of the visibility bake records.
struct VisibilityBake {
    buffers: VisibilityBuffers,
    bvh: GpuBvh,
    pipeline: PipelineId,
    push: Push,
}

impl VisibilityBake {
    /// Traces every word item, chunk by chunk, each chunk sized by the time the last ones took;
    /// a chunk whose invocations the device cut short is traced again with more invocations per
    /// word. Each chunk's words go to `scatter` with the chunk's first item.
    fn trace_chunks(
        &self,
        gpu: &mut Gpu,
        frame: Frame,
        states: &mut ResourceStates,
        progress: &mut Progress,
        mut scatter: impl FnMut(usize, &[u8]),
    ) -> Result<()> {
        let total = self.push.word_items as usize;
        let mut lanes = 1u32;
        // A last, short chunk (or a bake of fewer than 32 words) must not bring the ceiling under
        // the floor of 64.
        let mut sizer = BatchSizer::new(FIRST_CHUNK, 64, self.buffers.max_chunk, 2);
        let mut base = 0usize;
        // The rate counts from here: the patches, the BVH's upload and the pipeline before it
        // are not the rays' time (at 2 cm on the courtyard they made 2.5 s of rays read 226 h).
        progress.update(0, total as u64);
        while base < total {
            let n = sizer.size().min(total - base).min(MAX_INVOCATIONS / lanes as usize);
            let t0 = std::time::Instant::now();
            let mut graph = RenderGraph::new();
            self.record_chunk(&mut graph, base as u32, n as u32, lanes);
            graph.run_and_wait(gpu, frame, states, "sh light-map visibility")?;
            let cut = cut_invocations(gpu, self.buffers.status, "sh light-map visibility")?;
            if cut > 0 {
                if lanes >= MAX_LANES {
                    return Err(loop_limit_error(
                        gpu,
                        cut,
                        "SH light-map visibility ray(s)",
                        "use baker = \"cpu\"",
                    ));
                }
                // Fewer rays per invocation, and the same chunk again.
                lanes *= 2;
                sizer.shrink();
                continue;
            }
            let out = gpu.read_buffer_prefix(self.buffers.out, 4 * n)?;
            scatter(base, &out);
            base += n;
            progress.update(base as u64, total as u64);
            crate::bake::check_cancelled(progress, "sh light-map visibility")?;
            sizer.record(n, t0.elapsed());
        }
        Ok(())
    }

    /// One chunk of `n` word items from `first`, `lanes` invocations a word: the chunk's
    /// parameters, the cleared outputs, the trace and the read-back.
    fn record_chunk<'a>(&'a self, graph: &mut RenderGraph<'a>, first: u32, n: u32, lanes: u32) {
        let b = &self.buffers;
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let read = Access::StorageRead { stages: compute };
        let write = Access::StorageWrite { stages: compute };
        let (chunk_buf, lanes_buf, out_buf, status_buf) = (b.chunk, b.lanes, b.out, b.status);
        graph
            .pass("sh visibility chunk")
            .buffer(chunk_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(chunk_buf, first));
        graph
            .pass("sh visibility lanes")
            .buffer(lanes_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(lanes_buf, lanes));
        graph
            .pass("sh visibility clear bits")
            .buffer(out_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(out_buf, 0));
        graph
            .pass("sh visibility clear status")
            .buffer(status_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(status_buf, 0));
        let (pipeline, push) = (self.pipeline, self.push);
        self.bvh
            .read(graph.pass("sh visibility"), vk::PipelineStageFlags2::COMPUTE_SHADER)
            .buffer(b.patches, read, Some("patches"))
            .buffer(b.samples, read, Some("samples"))
            .buffer(b.sky, read, Some("sky"))
            .buffer(out_buf, write, Some("bits"))
            .buffer(status_buf, write, Some("status"))
            .buffer(chunk_buf, read, Some("chunk"))
            .buffer(lanes_buf, read, Some("lanes_per_word"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                ctx.rec.dispatch([n * lanes, 1, 1])
            });
        graph
            .pass("sh visibility host")
            .buffer(out_buf, Access::HostRead, None)
            .buffer(status_buf, Access::HostRead, None)
            .record(|_| Ok(()));
    }
}
