//! Staniszewski 2005's baker (digest §1.2–1.6): per batch of vertices, the occluders rendered from every
//! vertex into its tile of a visibility atlas (`glsl/prt/visibility.*`), then per group of four
//! coefficients the multiplicative stage (`multiply.comp`: V · weight · y_i) and the integration
//! — the document's four ping-pong passes (`reduce_axis.comp`, `reduce_last.comp`) or one
//! workgroup per tile (`reduce_tile.comp`) — into each receiver's slot of the coefficient buffer.
//! The visibility atlas is rendered once per batch and reused by every group.
//!
//! Receivers are laid out per occluder set, each set's first slot a multiple of the batch size,
//! so a batch holds the receivers of one set and an instance's tile is its slot modulo the batch;
//! the slots past a set's last receiver are the document's empty vertices: rendered as nothing,
//! never written back.

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use super::config::{Config, Coverage, Depth, Directions, Reduction};
use super::mapping;
use super::receivers::{tangent_frame, Receivers};
use crate::backend::{
    vk, Bind, BufferDesc, BufferId, ColorTarget, ComputePipelineDesc, DepthState, Gpu, GraphicsPipelineDesc, ImageDesc,
    ImageId, MemoryKind, PipelineId, RenderTarget, RenderingDesc, SamplerDesc, SamplerId, SpecConstant,
    SubresourceRange, VertexAttribute, VertexLayout,
};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::shaders::ShaderLibrary;
use crate::util::progress::Progress;

/// `PrtReceiver` in glsl/prt/mapping.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuReceiver {
    pub position: [f32; 4],
    pub tangent: [f32; 4],
    pub bitangent: [f32; 4],
    pub normal: [f32; 4],
}

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

/// The taps of the four reduction passes along one axis for a tile side (8 × 4 = 32, the
/// document's schedule).
pub fn taps(tile: u32) -> (u32, u32) {
    match tile {
        8 => (4, 2),
        16 => (4, 4),
        32 => (8, 4),
        64 => (8, 8),
        _ => (16, tile / 16),
    }
}

/// The receivers' slots: per occluder set a run starting at a multiple of the batch size.
pub struct Slots {
    /// Per receiver, its slot.
    pub slot: Vec<u32>,
    /// Per batch: (occluder set, first slot, receivers in it).
    pub batches: Vec<(usize, u32, u32)>,
    pub total: u32,
}

impl Slots {
    pub fn new(r: &Receivers, batch: u32) -> Slots {
        let mut slot = vec![0u32; r.len()];
        let mut batches = Vec::new();
        let mut next = 0u32;
        for s in 0..r.sets.len() {
            let members = r.of_set(s);
            for (k, &i) in members.iter().enumerate() {
                slot[i] = next + k as u32;
            }
            for (b, chunk) in members.chunks(batch as usize).enumerate() {
                batches.push((s, next + b as u32 * batch, chunk.len() as u32));
            }
            next += (members.len() as u32).div_ceil(batch) * batch;
        }
        Slots {
            slot,
            batches,
            total: next,
        }
    }
}

/// What one bake needs on the device.
struct Bake {
    receivers: BufferId,
    weights: BufferId,
    batch: BufferId,
    coefficients: BufferId,
    /// The occluder triangles as corners (vec4 × 3).
    triangles: BufferId,
    /// Exact coverage: the listing pass (`cull.comp`), its rectangles and the indirect draw
    /// command it counts into, and the triangles per chunk.
    cull: Option<Cull>,
    /// Per occluder set: (first corner, corner count) in `triangles`.
    set_vertices: Vec<(u32, u32)>,
    atlas: ImageId,
    depth: ImageId,
    product: ImageId,
    /// The reduction's intermediate images (the document's framebuffers 1–3).
    stages: [ImageId; 3],
    visibility: PipelineId,
    /// The document's directions: the colour-coded sphere's pipeline, vertices and count.
    sphere: Option<(PipelineId, BufferId, u32)>,
    /// Listing 2.2's basis textures (bound always; read with `directions = "sphere"`).
    basis: ImageId,
    sampler: SamplerId,
    /// Per coefficient group: multiply, then the reduction's pipelines.
    multiply: Vec<PipelineId>,
    reduce: Vec<Vec<PipelineId>>,
}

