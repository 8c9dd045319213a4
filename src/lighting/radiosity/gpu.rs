//! The shooting step on the GPU: the same progressive refinement as
//! [`crate::lighting::lightmap::solve`] — the same blocks, selection rules, form factors and visibility rays
//! through a BVH of the static triangles — with every shot run as three compute passes
//! (`glsl/radiosity/`: block powers, the selection in one workgroup, the receivers' gather). Many
//! shots go in one submission; the host reads back only the shot record between submissions (to
//! stop and show progress) and the patches' radiosity at the end.
//!
//! It differs from the CPU solve in precision (fp32 against fp64) and, in faithful mode, in the
//! random numbers that pick candidate shooters; tests/methods/radiosity_gpu.rs checks that both converge
//! to the same light-map.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::backend::{vk, BufferDesc, BufferId, ComputePipelineDesc, Frame, Gpu, MemoryKind, PipelineId};
use crate::bake::gpu_loop::{cut_invocations, dvec4, loop_limit_error, storage_buffer, BatchSizer};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::lighting::lightmap::patches::{Patches, Triangle, COVERAGE_SAMPLES};
use crate::lighting::lightmap::solve::{self, show_progress, Mode, Report, Settings};
use crate::lighting::lightmap::visibility::Matrix;
use crate::raytrace::bvh::Bvh;
use crate::raytrace::texel_table::GpuBvh;
use crate::raytrace::TracedTriangle;
use crate::shaders::ShaderLibrary;
use crate::util::progress::Progress;

/// `Patch` in glsl/radiosity/shooting.glsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuPatch {
    centre: [f32; 4],
    normal: [f32; 4],
    albedo: [f32; 4],
    ids: [u32; 4],
    first_sample: [f32; 4],
    step_u: [f32; 4],
    step_v: [f32; 4],
}

/// `Radiosity`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuRadiosity {
    total: [f32; 4],
    unshot: [f32; 4],
}

/// `Block`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuBlock {
    range: [u32; 4],
    corners: [[f32; 4]; 4],
}

/// `Shot`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuShot {
    centre: [f32; 4],
    normal: [f32; 4],
    flux: [f32; 4],
    corners: [[f32; 4]; 4],
    size: [f32; 4],
    state: [u32; 4],
    shots: [u32; 4],
}

/// `Push`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShootPush {
    patch_count: u32,
    block_count: u32,
    chart_count: u32,
    triangle_count: u32,
    mode: u32,
    samples_per_chart: u32,
    /// Every dispatch of a solve pushes the same constants: lavapipe compiles a shader anew for
    /// each set of push-constant values it has not seen (it inlines them), so the shot's number
    /// lives in the shot record instead.
    near_field: f32,
    log_capacity: u32,
    stop: f32,
    epsilon: f32,
    patch_size: f32,
    max_shots: u32,
    /// 1 when the visibility matrix was built; 0 makes every chart pair PARTIAL.
    visibility_matrix: u32,
}

const NO_BLOCK: u32 = u32::MAX;
/// Each shot is three passes and three descriptor sets; a frame's pool holds 2048 sets.
const MAX_SHOTS_PER_SUBMISSION: usize = 512;

/// A buffer the host reads back.
fn host_buffer(gpu: &mut Gpu, name: &str, size: u64, usage: vk::BufferUsageFlags) -> Result<BufferId> {
    Ok(gpu.create_buffer(&BufferDesc {
        name: name.into(),
        size: size.max(4),
        usage,
        memory: MemoryKind::GpuToCpu,
    })?)
}

/// Shoots on the GPU until the settings' stop, then writes every patch's total and unshot
/// radiosity back into `p`.
pub fn solve(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    p: &mut Patches,
    triangles: &[Triangle],
    settings: &Settings,
    progress: &mut Progress,
) -> Result<Report> {
    solve_in(gpu, shaders, p, triangles, None, settings, progress)
}

