//! The ray-cast truth the raster baker is measured against (Staniszewski 2005 §4, "Bake: reference and
//! modern paths"): per receiver, the transfer `T_i = ∫ V(ω) max(0, n·ω) y_i(ω) dω` estimated
//! with `N` stratified cosine-weighted directions, `T_i ≈ (π/N) Σ_k V(ω_k) y_i(ω_k)`, on the CPU
//! ([`bake_cpu`]) and in a compute pass (`glsl/prt/rays.comp`, [`bake_gpu`]).
//!
//! * Directions: the cell centres of a √N×√N grid on the unit square, mapped to the disk by
//!   the polar map and lifted to the hemisphere (Malley's method; [`cosine_directions`]), in
//!   the receiver's frame `tangent_frame(n, 0)`; deterministic, so both paths trace the same
//!   rays.
//! * Visibility: the ray from `p + near·ω` along ω is blocked by a triangle of the receiver's
//!   occluder set closer than `far − near` (so a hit counts at a distance in (near, far) from
//!   `p`); an empty set blocks nothing.
//! * Both paths build the rays in fp32 with the same operations in the same order (the frame
//!   and the local directions rounded from fp64, `d = t·x + b·y + n·z`, `o = p + d·near`; the
//!   shader marks them `precise`) and intersect them with the same fp32 Möller–Trumbore and slab
//!   tests over the same BVHs, so they agree ray for ray but where the last bit of a hit test
//!   decides; the SH basis and the sums differ only by rounding (fp64 against fp32).
//!   tests/methods/prt_rays.rs measured no ray that differs on lavapipe, and coefficients within 4e-7.
//! * Möller–Trumbore is not watertight: a ray exactly along an edge shared by two triangles may
//!   pass between them (both paths alike).

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

use super::receivers::{tangent_frame, Clip, Receivers};
use crate::backend::{vk, BufferId, ComputePipelineDesc, Frame, Gpu, MemoryKind, PipelineId, SpecConstant};
use crate::bake::gpu_loop::{cut_invocations, loop_limit_error, status_buffer, vec4, BatchSizer};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::raytrace::bvh::{box_entry, intersect_triangle, safe_inverse, Bvh, BvhNode};
use crate::raytrace::texel_table::GpuBvh;
use crate::raytrace::TracedTriangle;
use crate::shaders::ShaderLibrary;
use crate::util::parallel;
use crate::util::progress::{Estimate, Progress};

/// Most SH bands either path bakes (the shader's `SH_MAX_BANDS`).
pub const MAX_BANDS: usize = 8;
/// Most directions per receiver.
pub const MAX_SAMPLES: usize = 1 << 20;
/// The largest fp32 ray length (`NO_HIT` in glsl/common/bvh.glsl): an infinite far plane.
const UNBOUNDED: f32 = 3.0e38;

/// Checks the band and sample counts (`samples` must be a square: a √N×√N grid).
pub fn check(bands: usize, samples: usize) -> Result<()> {
    if !(1..=MAX_BANDS).contains(&bands) {
        return Err(Error::Usage(format!(
            "PRT ray cast: bands must be 1 to {MAX_BANDS}, not {bands}"
        )));
    }
    let side = samples.isqrt();
    if samples == 0 || samples > MAX_SAMPLES || side * side != samples {
        return Err(Error::Usage(format!(
            "PRT ray cast: samples must be a square number (16, 256, 1024, 4096…) up to {MAX_SAMPLES}, not {samples}"
        )));
    }
    Ok(())
}

/// [`check`], and a clip with `0 ≤ near < far` and receivers that name existing sets.
fn check_all(r: &Receivers, bands: usize, samples: usize, clip: Clip) -> Result<()> {
    check(bands, samples)?;
    if !(clip.near >= 0.0 && clip.near.is_finite() && clip.far > clip.near) {
        return Err(Error::Usage(format!(
            "PRT ray cast: the clip needs 0 ≤ near < far (near {}, far {})",
            clip.near, clip.far
        )));
    }
    if r.set.len() != r.len() || r.normals.len() != r.len() {
        return Err(Error::Usage(format!(
            "PRT ray cast: {} receivers with {} normals and {} set indices",
            r.len(),
            r.normals.len(),
            r.set.len()
        )));
    }
    if let Some(k) = r.set.iter().position(|&s| s as usize >= r.sets.len()) {
        return Err(Error::Usage(format!(
            "PRT ray cast: receiver {k} names occluder set {} of {}",
            r.set[k],
            r.sets.len()
        )));
    }
    Ok(())
}

/// The stratified cosine-weighted directions in the receiver's frame (z = normal): the cell
/// centres `(u₁, u₂)` of a √N×√N grid (`k = row·√N + column`, u₁ by column, u₂ by row) through
/// the polar disk map `r = √u₁, φ = 2πu₂`, lifted to `z = √(1 − r²)`. For a count that is not a
/// square, the largest square below it.
///
/// The polar map rather than the concentric one: with cell centres, the concentric map's corners
/// bend its rings of constant radius into squares and it converges slower near the horizon
/// (unoccluded, n up, N = 4096: T₃₀ = −3.0e-3 against −4.9e-4 polar, T₁₀ off by 1.6e-3 against
/// 1.7e-4). Either way the rings alias: an occluder symmetric about the normal flips a whole
/// ring of u₁ at once (an error of at most ~0.886/(2√N) in T₀₀), nothing where its edge falls on
/// a cell edge, `sin²α = k/√N`.
pub fn cosine_directions(samples: usize) -> Vec<DVec3> {
    let side = samples.isqrt();
    let mut out = Vec::with_capacity(side * side);
    for row in 0..side {
        let phi = std::f64::consts::TAU * (row as f64 + 0.5) / side as f64;
        for col in 0..side {
            let u = (col as f64 + 0.5) / side as f64;
            let r = u.sqrt();
            out.push(DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u).sqrt()));
        }
    }
    out
}