/// Exact coverage's listing of the rectangles to draw (`glsl/prt/cull.comp`).
struct Cull {
    pipeline: PipelineId,
    rects: BufferId,
    /// Two triangles over each rectangle's four vertices, for as many rectangles as a chunk holds.
    indices: BufferId,
    command: BufferId,
    chunk_triangles: u32,
}

/// `Chunk` in glsl/prt/cull.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ChunkPush {
    first_slot: u32,
    receivers: u32,
    first_triangle: u32,
    triangle_count: u32,
}

/// Bytes of one listed rectangle (`Rect` in glsl/prt/cull.comp).
const RECT_BYTES: u64 = 64;

/// Bakes the transfer of every receiver (`bands²` per receiver, receiver-major) on the device.
pub fn bake(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    r: &Receivers,
    config: &Config,
    progress: &mut Progress,
) -> Result<Vec<f32>> {
    gpu.scoped(|gpu| run(gpu, shaders, r, config, None, progress))
}

/// The integration stage alone over a given product atlas (RGBA per pixel, row-major, the
/// atlas's size), for one batch of `config.batch` real receivers: the per-tile sums, 4 per tile
/// (test 10, reduction exactness).
pub fn reduce_only(gpu: &mut Gpu, shaders: &ShaderLibrary, config: &Config, product: &[f32]) -> Result<Vec<f32>> {
    let n = config.batch as usize;
    let r = Receivers::explicit(&vec![(DVec3::ZERO, DVec3::Y); n], Vec::new());
    let all = gpu.scoped(|gpu| {
        run(
            gpu,
            shaders,
            &r,
            config,
            Some(product),
            &mut Progress::new("prt reduction"),
        )
    })?;
    // Every group reduces the same uploaded atlas: the first group's four are the sums.
    let dim = config.bands() * config.bands();
    Ok(all.chunks(dim).flat_map(|c| c[..4].to_vec()).collect())
}

fn image(gpu: &mut Gpu, name: &str, format: vk::Format, w: u32, h: u32, usage: vk::ImageUsageFlags) -> Result<ImageId> {
    Ok(gpu.create_image(&ImageDesc::new_2d(name, format, w, h).usage(usage))?)
}

fn run(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    r: &Receivers,
    config: &Config,
    product_override: Option<&[f32]>,
    progress: &mut Progress,
) -> Result<Vec<f32>> {
    let dim = config.bands() * config.bands();
    if r.is_empty() {
        progress.finish();
        return Ok(Vec::new());
    }
    let slots = Slots::new(r, config.batch);
    let side = config.atlas_side();
    let rows = config.batch.div_ceil(config.tiles_per_row());
    let (w, h) = (side, rows * config.tile);
    if w > gpu.caps().max_image_dimension_2d || h > gpu.caps().max_image_dimension_2d {
        return Err(Error::Usage(format!(
            "prt: a {w}x{h} visibility atlas exceeds the device's {} pixels; lower batch or tile",
            gpu.caps().max_image_dimension_2d
        )));
    }
    let receivers = gpu_receivers(r, &slots, config);
    let occluders = OccluderCorners::new(r);
    // An unbounded far plane becomes one past everything (depth only orders occluders).
    let far = if config.far.is_finite() {
        config.far
    } else {
        config.near + 2.0 * (occluders.hi - occluders.lo).length().max(1.0)
    };
    let mut bake = Bake::create(gpu, shaders, config, &slots, &receivers, occluders, (w, h, far))?;
    for g in 0..dim.div_ceil(4) as u32 {
        let (multiply, reduce) = group_pipelines(gpu, shaders, config, g)?;
        bake.multiply.push(multiply);
        bake.reduce.push(reduce);
    }
    if let Some(product) = product_override {
        if product.len() != (w * h * 4) as usize {
            return Err(Error::Internal(format!(
                "prt: a product atlas of {} floats, expected {}",
                product.len(),
                w * h * 4
            )));
        }
        gpu.upload_image(bake.product, 0, bytemuck::cast_slice(product))?;
    }
    run_batches(gpu, &bake, config, &slots, (w, h), product_override.is_none(), progress)?;
    let bytes = gpu.read_buffer(bake.coefficients)?;
    let all: &[f32] = bytemuck::try_cast_slice(&bytes[..slots.total as usize * 64])
        .map_err(|e| Error::Internal(format!("prt: coefficient readback: {e}")))?;
    let mut out = vec![0.0f32; r.len() * dim];
    for i in 0..r.len() {
        let s = slots.slot[i] as usize;
        out[i * dim..(i + 1) * dim].copy_from_slice(&all[s * 16..s * 16 + dim]);
    }
    Ok(out)
}