/// [`solve()`] with the visibility matrix started from a leaf PVS, as the CPU solve starts it
/// from [`solve::Occluders::pvs`].
pub fn solve_in(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    p: &mut Patches,
    triangles: &[Triangle],
    pvs: Option<&crate::lighting::lightmap::visibility::ChartPvs>,
    settings: &Settings,
    progress: &mut Progress,
) -> Result<Report> {
    // Every buffer, pipeline and frame of the solve is freed on every exit path.
    gpu.scoped(|gpu| run(gpu, shaders, p, triangles, pvs, settings, progress))
}

fn run(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    p: &mut Patches,
    triangles: &[Triangle],
    pvs: Option<&crate::lighting::lightmap::visibility::ChartPvs>,
    settings: &Settings,
    progress: &mut Progress,
) -> Result<Report> {
    // The CPU solve's blocks: parted by walls in the corrected mode.
    let walls = (settings.mode == solve::Mode::Corrected).then(|| solve::Occluders::new(triangles));
    let blocks = solve::blocks(p, settings.block.max(1), walls.as_ref());
    let mut report = Report::default();
    if blocks.is_empty() {
        progress.finish();
        return Ok(report);
    }
    let tables = Tables::new(p, &blocks);
    // The CPU solve's visibility matrix.
    let matrix = progress.stage("chart visibility", || {
        Matrix::build_up_to(
            triangles,
            &p.charts,
            settings.full_visibility,
            pvs,
            settings.matrix_charts,
        )
    });
    report.visibility = matrix.counts();
    let visibility = packed_visibility(&matrix, p.charts.len());
    let tris: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.p.map(|q| q.as_vec3())).collect();
    let bvh = Bvh::build(&tris);
    let traced = TracedTriangle::in_leaf_order(&bvh, &tris);
    let log_capacity = settings.max_shots.saturating_add(1).min(1 << 22);
    crate::bake::check_cancelled(progress, super::bake::SET_UP)?;
    let shooter = Shooter::new(gpu, shaders, &tables, &visibility, log_capacity)?;

    // The initial unshot power, as the CPU solve measures it (its stop is a fraction of it).
    let initial: f64 = blocks
        .iter()
        .flat_map(|b| &b.members)
        .map(|&k| p.patches[k].unshot.abs().element_sum() * p.patches[k].area)
        .sum();
    let push = ShootPush {
        patch_count: p.patches.len() as u32,
        block_count: blocks.len() as u32,
        chart_count: p.charts.len() as u32,
        triangle_count: traced.len() as u32,
        mode: match settings.mode {
            Mode::Faithful => 0,
            Mode::Corrected => 1,
        },
        samples_per_chart: settings.samples_per_chart as u32,
        near_field: solve::NEAR_FIELD as f32,
        log_capacity: log_capacity as u32,
        stop: (settings.threshold * initial) as f32,
        epsilon: (1e-4 * p.size) as f32,
        patch_size: p.size as f32,
        max_shots: settings.max_shots.min(u32::MAX as usize) as u32,
        visibility_matrix: u32::from(matrix.is_built()),
    };
    let mut states = ResourceStates::default();
    let bvh_tables = GpuBvh::upload(
        gpu,
        &mut states,
        "radiosity",
        &bvh.nodes,
        &traced,
        Some(&bvh.skip_links()),
    )?;
    crate::bake::check_cancelled(progress, super::bake::SET_UP)?;
    // The shooting's rate is timed from here, not from the set-up's start.
    show_progress(progress, 0, initial, initial, settings.threshold);
    let (shot, unshot_power) = shooter.shoot(gpu, &mut states, &bvh_tables, push, |shots, left| {
        show_progress(progress, shots, left.unwrap_or(initial), initial, settings.threshold);
        crate::bake::check_cancelled(progress, "radiosity shooting")
    })?;
    report.unshot_power = unshot_power;
    report.shots = shot.shots[0] as usize;
    report.full_searches = shot.state[2] as usize;
    // The GPU does not count its rays one by one (report.rays and rays_saved stay 0).

    let solved = shooter.read_back_state(gpu, &mut states, tables.state.len())?;
    for (q, s) in p.patches.iter_mut().zip(&solved) {
        q.total = glam::DVec3::new(s.total[0] as f64, s.total[1] as f64, s.total[2] as f64);
        q.unshot = glam::DVec3::new(s.unshot[0] as f64, s.unshot[1] as f64, s.unshot[2] as f64);
    }
    progress.finish();
    Ok(report)
}