/// A receiver's frame in fp32, as both paths build rays from it: tangent, bitangent, normal.
fn frame(n: DVec3) -> [Vec3; 3] {
    let (t, b) = tangent_frame(n, 0.0);
    [t.as_vec3(), b.as_vec3(), n.as_vec3()]
}

/// The world direction of local direction `l` (the shader's `precise` expression, same order).
fn world_dir(f: &[Vec3; 3], l: Vec3) -> Vec3 {
    f[0] * l.x + f[1] * l.y + f[2] * l.z
}

/// The ray's length past its start at `p + near·ω`.
fn ray_length(clip: Clip) -> f32 {
    ((clip.far - clip.near) as f32).min(UNBOUNDED)
}

/// World (y up) to the SH frame (z up).
fn to_sh(d: Vec3) -> DVec3 {
    DVec3::new(d.x as f64, -d.z as f64, d.y as f64)
}

/// One occluder set's BVH with its triangles in leaf-slot order as corner and edges (the
/// shader's `Triangle`), and the skip links of the CPU's stackless any-hit walk (the shader
/// walks the tree with a stack: glsl/common/bvh.glsl, trace_triangles_from).
struct SetBvh {
    nodes: Vec<BvhNode>,
    skips: Vec<u32>,
    triangles: Vec<[Vec3; 3]>,
}

impl SetBvh {
    fn build(tris: &[[Vec3; 3]]) -> Option<SetBvh> {
        if tris.is_empty() {
            return None;
        }
        let bvh = Bvh::build(tris);
        let triangles = bvh
            .order
            .iter()
            .map(|&t| {
                let [a, b, c] = tris[t as usize];
                [a, b - a, c - a]
            })
            .collect();
        Some(SetBvh {
            skips: bvh.skip_links(),
            nodes: bvh.nodes,
            triangles,
        })
    }

    /// Whether a triangle lies on the ray closer than `t_max`: `occluded` of
    /// glsl/common/bvh.glsl. The bake's shader walks the tree in another order (with a stack,
    /// nearer child first) but tests triangles with the same arithmetic, so it answers alike.
    fn occluded(&self, o: Vec3, d: Vec3, t_max: f32) -> bool {
        let inv_d = safe_inverse(d);
        let mut node = 0usize;
        while node < self.nodes.len() {
            let n = &self.nodes[node];
            if box_entry(n.lo.into(), n.hi.into(), o, inv_d, t_max).is_none() {
                node = self.skips[node] as usize;
                continue;
            }
            if !n.is_leaf() {
                node += 1;
                continue;
            }
            for [p0, e1, e2] in &self.triangles[n.index as usize..(n.index + n.count) as usize] {
                if intersect_triangle(o, d, *p0, *e1, *e2, t_max).is_some() {
                    return true;
                }
            }
            node = self.skips[node] as usize;
        }
        false
    }
}

/// Receivers per work item of a CPU thread at most.
const CPU_CHUNK: usize = 32;
/// Rays per work item of a CPU thread at most (whole receivers, one at least): at a million rays
/// a receiver, 32 receivers a thread would keep the progress line silent for half a minute.
const CPU_CHUNK_RAYS: usize = 1 << 17;
/// The calibration before a CPU bake: receivers per core, spread over the receivers, and rays
/// each at most (spread over the sample directions), timed twice: the second run counts (the
/// first finds the trees outside the caches, and took about twice as long on lavapipe).
const CALIBRATION_RECEIVERS: usize = 4;
const CALIBRATION_RAYS: usize = 4096;

/// The CPU's rays: every occluder set's BVH and the clip.
struct CpuTracer {
    bvhs: Vec<Option<SetBvh>>,
    near: f32,
    t_max: f32,
    bands: usize,
}

impl CpuTracer {
    fn new(r: &Receivers, bands: usize, clip: Clip) -> CpuTracer {
        CpuTracer {
            bvhs: r.sets.iter().map(|s| SetBvh::build(&s.triangles)).collect(),
            near: clip.near as f32,
            t_max: ray_length(clip),
            bands,
        }
    }

    /// Σ over the local directions `dirs` of receiver `k`'s unoccluded rays of the SH basis.
    fn trace(&self, r: &Receivers, k: usize, dirs: &[Vec3], acc: &mut [f64; MAX_BANDS * MAX_BANDS]) {
        let dim = self.bands * self.bands;
        let bvh = self.bvhs[r.set[k] as usize].as_ref();
        let f = frame(r.normals[k]);
        let p = r.positions[k].as_vec3();
        let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
        for &l in dirs {
            let d = world_dir(&f, l);
            if bvh.is_some_and(|b| b.occluded(p + d * self.near, d, self.t_max)) {
                continue;
            }
            // The band count is checked, so the basis cannot fail.
            if crate::sh::eval_basis_f64(to_sh(d), self.bands, &mut y).is_ok() {
                for (a, y) in acc[..dim].iter_mut().zip(&y[..dim]) {
                    *a += y;
                }
            }
        }
    }

    /// The calibration's receivers and rays each.
    fn calibration(r: &Receivers, local: &[Vec3]) -> (usize, usize) {
        let receivers = (CALIBRATION_RECEIVERS * parallel::cores()).min(r.len());
        (receivers, local.len().min(CALIBRATION_RAYS))
    }

    /// Whether `keys` bakes of `r` at `local.len()` rays take much longer than the calibration.
    fn worth_estimating(r: &Receivers, local: &[Vec3], keys: usize) -> bool {
        let (receivers, rays) = CpuTracer::calibration(r, local);
        (r.len() * local.len()) as f64 * keys as f64 >= 100.0 * (receivers * rays) as f64
    }