/// Every receiver's frame in its slot (the empty slots zero).
fn gpu_receivers(r: &Receivers, slots: &Slots, config: &Config) -> Vec<GpuReceiver> {
    let mut receivers = vec![GpuReceiver::default(); slots.total as usize];
    for i in 0..r.len() {
        let (t, b) = tangent_frame(r.normals[i], config.twist);
        receivers[slots.slot[i] as usize] = GpuReceiver {
            position: v4(r.positions[i], 1.0),
            tangent: v4(t, 0.0),
            bitangent: v4(b, 0.0),
            normal: v4(r.normals[i], 0.0),
        };
    }
    receivers
}

/// The occluder sets' triangles as one list of corners, each set's range in it, and the
/// bounds of the receivers and occluders together.
struct OccluderCorners {
    /// vec4 corners, three a triangle (one zero corner when there are none, as a buffer is never
    /// empty).
    corners: Vec<[f32; 4]>,
    /// Per occluder set: (first corner, corner count).
    set_vertices: Vec<(u32, u32)>,
    lo: DVec3,
    hi: DVec3,
}

impl OccluderCorners {
    fn new(r: &Receivers) -> Self {
        let mut vertices: Vec<[f32; 3]> = Vec::new();
        let mut set_vertices = Vec::new();
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in &r.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        for s in &r.sets {
            set_vertices.push((vertices.len() as u32, 3 * s.triangles.len() as u32));
            for t in &s.triangles {
                for p in t {
                    lo = lo.min(p.as_dvec3());
                    hi = hi.max(p.as_dvec3());
                    vertices.push(p.to_array());
                }
            }
        }
        let mut corners: Vec<[f32; 4]> = vertices.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        if corners.is_empty() {
            corners.push([0.0; 4]);
        }
        OccluderCorners {
            corners,
            set_vertices,
            lo,
            hi,
        }
    }
}

impl Bake {
    /// The bake's buffers, images and rendering pipelines for a `w` × `h` atlas with depth out
    /// to `far`; the per-group compute pipelines are added after.
    fn create(
        gpu: &mut Gpu,
        shaders: &ShaderLibrary,
        config: &Config,
        slots: &Slots,
        receivers: &[GpuReceiver],
        occluders: OccluderCorners,
        (w, h, far): (u32, u32, f64),
    ) -> Result<Bake> {
        let weights = mapping::weights(config.mapping, config.weights, config.tile);
        let usage_storage = vk::ImageUsageFlags::STORAGE;
        let rgba = vk::Format::R32G32B32A32_SFLOAT;
        let (ta, _) = taps(config.tile);
        Ok(Bake {
            receivers: gpu.create_storage_buffer("prt receivers", bytemuck::cast_slice(receivers))?,
            weights: gpu.create_storage_buffer("prt weights", bytemuck::cast_slice(&weights))?,
            batch: gpu.create_storage_output("prt batch", 4, MemoryKind::GpuOnly)?,
            coefficients: gpu.create_storage_output(
                "prt coefficients",
                slots.total as u64 * 64,
                MemoryKind::GpuToCpu,
            )?,
            triangles: gpu.create_storage_buffer("prt occluder triangles", bytemuck::cast_slice(&occluders.corners))?,
            cull: match config.coverage {
                Coverage::Projected => None,
                Coverage::Exact => Some(cull(gpu, shaders, config)?),
            },
            set_vertices: occluders.set_vertices,
            atlas: image(
                gpu,
                "prt visibility atlas",
                rgba,
                w,
                h,
                vk::ImageUsageFlags::COLOR_ATTACHMENT | usage_storage,
            )?,
            depth: image(
                gpu,
                "prt visibility depth",
                vk::Format::D32_SFLOAT,
                w,
                h,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            )?,
            product: image(
                gpu,
                "prt product",
                rgba,
                w,
                h,
                usage_storage | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED,
            )?,
            stages: [
                image(gpu, "prt reduction 1", rgba, w / ta, h, usage_storage)?,
                image(gpu, "prt reduction 2", rgba, w / config.tile, h, usage_storage)?,
                image(gpu, "prt reduction 3", rgba, w / config.tile, h / ta, usage_storage)?,
            ],
            visibility: visibility_pipeline(gpu, shaders, config, w, h, far)?,
            sphere: match config.directions {
                Directions::Analytic => None,
                Directions::Sphere => Some(colour_sphere(gpu, shaders, config, w, h)?),
            },
            basis: basis_textures(gpu)?,
            sampler: gpu.sampler(SamplerDesc::LINEAR_CLAMP)?,
            multiply: Vec::new(),
            reduce: Vec::new(),
        })
    }
}