/// The patches, blocks and charts as the shaders read them, and the patches' starting radiosity.
struct Tables {
    patches: Vec<GpuPatch>,
    state: Vec<GpuRadiosity>,
    blocks: Vec<GpuBlock>,
    /// Each block's patches, block after block (`GpuBlock::range` indexes it).
    members: Vec<u32>,
    /// Each chart's first block and block count.
    charts: Vec<[u32; 2]>,
}

impl Tables {
    fn new(p: &Patches, blocks: &[solve::Block]) -> Tables {
        let mut block_of = vec![NO_BLOCK; p.patches.len()];
        let mut members = Vec::new();
        let mut gpu_blocks = Vec::with_capacity(blocks.len());
        let mut charts = vec![[0u32; 2]; p.charts.len()];
        for (b, block) in blocks.iter().enumerate() {
            // solve::blocks lays blocks out chart by chart.
            let c = &mut charts[block.chart];
            if c[1] == 0 {
                c[0] = b as u32;
            }
            c[1] += 1;
            gpu_blocks.push(GpuBlock {
                range: [members.len() as u32, block.members.len() as u32, block.chart as u32, 0],
                corners: block.corners.map(|q| dvec4(q, 1.0)),
            });
            for &k in &block.members {
                block_of[k] = b as u32;
                members.push(k as u32);
            }
        }
        let patches = p
            .patches
            .iter()
            .enumerate()
            .map(|(k, q)| {
                let c = &p.charts[q.chart];
                let cell = c.cell_of(k);
                let step = p.size / COVERAGE_SAMPLES as f64;
                GpuPatch {
                    centre: dvec4(q.centre, q.area as f32),
                    normal: dvec4(q.normal, 0.0),
                    albedo: dvec4(q.albedo, 0.0),
                    ids: [q.chart as u32, block_of[k], q.samples as u32, u32::from(c.curved)],
                    first_sample: dvec4(c.sub_sample(p.size, cell, (0, 0)), 0.0),
                    step_u: dvec4(c.u * step, 0.0),
                    step_v: dvec4(c.v * step, 0.0),
                }
            })
            .collect();
        let state = p
            .patches
            .iter()
            .map(|q| GpuRadiosity {
                total: dvec4(q.total, 0.0),
                unshot: dvec4(q.unshot, 0.0),
            })
            .collect();
        Tables {
            patches,
            state,
            blocks: gpu_blocks,
            members,
            charts,
        }
    }
}

/// The visibility matrix as the shader reads it: 2 bits per ordered chart pair (i·charts + j).
fn packed_visibility(matrix: &Matrix, n: usize) -> Vec<u32> {
    if !matrix.is_built() {
        // The shader reads no entry then (`visibility_matrix` 0); a binding needs a word.
        return vec![0];
    }
    let mut visibility = vec![0u32; (n * n).div_ceil(16)];
    for i in 0..n {
        for j in 0..n {
            let k = i * n + j;
            visibility[k / 16] |= (matrix.get(i, j) as u32) << (2 * (k % 16));
        }
    }
    visibility
}

/// The solve's buffers, pipelines and frame on the device.
struct Shooter {
    patches: BufferId,
    state: BufferId,
    blocks: BufferId,
    members: BufferId,
    charts: BufferId,
    power: BufferId,
    visibility: BufferId,
    shot: BufferId,
    status: BufferId,
    log: BufferId,
    readback: BufferId,
    power_pipeline: PipelineId,
    select_pipeline: PipelineId,
    shoot_pipeline: PipelineId,
    frame: Frame,
}