    /// Times the real rays of a few receivers spread over `r` (a spread subset of each one's
    /// directions, on every core as the bake runs) and extrapolates to `keys` bakes of every
    /// receiver at `local.len()` rays.
    fn estimate(&self, r: &Receivers, local: &[Vec3], keys: usize) -> Option<Estimate> {
        let threads = parallel::cores();
        let (receivers, rays) = CpuTracer::calibration(r, local);
        let all = r.len() as f64 * local.len() as f64 * keys as f64;
        if receivers == 0 || rays == 0 {
            return None;
        }
        // An odd stride is a permutation of a power-of-two count and scatters over the
        // stratified grid for others, where a plain stride would keep to a few of its columns.
        let dirs: Vec<Vec3> = (0..rays)
            .map(|i| local[(i as u64 * 2_654_435_761 % local.len() as u64) as usize])
            .collect();
        let picked: Vec<usize> = (0..receivers).map(|i| i * r.len() / receivers).collect();
        let run = || {
            let start = std::time::Instant::now();
            std::thread::scope(|scope| {
                for mine in picked.chunks(CALIBRATION_RECEIVERS) {
                    let dirs = &dirs;
                    scope.spawn(move || {
                        for &k in mine {
                            let mut acc = [0.0f64; MAX_BANDS * MAX_BANDS];
                            self.trace(r, k, dirs, &mut acc);
                            std::hint::black_box(acc);
                        }
                    });
                }
            });
            start.elapsed().as_secs_f64()
        };
        run();
        let seconds = run();
        let per_ray = seconds / (receivers * rays) as f64;
        Some(Estimate {
            seconds: per_ray * all,
            method: format!(
                "{receivers} receivers × {rays} rays timed: {:.2} µs a ray on {threads} core(s)",
                per_ray * 1e6
            ),
            dominant: format!(
                "tracing {} receivers × {} rays{}",
                r.len(),
                local.len(),
                if keys > 1 {
                    format!(" × {keys} keys")
                } else {
                    String::new()
                }
            ),
            remedy: "fewer samples (or the \"rays\" baker on a GPU)".into(),
        })
    }
}

/// The transfer of every receiver on the CPU: `bands²` coefficients per receiver,
/// receiver-major, from `samples` stratified cosine-weighted rays each (module docs).
pub fn bake_cpu(r: &Receivers, bands: usize, samples: usize, clip: Clip, progress: &mut Progress) -> Result<Vec<f32>> {
    bake_cpu_of_keys(r, bands, samples, clip, 1, progress)
}

/// [`bake_cpu`], one of `keys` such bakes: the first warns when all of them are estimated past
/// a minute, before its rays are cast.
pub fn bake_cpu_of_keys(
    r: &Receivers,
    bands: usize,
    samples: usize,
    clip: Clip,
    keys: usize,
    progress: &mut Progress,
) -> Result<Vec<f32>> {
    check_all(r, bands, samples, clip)?;
    let dim = bands * bands;
    let mut out = vec![0.0f32; r.len() * dim];
    let tracer = CpuTracer::new(r, bands, clip);
    let local: Vec<Vec3> = cosine_directions(samples).iter().map(|d| d.as_vec3()).collect();
    if CpuTracer::worth_estimating(r, &local, keys) {
        if let Some(e) = tracer.estimate(r, &local, keys) {
            progress.warn_before(&e);
        }
    }
    let weight = std::f64::consts::PI / samples as f64;
    let receiver = |k: usize, row: &mut [f32]| {
        let mut acc = [0.0f64; MAX_BANDS * MAX_BANDS];
        tracer.trace(r, k, &local, &mut acc);
        for (o, a) in row.iter_mut().zip(&acc[..dim]) {
            *o = (a * weight) as f32;
        }
    };
    let threads = parallel::cores();
    let chunk = (CPU_CHUNK_RAYS / samples.max(1)).clamp(1, CPU_CHUNK);
    let mut done = 0;
    // The rate is timed from here, not from the bake's start.
    progress.update(0, r.len() as u64);
    for part in out.chunks_mut(chunk * dim * threads) {
        let first = done;
        std::thread::scope(|scope| {
            for (c, rows) in part.chunks_mut(chunk * dim).enumerate() {
                let receiver = &receiver;
                scope.spawn(move || {
                    rows.chunks_mut(dim)
                        .enumerate()
                        .for_each(|(i, row)| receiver(first + c * chunk + i, row))
                });
            }
        });
        done += part.len() / dim;
        progress.update(done as u64, r.len() as u64);
        crate::bake::check_cancelled(progress, "prt rays")?;
    }
    progress.finish();
    Ok(out)
}

/// `Receiver` in glsl/prt/rays.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuReceiver {
    position: [f32; 4],
    tangent: [f32; 4],
    bitangent: [f32; 4],
    normal: [f32; 4],
    /// x: the root node of its occluder set's BVH among the concatenated ones, or [`NO_BVH`].
    bvh: [u32; 4],
}

/// `Push`: the same for every dispatch of a bake (lavapipe compiles a shader per push-constant
/// set); the chunk's first receiver, its size and the rays per invocation go through buffers.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Push {
    receiver_count: u32,
    sample_count: u32,
    bands: u32,
    triangle_count: u32,
    near: f32,
    t_max: f32,
}

/// `glsl/prt/reduce_lanes.comp`'s push constants: the same for every dispatch of a bake.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReducePush {
    sample_count: u32,
    dim: u32,
    weight: f32,
}

const NO_BVH: u32 = u32::MAX;
/// Rays per invocation to start with; halved (more invocations per receiver) whenever the device
/// cuts an invocation's loops short.
const FIRST_RAYS_PER_LANE: u32 = 64;
/// Receivers in the first submission (small, so a device that cuts loops short wastes little).
const FIRST_CHUNK: usize = 64;
/// Invocations per dispatch at most: the guaranteed 65,535 workgroups of the shader's 64.
const MAX_INVOCATIONS: usize = 65_535 * 64;
/// The partial sums one submission writes, at most (bytes; more where one receiver's sums at one
/// ray per invocation need more).
const MAX_SUMS_BYTES: usize = 64 << 20;
/// How much a submission may grow over the last one. A small submission on a GPU costs its
/// latency (each invocation walks its rays one after another), not its size, so its time
/// understates the rate and the fit alone would grow slowly; doubling took 12 submissions to
/// cover 114k receivers whatever the device. A factor of 8 reaches the sums buffer's limit in
/// four, and still bounds what a chunk traced again after a cut loop wastes.
const MAX_CHUNK_GROWTH: usize = 8;