/// The colour-coded sphere's pipeline, vertex buffer and vertex count.
fn colour_sphere(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    config: &Config,
    w: u32,
    h: u32,
) -> Result<(PipelineId, BufferId, u32)> {
    let vertices = mapping::colour_sphere();
    let buffer = gpu.create_buffer_init(
        "prt colour sphere",
        vk::BufferUsageFlags::VERTEX_BUFFER,
        bytemuck::cast_slice(&vertices),
    )?;
    Ok((
        sphere_pipeline(gpu, shaders, config, w, h)?,
        buffer,
        vertices.len() as u32,
    ))
}

/// Listing 2.2's basis textures, uploaded.
fn basis_textures(gpu: &mut Gpu) -> Result<ImageId> {
    let basis = gpu.create_image(
        &ImageDesc::new_2d("prt SH basis textures", vk::Format::R32G32B32A32_SFLOAT, 64, 32)
            .layers(4)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    gpu.upload_image(basis, 0, bytemuck::cast_slice(&mapping::basis_textures()))?;
    Ok(basis)
}

/// Coefficient group `g`'s pipelines: the multiplicative stage, and the reduction's (four
/// passes, or one per tile).
fn group_pipelines(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    config: &Config,
    g: u32,
) -> Result<(PipelineId, Vec<PipelineId>)> {
    let common = |id: u32, bits: u32| SpecConstant { id, bits };
    let (ta, tb) = taps(config.tile);
    let base = vec![
        common(0, config.mapping as u32),
        common(2, config.tile),
        common(3, config.tiles_per_row()),
        common(4, config.batch),
        common(10, g),
    ];
    let mut multiply = base.clone();
    multiply.push(common(14, u32::from(config.directions == Directions::Sphere)));
    let multiply = gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: format!("prt multiply {g}"),
            shader: "prt/multiply.comp".into(),
            specialization: multiply,
        },
        shaders,
    )?;
    let mut reduce = Vec::new();
    match config.reduction {
        Reduction::Passes => {
            for (i, (taps, axis)) in [(ta, 0), (tb, 0), (ta, 1)].into_iter().enumerate() {
                reduce.push(gpu.create_compute_pipeline(
                    &ComputePipelineDesc {
                        name: format!("prt reduce pass {} group {g}", i + 1),
                        shader: "prt/reduce_axis.comp".into(),
                        specialization: vec![common(11, taps), common(12, axis)],
                    },
                    shaders,
                )?);
            }
            let mut last = base.clone();
            last.push(common(11, tb));
            reduce.push(gpu.create_compute_pipeline(
                &ComputePipelineDesc {
                    name: format!("prt reduce pass 4 group {g}"),
                    shader: "prt/reduce_last.comp".into(),
                    specialization: last,
                },
                shaders,
            )?);
        }
        Reduction::Compute => {
            reduce.push(gpu.create_compute_pipeline(
                &ComputePipelineDesc {
                    name: format!("prt reduce tiles {g}"),
                    shader: "prt/reduce_tile.comp".into(),
                    specialization: base,
                },
                shaders,
            )?);
        }
    }
    Ok((multiply, reduce))
}