impl Shooter {
    fn new(
        gpu: &mut Gpu,
        shaders: &ShaderLibrary,
        tables: &Tables,
        visibility: &[u32],
        log_capacity: usize,
    ) -> Result<Shooter> {
        let none = vk::BufferUsageFlags::empty();
        let storage = |gpu: &mut Gpu, name: &str, data: &[u8]| storage_buffer(gpu, name, none, data);
        let patches = storage(gpu, "radiosity patches", bytemuck::cast_slice(&tables.patches))?;
        let state = storage_buffer(
            gpu,
            "radiosity state",
            vk::BufferUsageFlags::TRANSFER_SRC,
            bytemuck::cast_slice(&tables.state),
        )?;
        let blocks = storage(gpu, "radiosity blocks", bytemuck::cast_slice(&tables.blocks))?;
        let members = storage(gpu, "radiosity block members", bytemuck::cast_slice(&tables.members))?;
        let charts = storage(gpu, "radiosity charts", bytemuck::cast_slice(&tables.charts))?;
        let power = storage(gpu, "radiosity block power", &vec![0u8; 4 * tables.blocks.len()])?;
        let visibility = storage(gpu, "radiosity visibility matrix", bytemuck::cast_slice(visibility))?;
        let storage_host = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let shot_size = std::mem::size_of::<GpuShot>() as u64;
        let shot = host_buffer(gpu, "radiosity shot", shot_size, storage_host)?;
        let status = host_buffer(gpu, "radiosity status", 4, storage_host)?;
        let log = host_buffer(gpu, "radiosity unshot log", 4 * log_capacity as u64, storage_host)?;
        let readback = host_buffer(
            gpu,
            "radiosity state readback",
            std::mem::size_of_val(tables.state.as_slice()) as u64,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let pipeline = |gpu: &mut Gpu, name: &str, shader: &str| -> Result<PipelineId> {
            Ok(gpu.create_compute_pipeline(
                &ComputePipelineDesc {
                    name: name.into(),
                    shader: shader.into(),
                    specialization: vec![],
                },
                shaders,
            )?)
        };
        Ok(Shooter {
            patches,
            state,
            blocks,
            members,
            charts,
            power,
            visibility,
            shot,
            status,
            log,
            readback,
            power_pipeline: pipeline(gpu, "radiosity block power", "radiosity/block_power.comp")?,
            select_pipeline: pipeline(gpu, "radiosity select", "radiosity/select.comp")?,
            shoot_pipeline: pipeline(gpu, "radiosity shoot", "radiosity/shoot.comp")?,
            frame: gpu.create_frame()?,
        })
    }

    /// Shoots in submissions sized by their time until the shaders report the stop, calling
    /// `progress` with the shots so far and the last unshot power logged (none yet: `None`)
    /// after each; an error it returns (the bake was cancelled) ends the shooting.
    /// Returns the last shot record and the unshot power logged after each shot.
    fn shoot(
        &self,
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        bvh: &GpuBvh,
        push: ShootPush,
        mut progress: impl FnMut(usize, Option<f64>) -> Result<()>,
    ) -> Result<(GpuShot, Vec<f64>)> {
        let mut recorded = 0usize;
        let mut sizer = BatchSizer::new(4, 1, MAX_SHOTS_PER_SUBMISSION, 2);
        loop {
            let batch = sizer.size();
            let t0 = std::time::Instant::now();
            let mut graph = RenderGraph::new();
            if recorded == 0 {
                self.add_clear(&mut graph);
            }
            for _ in 0..batch {
                self.add_shot(&mut graph, bvh, push);
            }
            graph.output_buffer(self.state);
            graph
                .pass("radiosity host")
                .buffer(self.shot, Access::HostRead, None)
                .buffer(self.log, Access::HostRead, None)
                .buffer(self.status, Access::HostRead, None)
                .record(|_| Ok(()));
            graph.run_and_wait(gpu, self.frame, states, "radiosity shooting")?;
            recorded += batch;
            let cut = cut_invocations(gpu, self.status, "radiosity shooting")?;
            if cut > 0 {
                return Err(loop_limit_error(
                    gpu,
                    cut,
                    "radiosity visibility ray(s)",
                    "use baker = \"cpu\"",
                ));
            }
            let (shot, log) = self.read_shot(gpu)?;
            progress(shot.shots[0] as usize, log.last().copied())?;
            if shot.state[1] != 0 {
                return Ok((shot, log));
            }
            sizer.record(batch, t0.elapsed());
        }
    }

    /// Zeroes the shot record and the status word before the first shot.
    fn add_clear(&self, graph: &mut RenderGraph<'_>) {
        let (shot, status) = (self.shot, self.status);
        graph
            .pass("radiosity clear shot")
            .buffer(shot, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(shot, 0));
        graph
            .pass("radiosity clear status")
            .buffer(status, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(status, 0));
    }

    /// One shot: the blocks' unshot power, the selection of the shooter, the receivers' gather.
    fn add_shot(&self, graph: &mut RenderGraph<'_>, bvh: &GpuBvh, push: ShootPush) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let read = Access::StorageRead { stages: compute };
        let write = Access::StorageWrite { stages: compute };
        let (power_pipeline, select_pipeline, shoot_pipeline) =
            (self.power_pipeline, self.select_pipeline, self.shoot_pipeline);
        graph
            .pass("radiosity block power")
            .buffer(self.patches, read, Some("patches"))
            .buffer(self.state, read, Some("radiosity"))
            .buffer(self.blocks, read, Some("blocks"))
            .buffer(self.members, read, Some("members"))
            .buffer(self.shot, read, Some("shots"))
            .buffer(self.power, write, Some("block_power"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(power_pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                ctx.rec.dispatch([push.block_count, 1, 1])
            });
        graph
            .pass("radiosity select")
            .buffer(self.patches, read, Some("patches"))
            .buffer(self.state, read, Some("radiosity"))
            .buffer(self.blocks, read, Some("blocks"))
            .buffer(self.members, read, Some("members"))
            .buffer(self.shot, write, Some("shots"))
            .buffer(self.power, read, Some("block_power"))
            .buffer(self.charts, read, Some("charts"))
            .buffer(self.log, write, Some("unshot_log"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(select_pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                ctx.rec.dispatch([64, 1, 1])
            });
        bvh.read(graph.pass("radiosity shoot"), compute)
            .buffer(self.patches, read, Some("patches"))
            .buffer(self.state, write, Some("radiosity"))
            .buffer(self.shot, read, Some("shots"))
            .buffer(self.visibility, read, Some("visibility"))
            .buffer(self.status, write, Some("status"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(shoot_pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                ctx.rec.dispatch([push.patch_count, 1, 1])
            });
    }

    /// The shot record and the unshot power logged after each shot so far.
    fn read_shot(&self, gpu: &Gpu) -> Result<(GpuShot, Vec<f64>)> {
        let bytes = gpu.read_buffer(self.shot)?;
        let shot: GpuShot = bytemuck::pod_read_unaligned(
            bytes
                .get(..std::mem::size_of::<GpuShot>())
                .ok_or_else(|| Error::Internal("radiosity: the shot record read back short".into()))?,
        );
        let log = gpu.read_buffer(self.log)?;
        let logged = (shot.state[3] as usize).min(log.len() / 4);
        let log = bytemuck::cast_slice::<u8, f32>(&log[..4 * logged])
            .iter()
            .map(|&x| x as f64)
            .collect();
        Ok((shot, log))
    }

    /// Copies the patches' radiosity (`patches` of them) to the host and reads it.
    fn read_back_state(&self, gpu: &mut Gpu, states: &mut ResourceStates, patches: usize) -> Result<Vec<GpuRadiosity>> {
        let state_bytes = patches * std::mem::size_of::<GpuRadiosity>();
        let (state, readback) = (self.state, self.readback);
        let mut graph = RenderGraph::new();
        graph
            .pass("radiosity read back")
            .buffer(state, Access::TransferRead, None)
            .buffer(readback, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.copy_buffer(state, readback, state_bytes as u64));
        graph
            .pass("radiosity host")
            .buffer(readback, Access::HostRead, None)
            .record(|_| Ok(()));
        graph.run_and_wait(gpu, self.frame, states, "radiosity readback")?;
        let bytes = gpu.read_buffer(readback)?;
        bytes
            .get(..state_bytes)
            .map(bytemuck::pod_collect_to_vec)
            .ok_or_else(|| Error::Internal("radiosity: the read-back state is short".into()))
    }
}