/// Items one thread maps at a time where the GPU bake's inputs are prepared on every core (a
/// million receivers and 2 M triangles took about 0.1 s on one core here).
const MAP_PIECE: usize = 16_384;

/// [`bake_cpu`] in a compute pass (`glsl/prt/rays.comp`): the same rays, BVHs and layout. Each
/// invocation traces a share of one receiver's rays and writes its partial sums, which a second
/// pass (`glsl/prt/reduce_lanes.comp`) adds up in a fixed order. Where the device bounds an
/// invocation's loop iterations (llvmpipe: 65,535) and a walk is cut short, the chunk is traced
/// again with fewer rays per invocation, down to one, and then the bake is refused.
pub fn bake_gpu(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    r: &Receivers,
    bands: usize,
    samples: usize,
    clip: Clip,
    progress: &mut Progress,
) -> Result<Vec<f32>> {
    check_all(r, bands, samples, clip)?;
    if r.is_empty() {
        progress.finish();
        return Ok(Vec::new());
    }
    // Every buffer, pipeline and frame of the pass is freed on every exit path.
    gpu.scoped(|gpu| run(gpu, shaders, r, bands, samples, clip, progress))
}

fn run(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    r: &Receivers,
    bands: usize,
    samples: usize,
    clip: Clip,
    progress: &mut Progress,
) -> Result<Vec<f32>> {
    // Where a bake's time goes, printed at the end: on a fast GPU the set-up, not the rays, is
    // most of it (measured on an H200: 533 ms at 256 rays, 572 ms at 1,024).
    let start = std::time::Instant::now();
    let mut phases = BakePhases::default();
    let dim = bands * bands;
    let total = r.len();
    let (nodes, traced, roots) = concatenated_bvhs(r)?;
    let receivers = gpu_receivers(r, &roots);
    let local: Vec<[f32; 4]> = cosine_directions(samples)
        .iter()
        .map(|d| vec4(d.as_vec3(), 0.0))
        .collect();
    phases.trees = start.elapsed();
    let buffers = RayBuffers::create(gpu, &receivers, &local, (total, samples, dim), start, &mut phases)?;
    let t = std::time::Instant::now();
    let (pipeline, reduce) = ray_pipelines(gpu, shaders, bands)?;
    phases.pipeline = t.elapsed();
    let t = std::time::Instant::now();
    let frame = gpu.create_frame()?;
    phases.set_up[2] = t.elapsed();

    let push = Push {
        receiver_count: total as u32,
        sample_count: samples as u32,
        bands: bands as u32,
        triangle_count: traced.len() as u32,
        near: clip.near as f32,
        t_max: ray_length(clip),
    };
    let reduce_push = ReducePush {
        sample_count: samples as u32,
        dim: dim as u32,
        weight: (std::f64::consts::PI / samples as f64) as f32,
    };
    let mut states = ResourceStates::default();
    let t = std::time::Instant::now();
    let bvh = GpuBvh::upload(gpu, &mut states, "prt rays", &nodes, &traced, None)?;
    phases.set_up[3] = t.elapsed();
    phases.buffers = start.elapsed().saturating_sub(phases.trees + phases.pipeline);
    let bake = RayBake {
        buffers,
        bvh,
        pipeline,
        reduce,
        push,
        reduce_push,
        samples,
        dim,
        total,
    };
    let out = bake.trace_chunks(gpu, frame, &mut states, &mut phases, progress)?;
    progress.finish();
    phases.total = start.elapsed();
    crate::errln!("{}", phases.report(total, samples));
    Ok(out)
}

/// The occluder sets' BVHs one after the other, their node and slot indices offset: the nodes,
/// the triangles in leaf order, and per set its root node (or [`NO_BVH`]: no occluders).
fn concatenated_bvhs(r: &Receivers) -> Result<(Vec<BvhNode>, Vec<TracedTriangle>, Vec<u32>)> {
    let (mut nodes, mut traced) = (Vec::<BvhNode>::new(), Vec::<TracedTriangle>::new());
    let roots: Vec<u32> = r
        .sets
        .iter()
        .map(|s| {
            if s.triangles.is_empty() {
                return NO_BVH;
            }
            let bvh = Bvh::build(&s.triangles);
            // The triangles in leaf order as the shader reads them, the same arithmetic as
            // SetBvh's (p0, p1 - p0, p2 - p0).
            let set_traced = parallel::map(&bvh.order, MAP_PIECE, |&t| {
                let [a, b, c] = s.triangles[t as usize];
                TracedTriangle::new([a, b, c])
            });
            let (node_base, slot_base) = (nodes.len() as u32, traced.len() as u32);
            if nodes.is_empty() {
                // The first set's indices need no offset: its arrays move rather than copy
                // (3.5 M nodes and 2 M triangles for a 2 M-triangle set).
                (nodes, traced) = (bvh.nodes, set_traced);
            } else {
                nodes.extend(bvh.nodes.iter().map(|n| BvhNode {
                    index: n.index + if n.is_leaf() { slot_base } else { node_base },
                    ..*n
                }));
                traced.extend(set_traced);
            }
            node_base
        })
        .collect();
    if nodes.len() >= NO_BVH as usize || traced.len() > u32::MAX as usize {
        return Err(Error::Usage(
            "PRT ray cast: the occluder sets are too large for one GPU bake".into(),
        ));
    }
    Ok((nodes, traced, roots))
}