/// Records and runs every batch, one graph each, reporting the rate; `render` false when the
/// product atlas was uploaded (only the integration runs).
fn run_batches(
    gpu: &mut Gpu,
    bake: &Bake,
    config: &Config,
    slots: &Slots,
    (w, h): (u32, u32),
    render: bool,
    progress: &mut Progress,
) -> Result<()> {
    let frame = gpu.create_frame()?;
    let mut states = ResourceStates::default();
    states.set_image(
        gpu,
        bake.basis,
        Access::SampledRead {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
        },
    )?;
    if !render {
        states.set_image(
            gpu,
            bake.product,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )?;
    }
    let t_start = std::time::Instant::now();
    // The rate counts from the first batch, not from the set-up before it.
    progress.update(0, slots.batches.len() as u64);
    for (k, &(set, first, count)) in slots.batches.iter().enumerate() {
        // A large scene's batch can take a minute on a CPU device: stop between them when asked.
        crate::bake::check_cancelled(progress, "prt raster bake")?;
        let mut graph = RenderGraph::new();
        record_batch(&mut graph, bake, config, (set, first, count), (w, h), render);
        graph
            .pass("prt readback")
            .buffer(bake.coefficients, Access::HostRead, None)
            .record(|_| Ok(()));
        graph.run_and_wait(gpu, frame, &mut states, "prt raster bake")?;
        progress.set_detail(format!(
            "batch {}/{}, {:.0} vertices/s",
            k + 1,
            slots.batches.len(),
            (k + 1) as f64 * config.batch as f64 / t_start.elapsed().as_secs_f64().max(1e-9)
        ));
        progress.update(k as u64 + 1, slots.batches.len() as u64);
    }
    progress.finish();
    Ok(())
}

fn cull(gpu: &mut Gpu, shaders: &ShaderLibrary, config: &Config) -> Result<Cull> {
    let chunk_triangles = (config.rect_budget / config.batch).max(1);
    let rects = u64::from(chunk_triangles) * u64::from(config.batch);
    let c = |id: u32, bits: u32| SpecConstant { id, bits };
    let pipeline = gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: "prt cull".into(),
            shader: "prt/cull.comp".into(),
            specialization: vec![c(0, config.mapping as u32), c(2, config.tile)],
        },
        shaders,
    )?;
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    let indices: Vec<u32> = (0..rects as u32)
        .flat_map(|k| [0, 1, 2, 0, 2, 3].map(|i| 4 * k + i))
        .collect();
    Ok(Cull {
        pipeline,
        indices: gpu.create_buffer_init(
            "prt rectangle indices",
            vk::BufferUsageFlags::INDEX_BUFFER,
            bytemuck::cast_slice(&indices),
        )?,
        rects: gpu.create_buffer(&BufferDesc {
            name: "prt rectangles".into(),
            size: rects * RECT_BYTES,
            usage,
            memory: MemoryKind::GpuOnly,
        })?,
        command: gpu.create_buffer(&BufferDesc {
            name: "prt draw command".into(),
            size: 20,
            usage: usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            memory: MemoryKind::GpuOnly,
        })?,
        chunk_triangles,
    })
}

fn visibility_pipeline(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    config: &Config,
    w: u32,
    h: u32,
    far: f64,
) -> Result<PipelineId> {
    let mut desc = match config.coverage {
        Coverage::Projected => {
            GraphicsPipelineDesc::new("prt visibility", "prt/visibility.vert", Some("prt/visibility.frag"))
        }
        Coverage::Exact => GraphicsPipelineDesc::new(
            "prt visibility exact",
            "prt/visibility_exact.vert",
            Some("prt/visibility_exact.frag"),
        ),
    };
    // Occluders block from both sides.
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.depth = DepthState {
        test: true,
        write: true,
        compare: vk::CompareOp::LESS,
    };
    // Occluders write B only: R and G hold the colour-coded sphere's angles.
    desc.color_targets = vec![ColorTarget {
        write_mask: vk::ColorComponentFlags::B,
        ..ColorTarget::new(vk::Format::R32G32B32A32_SFLOAT)
    }];
    desc.depth_format = Some(vk::Format::D32_SFLOAT);
    let c = |id: u32, bits: u32| SpecConstant { id, bits };
    desc.specialization = vec![
        c(0, config.mapping as u32),
        c(1, u32::from(config.depth == Depth::Radial)),
        c(2, config.tile),
        c(3, config.tiles_per_row()),
        c(4, config.batch),
        c(5, w),
        c(6, h),
        c(7, (config.near as f32).to_bits()),
        c(8, (far as f32).to_bits()),
        c(9, u32::from(config.gradient)),
    ];
    Ok(gpu.create_graphics_pipeline(&desc, shaders)?)
}

/// One batch: its first slot into the batch buffer, the visibility atlas, then per group the
/// multiplicative stage and the integration into the coefficient buffer.
fn record_batch<'a>(
    graph: &mut RenderGraph<'a>,
    b: &'a Bake,
    config: &'a Config,
    (set, first, count): (usize, u32, u32),
    (w, h): (u32, u32),
    render: bool,
) {
    let batch = b.batch;
    graph
        .pass("prt batch")
        .buffer(batch, Access::TransferWrite, None)
        .record(move |ctx| ctx.rec.fill_buffer(batch, first));
    if render {
        match &b.cull {
            None => record_visibility(graph, b, config, set, (first, count)),
            Some(cull) => record_exact_visibility(graph, b, cull, set, (first, count)),
        }
    }
    for g in 0..b.multiply.len() {
        record_group(graph, b, config, g, (w, h), render);
    }
}

/// Begins rendering into the visibility atlas, cleared (`clear`) or loaded. B (visibility)
/// starts at 1; R and G (the sphere's angles) at 0, where the document leaves pixels the sphere
/// does not reach.
fn begin_atlas(
    rec: &mut crate::backend::Recorder<'_>,
    b: &Bake,
    clear: bool,
) -> std::result::Result<(), crate::backend::BackendError> {
    let [colour, depth] = if clear {
        [
            RenderTarget::clear_color(b.atlas, [0.0, 0.0, 1.0, 0.0]),
            RenderTarget::clear_depth(b.depth, 1.0, 0),
        ]
    } else {
        [RenderTarget::load(b.atlas), RenderTarget::load(b.depth)]
    };
    rec.begin_rendering(&RenderingDesc {
        colors: vec![colour],
        depth_stencil: Some(depth),
    })
    .map(|_| ())
}

/// Projected coverage: the sphere, then every occluder triangle of set `set` drawn into each
/// of the batch's tiles (one instance per receiver).
fn record_visibility<'a>(
    graph: &mut RenderGraph<'a>,
    b: &'a Bake,
    config: &'a Config,
    set: usize,
    (first, count): (u32, u32),
) {
    let (first_vertex, vertex_count) = b.set_vertices[set];
    // Buffers are bound by name per pipeline: the sphere's and the occluders' pipelines share
    // the pass and read different ones.
    let vertex = Access::StorageRead {
        stages: vk::PipelineStageFlags2::VERTEX_SHADER,
    };
    graph
        .pass("prt visibility")
        .color_attachment(b.atlas, SubresourceRange::full(), true)
        .depth_stencil_write(b.depth, true)
        .buffer(b.receivers, vertex, None)
        .buffer(b.triangles, vertex, None)
        .record(move |ctx| {
            begin_atlas(ctx.rec, b, true)?;
            draw_sphere(ctx, b, first, count)?;
            if vertex_count > 0 {
                ctx.rec.bind_pipeline(b.visibility)?;
                ctx.bind(&[
                    ("receivers", Bind::StorageBuffer(b.receivers)),
                    ("triangles", Bind::StorageBuffer(b.triangles)),
                ])?;
                // Radial depth: six vertices a triangle (visibility.vert: the fan of the
                // triangle clipped to the hemisphere).
                let k = if config.depth == Depth::Radial { 2 } else { 1 };
                ctx.rec
                    .draw_instanced(k * vertex_count, k * first_vertex, count, first)?;
            }
            ctx.rec.end_rendering();
            Ok(())
        });
}