/// Every receiver's position, frame and its set's BVH root.
fn gpu_receivers(r: &Receivers, roots: &[u32]) -> Vec<GpuReceiver> {
    let indices: Vec<usize> = (0..r.len()).collect();
    parallel::map(&indices, MAP_PIECE, |&k| {
        let f = frame(r.normals[k]);
        GpuReceiver {
            position: vec4(r.positions[k].as_vec3(), 0.0),
            tangent: vec4(f[0], 0.0),
            bitangent: vec4(f[1], 0.0),
            normal: vec4(f[2], 0.0),
            bvh: [roots[r.set[k] as usize], 0, 0, 0],
        }
    })
}

/// The ray pass's pipeline, with the bands as a constant (the shader then keeps only the SH
/// evaluation it needs), and the reduction's.
fn ray_pipelines(gpu: &mut Gpu, shaders: &ShaderLibrary, bands: usize) -> Result<(PipelineId, PipelineId)> {
    let specialization = vec![SpecConstant {
        id: 0,
        bits: bands as u32,
    }];
    let pipeline = gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: "prt rays".into(),
            shader: "prt/rays.comp".into(),
            specialization,
        },
        shaders,
    )?;
    let reduce = gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: "prt rays reduce".into(),
            shader: "prt/reduce_lanes.comp".into(),
            specialization: Vec::new(),
        },
        shaders,
    )?;
    Ok((pipeline, reduce))
}

/// The ray bake's buffers.
struct RayBuffers {
    receivers: BufferId,
    directions: BufferId,
    /// Every invocation's partial sums, `sums_bytes` of them.
    sums: BufferId,
    sums_bytes: usize,
    /// The reduced transfer of one chunk, read by the host.
    transfer: BufferId,
    status: BufferId,
    chunk_base: BufferId,
    chunk_count: BufferId,
    per_lane: BufferId,
}

impl RayBuffers {
    /// Uploads the receivers and directions and creates the outputs, timing both into
    /// `phases.set_up` (from `start`, after the trees).
    fn create(
        gpu: &mut Gpu,
        receivers: &[GpuReceiver],
        directions: &[[f32; 4]],
        (total, samples, dim): (usize, usize, usize),
        start: std::time::Instant,
        phases: &mut BakePhases,
    ) -> Result<RayBuffers> {
        let receivers = gpu.create_storage_buffer("prt rays receivers", bytemuck::cast_slice(receivers))?;
        let directions = gpu.create_storage_buffer("prt rays directions", bytemuck::cast_slice(directions))?;
        phases.set_up[0] = start.elapsed() - phases.trees;
        // Room for at least one receiver at one ray per invocation. The partial sums stay on
        // the device; the host reads the reduced transfer, at most one chunk of it at a time.
        let sums_bytes = (total * samples * dim * 4).min(MAX_SUMS_BYTES.max(samples * dim * 4));
        let sums = gpu.create_storage_output("prt rays partial sums", sums_bytes as u64, MemoryKind::GpuOnly)?;
        let most_receivers = total.min(sums_bytes / (4 * dim));
        let transfer = gpu.create_storage_output(
            "prt rays transfer",
            (most_receivers * dim * 4) as u64,
            MemoryKind::GpuToCpu,
        )?;
        let status = status_buffer(gpu, "prt rays")?;
        let chunk_base = gpu.create_storage_output("prt rays chunk base", 4, MemoryKind::GpuOnly)?;
        let chunk_count = gpu.create_storage_output("prt rays chunk count", 4, MemoryKind::GpuOnly)?;
        let per_lane = gpu.create_storage_output("prt rays per lane", 4, MemoryKind::GpuOnly)?;
        phases.set_up[1] = start.elapsed() - phases.trees - phases.set_up[0];
        Ok(RayBuffers {
            receivers,
            directions,
            sums,
            sums_bytes,
            transfer,
            status,
            chunk_base,
            chunk_count,
            per_lane,
        })
    }
}

/// Everything a chunk of the ray bake records.
struct RayBake {
    buffers: RayBuffers,
    bvh: GpuBvh,
    pipeline: PipelineId,
    reduce: PipelineId,
    push: Push,
    reduce_push: ReducePush,
    samples: usize,
    dim: usize,
    total: usize,
}

impl RayBake {
    /// Traces every receiver, chunk by chunk, each chunk sized by the time the last ones took;
    /// a chunk whose invocations the device cut short is traced again with fewer rays per
    /// invocation. Returns the transfer, receiver-major.
    fn trace_chunks(
        &self,
        gpu: &mut Gpu,
        frame: Frame,
        states: &mut ResourceStates,
        phases: &mut BakePhases,
        progress: &mut Progress,
    ) -> Result<Vec<f32>> {
        let (samples, dim, total) = (self.samples, self.dim, self.total);
        let mut out = vec![0.0f32; total * dim];
        let mut per = FIRST_RAYS_PER_LANE.min(samples as u32);
        let mut sizer = BatchSizer::new(FIRST_CHUNK, 16, usize::MAX, MAX_CHUNK_GROWTH);
        let mut base = 0usize;
        // The rate counts from the first batch, not from the set-up before it.
        progress.update(0, total as u64);
        while base < total {
            let lanes = samples.div_ceil(per as usize);
            // Both dispatches within the guaranteed workgroup count: the trace's lanes, the
            // reduction's coefficients.
            let fits = (MAX_INVOCATIONS / lanes.max(dim))
                .min(self.buffers.sums_bytes / (4 * lanes * dim))
                .max(1);
            let n = sizer.size().min(total - base).min(fits);
            let t0 = std::time::Instant::now();
            let mut graph = RenderGraph::new();
            self.record_chunk(&mut graph, (base as u32, n as u32), per, lanes);
            graph.run_and_wait(gpu, frame, states, "PRT ray cast")?;
            phases.record_submission(n, t0.elapsed());
            let t_sum = std::time::Instant::now();
            let status = self.buffers.status;
            let cut = cut_invocations(gpu, status, "PRT ray cast")?;
            if cut > 0 {
                if per == 1 {
                    return Err(loop_limit_error(gpu, cut, "PRT ray(s)", "use the CPU baker"));
                }
                // Fewer rays per invocation, and the same chunk again.
                per = per.div_ceil(2);
                sizer.shrink();
                continue;
            }
            let transfer = gpu.read_buffer_prefix(self.buffers.transfer, 4 * n * dim)?;
            out[base * dim..(base + n) * dim].copy_from_slice(bytemuck::cast_slice(&transfer));
            phases.read_back += t_sum.elapsed();
            base += n;
            progress.update(base as u64, total as u64);
            crate::bake::check_cancelled(progress, "prt rays")?;
            sizer.record(n, t0.elapsed());
        }
        Ok(out)
    }

    /// One chunk of `count` receivers from `first`, `per` rays an invocation over `lanes`
    /// invocations a receiver: the chunk's parameters, the trace, the reduction, the read-back.
    fn record_chunk<'a>(&'a self, graph: &mut RenderGraph<'a>, (first, count): (u32, u32), per: u32, lanes: usize) {
        let b = &self.buffers;
        let (n, dim) = (count as usize, self.dim);
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let read = Access::StorageRead { stages: compute };
        let write = Access::StorageWrite { stages: compute };
        let (base_buf, count_buf, per_buf, status_buf) = (b.chunk_base, b.chunk_count, b.per_lane, b.status);
        graph
            .pass("prt rays chunk base")
            .buffer(base_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(base_buf, first));
        graph
            .pass("prt rays chunk count")
            .buffer(count_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(count_buf, count));
        graph
            .pass("prt rays per lane")
            .buffer(per_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(per_buf, per));
        graph
            .pass("prt rays clear status")
            .buffer(status_buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(status_buf, 0));
        let (pipeline, push) = (self.pipeline, self.push);
        self.bvh
            .read(graph.pass("prt rays"), vk::PipelineStageFlags2::COMPUTE_SHADER)
            .buffer(b.receivers, read, Some("receivers"))
            .buffer(b.directions, read, Some("directions"))
            .buffer(b.sums, write, Some("sums"))
            .buffer(status_buf, write, Some("status"))
            .buffer(base_buf, read, Some("chunk_base"))
            .buffer(count_buf, read, Some("chunk_count"))
            .buffer(per_buf, read, Some("per_lane"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                ctx.rec.dispatch([(n * lanes) as u32, 1, 1])
            });
        let (reduce, reduce_push) = (self.reduce, self.reduce_push);
        graph
            .pass("prt rays reduce")
            .buffer(b.sums, read, Some("sums"))
            .buffer(b.transfer, write, Some("transfer"))
            .buffer(status_buf, write, Some("status"))
            .buffer(count_buf, read, Some("chunk_count"))
            .buffer(per_buf, read, Some("per_lane"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(reduce)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&reduce_push))?;
                ctx.rec.dispatch([(n * dim) as u32, 1, 1])
            });
        graph
            .pass("prt rays host")
            .buffer(b.transfer, Access::HostRead, None)
            .buffer(status_buf, Access::HostRead, None)
            .record(|_| Ok(()));
    }
}

/// The compute ray baker's wall time by phase.
#[derive(Default)]
struct BakePhases {
    /// The occluder sets' BVHs and the receivers' frames (CPU).
    trees: std::time::Duration,
    pipeline: std::time::Duration,
    /// Creating the buffers and the frame, and uploading the receivers and the trees.
    buffers: std::time::Duration,
    /// Of those: the receivers and directions uploaded, the outputs created, the frame, the trees
    /// uploaded.
    set_up: [std::time::Duration; 4],
    /// Recording, submitting and waiting for the dispatches.
    traced: std::time::Duration,
    /// Reading the transfer back (CPU).
    read_back: std::time::Duration,
    submissions: usize,
    /// The first submission and the largest (receivers, wall time): the latency and the rate.
    first: Option<(usize, std::time::Duration)>,
    largest: Option<(usize, std::time::Duration)>,
    total: std::time::Duration,
}

impl BakePhases {
    fn record_submission(&mut self, receivers: usize, took: std::time::Duration) {
        self.submissions += 1;
        self.traced += took;
        self.first.get_or_insert((receivers, took));
        if self.largest.is_none_or(|(n, _)| receivers > n) {
            self.largest = Some((receivers, took));
        }
    }