/// Exact coverage: per chunk of set `set`'s triangles, list the rectangles with something to
/// draw, then draw them. The first chunk clears the atlas (and draws the sphere), the rest draw
/// over it.
fn record_exact_visibility<'a>(
    graph: &mut RenderGraph<'a>,
    b: &'a Bake,
    cull: &'a Cull,
    set: usize,
    (first, count): (u32, u32),
) {
    let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
    let vertex = Access::StorageRead {
        stages: vk::PipelineStageFlags2::VERTEX_SHADER,
    };
    let full = SubresourceRange::full();
    let (first_vertex, vertex_count) = b.set_vertices[set];
    let (first_triangle, triangles) = (first_vertex / 3, vertex_count / 3);
    let chunks = triangles.div_ceil(cull.chunk_triangles).max(1);
    for k in 0..chunks {
        let start = k * cull.chunk_triangles;
        let n = cull.chunk_triangles.min(triangles - start);
        let command = cull.command;
        graph
            .pass("prt cull reset")
            .buffer(command, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.update_buffer(command, &[0, 1, 0, 0, 0]));
        let push = ChunkPush {
            first_slot: first,
            receivers: count,
            first_triangle: first_triangle + start,
            triangle_count: n,
        };
        let (pipeline, rects, indices) = (cull.pipeline, cull.rects, cull.indices);
        graph
            .pass("prt cull")
            .buffer(b.receivers, Access::StorageRead { stages: compute }, Some("receivers"))
            .buffer(b.triangles, Access::StorageRead { stages: compute }, Some("triangles"))
            .buffer(rects, Access::StorageWrite { stages: compute }, Some("rects"))
            .buffer(command, Access::StorageWrite { stages: compute }, Some("command"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
                ctx.rec.dispatch([count * n, 1, 1])
            });
        graph
            .pass("prt visibility")
            .color_attachment(b.atlas, full, k == 0)
            .depth_stencil_write(b.depth, k == 0)
            .buffer(b.receivers, vertex, None)
            .buffer(rects, vertex, None)
            .buffer(indices, Access::IndexRead, None)
            .buffer(command, Access::IndirectRead, None)
            .record(move |ctx| {
                begin_atlas(ctx.rec, b, k == 0)?;
                if k == 0 {
                    draw_sphere(ctx, b, first, count)?;
                }
                ctx.rec.bind_pipeline(b.visibility)?;
                ctx.bind(&[("rects", Bind::StorageBuffer(rects))])?;
                ctx.rec.bind_index_buffer(indices, 0)?;
                ctx.rec.draw_indexed_indirect(command, 0)?;
                ctx.rec.end_rendering();
                Ok(())
            });
    }
}

/// Coefficient group `g`: the multiplicative stage (when rendering) and the integration into
/// the batch's receiver slots.
fn record_group<'a>(
    graph: &mut RenderGraph<'a>,
    b: &'a Bake,
    config: &'a Config,
    g: usize,
    (w, h): (u32, u32),
    render: bool,
) {
    let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
    let read = Access::StorageRead { stages: compute };
    let write = Access::StorageWrite { stages: compute };
    let full = SubresourceRange::full();
    let batch = b.batch;
    // The reduction's last step: `src` summed per tile into the batch's receiver slots.
    let to_slots = |graph: &mut RenderGraph<'a>, name: &str, src: ImageId, p: PipelineId, threads: [u32; 3]| {
        graph
            .pass(name)
            .storage_read("src", src, full, compute)
            .buffer(b.receivers, read, Some("receivers"))
            .buffer(b.coefficients, write, Some("coefficients"))
            .buffer(batch, read, Some("batch"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(p)?;
                ctx.bind(&[])?;
                ctx.rec.dispatch(threads)
            });
    };
    if render {
        let multiply = b.multiply[g];
        graph
            .pass("prt multiply")
            .buffer(b.receivers, read, Some("receivers"))
            .storage_read("visibility", b.atlas, full, compute)
            .buffer(b.weights, read, Some("weights"))
            .storage_write("product", b.product, full, compute)
            .buffer(batch, read, Some("batch"))
            .sample("sh_basis", b.basis, full, b.sampler, compute)
            .record(move |ctx| {
                ctx.rec.bind_pipeline(multiply)?;
                ctx.bind(&[])?;
                ctx.rec.dispatch([w, h, 1])
            });
    }
    let reduce = &b.reduce[g];
    match config.reduction {
        Reduction::Passes => {
            let chain = [b.product, b.stages[0], b.stages[1], b.stages[2]];
            for i in 0..3 {
                let (src, dst, p) = (chain[i], chain[i + 1], reduce[i]);
                graph
                    .pass(&format!("prt reduce pass {}", i + 1))
                    .storage_read("src", src, full, compute)
                    .storage_write("dst", dst, full, compute)
                    .record(move |ctx| {
                        ctx.rec.bind_pipeline(p)?;
                        ctx.bind(&[])?;
                        ctx.rec.dispatch([w, h, 1])
                    });
            }
            to_slots(
                graph,
                "prt reduce pass 4",
                b.stages[2],
                reduce[3],
                [w / config.tile, h / config.tile, 1],
            );
        }
        Reduction::Compute => {
            let tiles = (w / config.tile) * (h / config.tile);
            to_slots(graph, "prt reduce tiles", b.product, reduce[0], [64 * tiles, 1, 1]);
        }
    }
}

/// The document's directions: the colour-coded sphere drawn into every receiver's tile.
fn draw_sphere(
    ctx: &mut crate::graph::PassContext<'_, '_>,
    b: &Bake,
    first: u32,
    count: u32,
) -> std::result::Result<(), crate::backend::BackendError> {
    if let Some((pipeline, vertices, n)) = b.sphere {
        ctx.rec.bind_pipeline(pipeline)?;
        ctx.bind(&[("receivers", Bind::StorageBuffer(b.receivers))])?;
        ctx.rec.bind_vertex_buffers(&[(vertices, 0)])?;
        ctx.rec.draw_instanced(n, 0, count, first)?;
    }
    Ok(())
}

/// The colour-coded sphere (Listing 2.3) into R and G, with no depth test or write.
fn sphere_pipeline(gpu: &mut Gpu, shaders: &ShaderLibrary, config: &Config, w: u32, h: u32) -> Result<PipelineId> {
    let mut desc = GraphicsPipelineDesc::new("prt colour sphere", "prt/sphere.vert", Some("prt/sphere.frag"));
    desc.vertex_layout = VertexLayout {
        buffers: vec![(0, 20)],
        attributes: vec![
            VertexAttribute {
                location: 0,
                binding: 0,
                format: vk::Format::R32G32B32_SFLOAT,
                offset: 0,
            },
            VertexAttribute {
                location: 1,
                binding: 0,
                format: vk::Format::R32G32_SFLOAT,
                offset: 12,
            },
        ],
    };
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.depth = DepthState {
        test: false,
        write: false,
        compare: vk::CompareOp::ALWAYS,
    };
    desc.color_targets = vec![ColorTarget {
        write_mask: vk::ColorComponentFlags::R | vk::ColorComponentFlags::G,
        ..ColorTarget::new(vk::Format::R32G32B32A32_SFLOAT)
    }];
    desc.depth_format = Some(vk::Format::D32_SFLOAT);
    let c = |id: u32, bits: u32| SpecConstant { id, bits };
    desc.specialization = vec![
        c(0, config.mapping as u32),
        c(2, config.tile),
        c(3, config.tiles_per_row()),
        c(4, config.batch),
        c(5, w),
        c(6, h),
    ];
    Ok(gpu.create_graphics_pipeline(&desc, shaders)?)
}