    fn report(&self, receivers: usize, samples: usize) -> String {
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        let other = self
            .total
            .saturating_sub(self.trees + self.pipeline + self.buffers + self.traced + self.read_back);
        let one = |s: Option<(usize, std::time::Duration)>| {
            s.map_or("none".to_string(), |(n, d)| format!("{n} receivers in {:.1} ms", ms(d)))
        };
        format!(
            "prt rays: {receivers} receivers x {samples} rays in {:.0} ms: trees {:.0} ms, pipeline {:.0} ms, buffers and uploads {:.0} ms (receivers {:.0}, outputs {:.0}, frame {:.0}, trees {:.0}), {} submissions {:.0} ms (first {}, largest {}), read back {:.0} ms, the rest {:.0} ms",
            ms(self.total),
            ms(self.trees),
            ms(self.pipeline),
            ms(self.buffers),
            ms(self.set_up[0]),
            ms(self.set_up[1]),
            ms(self.set_up[2]),
            ms(self.set_up[3]),
            self.submissions,
            ms(self.traced),
            one(self.first),
            one(self.largest),
            ms(self.read_back),
            ms(other)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::receivers::OccluderSet;
    use super::*;

    const PI: f64 = std::f64::consts::PI;
    /// The clamped cosine's ZH about +z per band: √π/2, √(π/3), √(5π)/8, 0 (Staniszewski 2005 §5 test 1).
    const T00: f64 = 0.886227;
    const T10: f64 = 1.023327;
    const T20: f64 = 0.495416;
    /// Lambert's Â_l = √(4π/(2l+1))·z_l: π, 2π/3, π/4, 0, −π/24, 0, π/64, 0.
    const LAMBERT: [f64; 8] = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0, 0.0, PI / 64.0, 0.0];

    fn bake(r: &Receivers, bands: usize, samples: usize, clip: Clip) -> Vec<f32> {
        bake_cpu(r, bands, samples, clip, &mut Progress::new("test")).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The estimate made before a CPU bake from a few receivers' rays comes within a factor of
    /// three of the bake's measured time: receivers inside a closed box (every ray hits) and
    /// under the open sky (none does, each adds the basis), 2.4 M rays. The factor allows for
    /// the machine's load between the calibration and the bake (on a shared 2-core machine one
    /// run's time varied by about 1.5×).
    #[test]
    fn a_cpu_bake_takes_about_its_estimate() {
        let points: Vec<(DVec3, DVec3)> = (0..64)
            .map(|i| {
                let x = (i % 32) as f64 / 32.0 - 0.5;
                let centre = if i < 32 {
                    DVec3::new(x, -0.9, 0.1)
                } else {
                    DVec3::new(3.0 + x, 0.0, 0.0)
                };
                (centre, DVec3::new(0.2 * x, 1.0, 0.1).normalize())
            })
            .collect();
        let r = Receivers::explicit(&points, closed_box(2.0));
        let (bands, samples, clip) = (4, 36_864, Clip::default());
        let tracer = CpuTracer::new(&r, bands, clip);
        let local: Vec<Vec3> = cosine_directions(samples).iter().map(|d| d.as_vec3()).collect();
        let estimate = tracer.estimate(&r, &local, 1).expect("an estimate").seconds;
        let start = std::time::Instant::now();
        bake(&r, bands, samples, clip);
        let measured = start.elapsed().as_secs_f64();
        println!("estimated {estimate:.2} s, took {measured:.2} s");
        assert!(
            estimate / measured < 3.0 && measured / estimate < 3.0,
            "estimated {estimate:.2} s, took {measured:.2} s"
        );
    }

    fn up() -> (DVec3, DVec3) {
        (DVec3::ZERO, DVec3::Y)
    }

    /// A closed box of side `side` centred on the origin.
    fn closed_box(side: f32) -> Vec<[Vec3; 3]> {
        let m = crate::scene::generators::cuboid(Vec3::splat(side), 2);
        m.triangles().map(|t| t.map(|i| m.positions[i])).collect()
    }

    /// An opaque disk (a fan of 512 triangles) of radius `radius` centred at height `h` over the
    /// origin, facing down. Its spokes are turned off the directions' azimuths (multiples of
    /// 2π/128 about +y for n = +y): the fp32 Möller–Trumbore test is not watertight, and rays
    /// exactly along a spoke pass between its two triangles.
    fn disk(radius: f64, h: f64) -> Vec<[Vec3; 3]> {
        let n = 512;
        // The fan's area equals the disk's: the polygon's circumradius grows to match.
        let rim = radius * (2.0 * PI / n as f64 / (2.0 * PI / n as f64).sin()).sqrt();
        let at = |k: usize| {
            let a = 2.0 * PI * (k as f64 + 0.3) / n as f64;
            Vec3::new((rim * a.cos()) as f32, h as f32, (rim * a.sin()) as f32)
        };
        (0..n)
            .map(|k| [Vec3::new(0.0, h as f32, 0.0), at(k + 1), at(k)])
            .collect()
    }

    /// The largest difference between two rows.
    fn worst(a: &[f32], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(&x, &y)| (x as f64 - y).abs()).fold(0.0, f64::max)
    }

    /// Unoccluded transfer at normal `n`: T_lm = Â_l·y_lm(n) (rotation equivariance).
    fn unoccluded(n: DVec3, bands: usize) -> Vec<f64> {
        let n = n.normalize();
        let mut y = vec![0.0; bands * bands];
        crate::sh::eval_basis_f64(DVec3::new(n.x, -n.z, n.y), bands, &mut y).unwrap_or_else(|e| panic!("{e}"));
        (0..bands * bands)
            .map(|i| LAMBERT[crate::sh::band_of(i).0] * y[i])
            .collect()
    }

    #[test]
    fn the_directions_are_a_cosine_weighted_grid_on_the_hemisphere() {
        let dirs = cosine_directions(4096);
        assert_eq!(dirs.len(), 4096);
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-12 && d.z > 0.0));
        // Under the density cos θ/π: E[z] = 2/3, E[x] = E[y] = 0, E[z²] = 1/2.
        let mean = dirs.iter().sum::<DVec3>() / 4096.0;
        let z2 = dirs.iter().map(|d| d.z * d.z).sum::<f64>() / 4096.0;
        assert!(
            (mean.z - 2.0 / 3.0).abs() < 2e-4 && mean.x.abs() < 1e-12 && mean.y.abs() < 1e-12,
            "{mean}"
        );
        assert!((z2 - 0.5).abs() < 1e-4, "{z2}");
        // Not a square: the largest square below.
        assert_eq!(cosine_directions(1000).len(), 961);
    }

    #[test]
    fn an_unoccluded_receiver_facing_up_gets_the_clamped_cosine() {
        let r = Receivers::explicit(&[up()], Vec::new());
        let t = bake(&r, 4, 4096, Clip::default());
        let mut want = [0.0; 16];
        (want[0], want[2], want[6], want[12]) = (T00, T10, T20, 0.0);
        let err = worst(&t, &want);
        assert!(err < 2e-3, "{t:?}: max error {err}");
    }

    #[test]
    fn unoccluded_receivers_at_random_normals_get_the_rotated_clamped_cosine() {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut random = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let points: Vec<(DVec3, DVec3)> = (0..40)
            .map(|_| {
                (
                    DVec3::new(random(), random(), random()) * 5.0,
                    DVec3::new(random(), random(), random()),
                )
            })
            .collect();
        // Far off: a triangle that no ray reaches (the set is not empty, so rays are traced).
        let r = Receivers::explicit(
            &points,
            vec![[
                Vec3::splat(100.0),
                Vec3::new(101.0, 100.0, 100.0),
                Vec3::new(100.0, 101.0, 100.0),
            ]],
        );
        for bands in [4, 6] {
            let t = bake(&r, bands, 4096, Clip::default());
            let dim = bands * bands;
            for (k, p) in points.iter().enumerate() {
                let err = worst(&t[k * dim..(k + 1) * dim], &unoccluded(p.1, bands));
                assert!(err < 2e-3, "{bands} bands, normal {}: max error {err}", p.1);
            }
        }
    }

    #[test]
    fn a_disk_overhead_leaves_the_cosine_outside_its_cone() {
        // 40°: sin²α is no multiple of 1/64, so the edge cuts a ring of cells.
        for (deg, t00, t10) in [
            (30.0f64, 0.66467, 0.66467),
            (40.0, 0.52006, 0.46002),
            (45.0, 0.44311, 0.36180),
            (60.0, 0.22156, 0.12792),
        ] {
            let a = deg.to_radians();
            // The closed forms: the visible cone is θ > α.
            assert!((T00 * a.cos().powi(2) - t00).abs() < 1e-5 && (T10 * a.cos().powi(3) - t10).abs() < 1e-5);
            let h = 1.5;
            let r = Receivers::explicit(&[up()], disk(h * a.tan(), h));
            let t = bake(&r, 4, 4096, Clip::default());
            assert!(
                (t[0] as f64 - t00).abs() < 0.01 && (t[2] as f64 - t10).abs() < 0.01,
                "α = {deg}°: T00 {} want {t00}, T10 {} want {t10}",
                t[0],
                t[2]
            );
            // Symmetric about the normal: no m ≠ 0 terms.
            for (i, &x) in t.iter().enumerate() {
                assert!(
                    crate::sh::band_of(i).1 == 0 || x.abs() < 2e-3,
                    "α = {deg}°: T[{i}] = {x}"
                );
            }
        }
    }

    #[test]
    fn a_receiver_inside_a_closed_box_sees_nothing() {
        let r = Receivers::explicit(
            &[(DVec3::new(0.1, -0.2, 0.3), DVec3::new(0.3, 1.0, -0.5)), up()],
            closed_box(2.0),
        );
        let t = bake(&r, 4, 1024, Clip::default());
        assert!(t.iter().all(|x| x.abs() < 1e-6), "{t:?}");
    }

    #[test]
    fn an_empty_occluder_set_shadows_nothing_even_inside_a_box() {
        let mut r = Receivers::explicit(&[up(), up()], closed_box(2.0));
        r.sets.push(OccluderSet::default());
        r.set[1] = 1;
        let t = bake(&r, 4, 4096, Clip::default());
        assert!(
            t[..16].iter().all(|x| x.abs() < 1e-6),
            "in the box's set: {:?}",
            &t[..16]
        );
        let err = worst(&t[16..], &unoccluded(DVec3::Y, 4));
        assert!(err < 2e-3, "in the empty set: {:?}, max error {err}", &t[16..]);
    }

    #[test]
    fn far_ignores_walls_beyond_it() {
        // The walls are 1 to √3 away from the centre.
        let r = Receivers::explicit(&[up()], closed_box(2.0));
        let free = unoccluded(DVec3::Y, 4);
        let short = bake(&r, 4, 4096, Clip { near: 1e-3, far: 0.95 });
        assert!(worst(&short, &free) < 2e-3, "far 0.95: {short:?}");
        let long = bake(
            &r,
            4,
            4096,
            Clip {
                near: 1e-3,
                far: f64::INFINITY,
            },
        );
        assert!(long.iter().all(|x| x.abs() < 1e-6), "far ∞: {long:?}");
        // Far between the nearest wall and the corners: only part of the box blocks.
        let some = bake(&r, 4, 4096, Clip { near: 1e-3, far: 1.2 });
        assert!(
            some[0] > 0.05 && some[0] < (T00 - 0.05) as f32,
            "far 1.2: T00 {}",
            some[0]
        );
    }

    #[test]
    fn near_ignores_an_occluder_closer_than_it() {
        // A disk 0.5 above, 60° half-angle; its points are 0.5 to 1.0 away.
        let r = Receivers::explicit(&[up()], disk(0.5 * 3f64.sqrt(), 0.5));
        let behind = bake(
            &r,
            4,
            4096,
            Clip {
                near: 1.01,
                far: f64::INFINITY,
            },
        );
        assert!(worst(&behind, &unoccluded(DVec3::Y, 4)) < 2e-3, "near 1.01: {behind:?}");
        let before = bake(
            &r,
            4,
            4096,
            Clip {
                near: 0.45,
                far: f64::INFINITY,
            },
        );
        assert!(
            (before[0] as f64 - 0.22156).abs() < 0.01 && (before[2] as f64 - 0.12792).abs() < 0.01,
            "near 0.45: {before:?}"
        );
    }

    #[test]
    fn bad_arguments_are_refused() {
        let r = Receivers::explicit(&[up()], Vec::new());
        let mut p = Progress::new("test");
        for (bands, samples) in [(0, 1024), (9, 1024), (4, 0), (4, 1000), (4, 2)] {
            assert!(
                matches!(
                    bake_cpu(&r, bands, samples, Clip::default(), &mut p),
                    Err(Error::Usage(_))
                ),
                "{bands} bands, {samples} samples"
            );
        }
        for clip in [
            Clip { near: 1.0, far: 0.5 },
            Clip { near: -1.0, far: 1.0 },
            Clip {
                near: f64::NAN,
                far: 1.0,
            },
        ] {
            assert!(
                matches!(bake_cpu(&r, 4, 1024, clip, &mut p), Err(Error::Usage(_))),
                "{clip:?}"
            );
        }
        let mut bad = r.clone();
        bad.set[0] = 1;
        assert!(matches!(
            bake_cpu(&bad, 4, 1024, Clip::default(), &mut p),
            Err(Error::Usage(_))
        ));
        assert!(bake_cpu(&Receivers::default(), 4, 1024, Clip::default(), &mut p).is_ok_and(|t| t.is_empty()));
    }
}
