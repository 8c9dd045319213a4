//! Ridderhof 2002's BSP shadow system (digest §1.5, §4 "BSP"): per-light vertex colours with exact
//! hard shadows baked once, relit every frame by the lights' current intensities.
//!
//! - **Set-up** ([`setup`], through the bake stage): the BSP of the scene polygons with the
//!   first polygon as splitter, its fragments segmented to `max_segment_area`, and per light the
//!   full-intensity colour `C_l(v)` of every segment vertex with the painter's shadow pass from
//!   the light. Stored as a vertices × lights matrix (f32 RGB, or f16 with `storage = "f16"`),
//!   on the GPU either whole (`layout = "dense"`, light-major) or as each vertex's non-zero
//!   entries only (`layout = "sparse"`, a CSR row per vertex: a light that does not reach a
//!   vertex — outside its cone, facing away, in shadow — costs neither memory nor time).
//!   `layout = "auto"` (default) takes the sparse layout when it is under half the dense one.
//! - **Run time**: each light's scale `s_l` is its current intensity over the baked one (the
//!   ratio of their largest channels: the thesis's lights are dimmers, a scalar per light, and a
//!   light board dims every channel alike; a change of hue is not representable in a per-light
//!   scalar and is not modelled). Lights with `s_l` below `threshold` are skipped; a compute
//!   pass forms `colour(v) = Σ s_l·C_l(v)` over the active ones (a GEMV) into a vertex colour
//!   buffer, and a graphics pass draws the segments with it, Gouraud-interpolated, as the direct
//!   term. The base term is forward's: emission plus the unshadowed environment irradiance.
//!
//! `mode = "corrected"` (default) uses the physical light model (radiance, comparable with the
//! path tracer) and the projection's validity checks; `mode = "faithful"` uses the thesis's
//! `k·ρ·cos/d` model with its linear spot ramp, projects every occluder vertex as written and
//! rounds every coordinate to four decimals with planes as thick (the thesis's §5.6.1).

pub(crate) mod painter;
pub mod setup;

#[cfg(test)]
mod tests;

use bytemuck::{Pod, Zeroable};

use crate::backend::{
    vk, Bind, BufferDesc, BufferId, ComputePipelineDesc, Gpu, MemoryKind, PipelineId, SpecConstant, VertexAttribute,
    VertexLayout,
};
use crate::bake::{BakeData, BakeKey};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::lighting::many_lights::{scene_polygons, LightModel, ManyLight};
use crate::lighting::params::Params;
use crate::lighting::{
    begin_term_rendering, term_pass, term_pipeline_desc, CreateContext, FrameContext, LightingMethod, ReferenceKind,
    Term, Terms,
};
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema, Scene};
use crate::shaders::ShaderLibrary;
use crate::world::Tolerance;
use setup::Projection;

pub const NAME: &str = "bsp_lights";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "max_segment_area",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "k",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "threshold",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "storage",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "layout",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "hidden",
            kind: ParamKind::String,
        },
    ],
};

/// Bumped whenever the set-up's output for the same inputs changes.
const SETUP_VERSION: u32 = 4;

/// The matrix is bound whole as one storage buffer by the GEMV: every Vulkan device binds 2²⁷
/// bytes (`maxStorageBufferRange`'s required minimum); [`matrix_limit`] is the device's own.
pub const MAX_MATRIX_BYTES: u64 = 1 << 27;

/// The most bytes of matrix `caps`' device binds as one storage buffer, in one allocation.
pub fn matrix_limit(caps: &crate::backend::DeviceCaps) -> u64 {
    (caps.max_storage_buffer_range as u64).min(caps.max_memory_allocation_size)
}

/// Lights one GEMV invocation loops over at most: llvmpipe ends any invocation after 65,535 loop
/// iterations, and the stress scene has 4,096 lights.
pub const MAX_LIGHTS: usize = 8192;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Corrected,
    Faithful,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    F32,
    F16,
}

impl Storage {
    /// Bytes of one vertex's RGB colour for one light.
    pub fn bytes_per_entry(self) -> u64 {
        match self {
            Storage::F32 => 12,
            Storage::F16 => 6,
        }
    }
}

/// How the matrix lies on the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Every entry, light-major: the GEMV reads each active light's column.
    Dense,
    /// Per vertex, its non-zero entries (light index and colour): the GEMV reads each vertex's
    /// row, whatever the lights' scales.
    Sparse,
    /// Sparse when that takes under half the dense bytes, else dense.
    Auto,
}

impl Storage {
    /// Bytes of one non-zero entry in the sparse layout: the light's index with the colour
    /// (f16: a 16-bit index and three halves in two words; f32: four words).
    pub fn bytes_per_sparse_entry(self) -> u64 {
        match self {
            Storage::F32 => 16,
            Storage::F16 => 8,
        }
    }
}

/// Bytes of the matrix on the GPU in each layout: `(dense, sparse)` for `vertices`, `lights`
/// and `non_zero` entries (the sparse layout adds a row start per vertex and one at the end).
pub fn layout_bytes(vertices: usize, lights: usize, non_zero: usize, storage: Storage) -> (u64, u64) {
    (
        vertices as u64 * lights as u64 * storage.bytes_per_entry(),
        4 * (vertices as u64 + 1) + non_zero as u64 * storage.bytes_per_sparse_entry(),
    )
}

/// The layout `layout` resolves to for a matrix of `vertices × lights` with `non_zero` entries.
pub fn choose_layout(layout: Layout, vertices: usize, lights: usize, non_zero: usize, storage: Storage) -> Layout {
    match layout {
        Layout::Auto => {
            let (dense, sparse) = layout_bytes(vertices, lights, non_zero, storage);
            if 2 * sparse < dense {
                Layout::Sparse
            } else {
                Layout::Dense
            }
        }
        l => l,
    }
}

/// How hidden surfaces are removed when this method draws the base (`painter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hidden {
    /// The depth buffer.
    Depth,
    /// No depth test: the fragments back to front from each frame's eye by the BSP.
    Painter,
    /// No depth test: the order back to front from the first frame's eye, kept (the thesis's
    /// "predetermined order", wrong once the eye crosses a node's plane).
    Fixed,
}

/// The method's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    pub mode: Mode,
    /// Largest segment, m².
    pub max_segment_area: f64,
    /// The thesis's arbitrary attenuation constant (faithful mode).
    pub k: f64,
    /// Lights scaled below this fraction of their baked intensity are skipped.
    pub threshold: f64,
    pub storage: Storage,
    pub layout: Layout,
    pub hidden: Hidden,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            mode: Mode::Corrected,
            max_segment_area: 0.01,
            k: 1.0,
            threshold: 0.05,
            storage: Storage::F32,
            layout: Layout::Auto,
            hidden: Hidden::Depth,
        }
    }
}

impl Config {
    /// The parameters that do nothing with this configuration, and why.
    pub fn inert(&self) -> Vec<(&'static str, &'static str)> {
        match self.mode {
            Mode::Corrected => vec![(
                "k",
                "in corrected mode (the thesis's light model's k is faithful mode's)",
            )],
            Mode::Faithful => Vec::new(),
        }
    }

    pub fn from_decl(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let mut c = Config::default();
        if let Some(mode) =
            params.get_choice("mode", &[("corrected", Mode::Corrected), ("faithful", Mode::Faithful)])?
        {
            c.mode = mode;
        }
        if let Some(storage) = params.get_choice("storage", &[("f32", Storage::F32), ("f16", Storage::F16)])? {
            c.storage = storage;
        }
        if let Some(layout) = params.get_choice(
            "layout",
            &[
                ("auto", Layout::Auto),
                ("dense", Layout::Dense),
                ("sparse", Layout::Sparse),
            ],
        )? {
            c.layout = layout;
        }
        if let Some(hidden) = params.get_choice(
            "hidden",
            &[
                ("depth", Hidden::Depth),
                ("painter", Hidden::Painter),
                ("fixed", Hidden::Fixed),
            ],
        )? {
            c.hidden = hidden;
        }
        if let Some(v) = decl.param("max_segment_area") {
            c.max_segment_area = Params::float(v)
                .filter(|x| x.is_finite() && *x > 0.0)
                .ok_or_else(|| params.error("max_segment_area", "an area in m² above 0", v))?;
        }
        if let Some(v) = decl.param("k") {
            c.k = Params::float(v)
                .filter(|x| x.is_finite() && *x > 0.0)
                .ok_or_else(|| params.error("k", "a positive number", v))?;
        }
        if let Some(v) = decl.param("threshold") {
            c.threshold = Params::float(v)
                .filter(|x| (0.0..1.0).contains(x))
                .ok_or_else(|| params.error("threshold", "a fraction in [0, 1)", v))?;
        }
        Ok(c)
    }

    pub fn model(&self) -> LightModel {
        match self.mode {
            Mode::Corrected => LightModel::Physical,
            Mode::Faithful => LightModel::Seed { k: self.k },
        }
    }

    /// Corrected mode lights both sides of a surface, as every other method and the path
    /// tracer do; faithful lights the front only, as the thesis does.
    pub fn two_sided(&self) -> bool {
        self.mode == Mode::Corrected
    }

    pub fn projection(&self) -> Projection {
        match self.mode {
            Mode::Corrected => Projection::Valid,
            Mode::Faithful => Projection::Thesis,
        }
    }

    /// Faithful mode rounds every coordinate to four decimals as the thesis does (§5.6.1).
    pub fn tolerance(&self) -> Tolerance {
        match self.mode {
            Mode::Corrected => Tolerance::MESH,
            Mode::Faithful => Tolerance::THESIS,
        }
    }
}

/// The chart's sweep: as declared; the segment area at 4×, 1× and ¼ of the declared one, the
/// last in f16 (four times the vertices in twice the bytes each would be 8× the declared
/// matrix, and one point over the memory limit stops the whole chart); the faithful mode.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d, None) {
            let storage = if c.storage == Storage::F16 { " f16" } else { "" };
            let label = format!("bsp_lights {:?} area={}{storage}", c.mode, c.max_segment_area).to_lowercase();
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    let declared = Config::from_decl(decl, None)
        .map(|c| c.max_segment_area)
        .unwrap_or(Config::default().max_segment_area);
    for a in [4.0 * declared, declared] {
        push(decl.with("max_segment_area", a.into()));
    }
    push(
        decl.with("max_segment_area", (0.25 * declared).into())
            .with("storage", "f16".into()),
    );
    push(decl.with("mode", "faithful".into()));
    out
}

pub fn reference(_decl: &MethodDecl) -> ReferenceKind {
    ReferenceKind::Direct
}

/// A segment vertex as `glsl/bsp_lights/segments.vert` reads it (world space). Rows past the
/// drawn vertices are back sides, read only through `back`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SegmentVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub albedo: [f32; 3],
    pub emission: [f32; 3],
    /// The row of this vertex's back side in the colour buffer, or `NO_BACK`.
    pub back: u32,
}

/// `SegmentVertex::back` of a vertex whose back side receives no direct light.
pub const NO_BACK: u32 = u32::MAX;

/// The baked set-up as the run time needs it (and the cache stores it).
#[derive(Clone, Debug, PartialEq)]
pub struct Baked {
    pub vertices: Vec<SegmentVertex>,
    pub indices: Vec<u32>,
    pub lights: usize,
    /// `C_l(v)` light-major, RGB: `3·(l·V + v) + channel`.
    pub colours: Vec<f32>,
    pub polygons: usize,
    pub fragments: usize,
    /// The BSP and each fragment's triangles, for drawing without a depth test.
    pub painter: painter::PainterTree,
}

impl Baked {
    /// Bytes of one light's column in `storage`.
    pub fn bytes_per_light(&self, storage: Storage) -> u64 {
        self.vertices.len() as u64 * storage.bytes_per_entry()
    }
}

const BAKED_MAGIC: u32 = 0x4253_504c;

impl BakeData for Baked {
    fn encode(&self) -> Vec<u8> {
        // The set-up's timings are not stored: the same inputs always give the same bytes, and a
        // cache hit has no timings of its own to report as new.
        let mut out = Vec::new();
        for w in [
            BAKED_MAGIC,
            self.vertices.len() as u32,
            self.indices.len() as u32,
            self.lights as u32,
            self.polygons as u32,
            self.fragments as u32,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(bytemuck::cast_slice(&self.vertices));
        out.extend_from_slice(bytemuck::cast_slice(&self.indices));
        out.extend_from_slice(bytemuck::cast_slice(&self.colours));
        out.extend_from_slice(&self.painter.encode());
        out
    }

    fn decode(bytes: &[u8]) -> Option<Self> {
        let word = |i: usize| Some(u32::from_le_bytes(bytes.get(4 * i..4 * i + 4)?.try_into().ok()?) as usize);
        if word(0)? != BAKED_MAGIC as usize {
            return None;
        }
        let (v, i, l) = (word(1)?, word(2)?, word(3)?);
        let head = 24;
        let vertex_bytes = v * std::mem::size_of::<SegmentVertex>();
        let (vb, ib, cb) = (
            head..head + vertex_bytes,
            head + vertex_bytes..head + vertex_bytes + 4 * i,
            head + vertex_bytes + 4 * i..head + vertex_bytes + 4 * i + 12 * v * l,
        );
        let (painter, painter_bytes) = painter::PainterTree::decode(bytes.get(cb.end..)?, (i / 3) as u32)?;
        if bytes.len() != cb.end + painter_bytes {
            return None;
        }
        Some(Baked {
            vertices: bytemuck::pod_collect_to_vec(&bytes[vb]),
            indices: bytemuck::pod_collect_to_vec(&bytes[ib]),
            lights: l,
            colours: bytemuck::pod_collect_to_vec(&bytes[cb]),
            polygons: word(4)?,
            fragments: word(5)?,
            painter,
        })
    }
}

/// `max_segment_area` when unset: the scene's area over the segment budget, or larger where
/// the light matrix (a row per segment vertex, about one per segment) would otherwise pass
/// [`MAX_MATRIX_BYTES`]. The matrix is refused against that limit by the set-up itself.
pub fn plan(
    decl: &MethodDecl,
    facts: &crate::lighting::plan::Facts<'_>,
) -> Result<Vec<crate::lighting::plan::Derived>> {
    use crate::lighting::plan::{round2, Derived, SEGMENT_BUDGET};
    let config = Config::from_decl(decl, Some(facts.scene))?;
    let area = facts.area(NAME)?;
    if decl.param("max_segment_area").is_some() || area <= 0.0 {
        return Ok(Vec::new());
    }
    let lights = facts.scene.lights.len().max(1) as u64;
    let triangles = facts.triangles(NAME)?.len() as f64;
    // Rows the matrix holds, less each triangle's corners. A fragment is split in four until no
    // piece passes the area, so pieces are a quarter of it at the least: up to 4 · area / a
    // vertex rows (the 1,024-light stage at 0.033 m² made 19,478 against 10,712 at one a piece).
    let capacity = MAX_MATRIX_BYTES / (lights * config.storage.bytes_per_entry());
    let rows = capacity as f64 - 3.0 * triangles;
    if rows < 4.0 {
        // The triangles' own corners fill the matrix: no segment area fits.
        return Err(Error::Usage(format!(
            "{}: {NAME}: the scene's {triangles} triangles have {} corners, and an {} light matrix of {lights} lights holds {capacity} vertex rows in {} (the device's storage-buffer limit), whatever max_segment_area is: use storage = \"f16\", fewer lights or fewer triangles",
            facts.scene.source,
            3.0 * triangles,
            if config.storage == Storage::F16 { "f16" } else { "f32" },
            crate::lighting::plan::bytes(MAX_MATRIX_BYTES)
        )));
    }
    let budget = SEGMENT_BUDGET.min((rows / 4.0).max(1.0));
    let chosen = round2(area / budget);
    let why = if budget < SEGMENT_BUDGET {
        format!(
            "the scene's {} m² over a quarter of the {rows:.0} vertex rows a {} matrix of {lights} lights holds in {MAX_MATRIX_BYTES} bytes",
            crate::lighting::plan::area_text(area),
            if config.storage == Storage::F16 { "f16" } else { "f32" }
        )
    } else {
        format!(
            "the scene's {} m² over a budget of {SEGMENT_BUDGET} segments",
            crate::lighting::plan::area_text(area)
        )
    };
    Ok(vec![Derived::new("max_segment_area", chosen, why)])
}

/// The full set-up of `scene`'s polygons and lights on the CPU, as the bake runs it, refused
/// when its matrix would take more than `max_matrix_bytes`.
pub fn bake_scene(
    scene: &Scene,
    geometry: &crate::lighting::lightmap::geometry::StaticGeometry,
    config: &Config,
    max_matrix_bytes: u64,
    progress: &mut crate::util::progress::Progress,
) -> Result<(setup::Setup, Vec<crate::lighting::many_lights::ScenePolygon>)> {
    let lights = ManyLight::from_scene(scene, NAME)?;
    let polygons = scene_polygons(&scene.source, geometry, NAME, &config.tolerance())?;
    let settings = setup::Settings {
        model: config.model(),
        projection: config.projection(),
        tolerance: config.tolerance(),
        max_segment_area: config.max_segment_area,
        two_sided: config.two_sided(),
        threads: 0,
        cull_by_cones: true,
        max_matrix_bytes,
        bytes_per_entry: config.storage.bytes_per_entry(),
    };
    let s = setup::run(&polygons, &lights, &settings, progress);
    // A cancelled set-up stopped its threads early: that, not a failed thread, is what happened.
    crate::bake::check_cancelled(progress, "bsp light set-up")?;
    Ok((s.map_err(|m| field_error(scene, "max_segment_area", m))?, polygons))
}
/// The set-up (segments, their colours, the light matrix), baked or read from the cache, checked
/// against the scene and the device's limit.
fn bake_setup(cx: &mut CreateContext<'_>, config: &Config, lights: &[ManyLight], limit: u64) -> Result<Baked> {
    let scene = cx.scene;
    let geometry = crate::lighting::lightmap::geometry::static_geometry(scene, cx.scene_gpu, NAME)?;
    let polygons = scene_polygons(&scene.source, &geometry, NAME, &config.tolerance())?;
    if polygons.is_empty() {
        return Err(Error::Usage(format!(
            "{}: {NAME}: the scene has no static polygons to light",
            scene.source
        )));
    }
    let geometry_floats: Vec<f64> = polygons
        .iter()
        .flat_map(|p| {
            p.polygon
                .vertices
                .iter()
                .flat_map(|v| v.to_array())
                .chain(p.albedo.to_array())
                .chain(p.emission.to_array())
        })
        .collect();
    let key = BakeKey::new("bsp_lights set-up")
        .with("version", SETUP_VERSION)
        .with("model", config.model())
        .with("projection", config.projection())
        .with("tolerance", config.tolerance())
        .with("two_sided", config.two_sided())
        .with("max_segment_area", config.max_segment_area)
        .with("lights", lights)
        .with_bytes("geometry", bytemuck::cast_slice(&geometry_floats));
    let name = format!(
        "{NAME} set-up {:?} area={} lights={}",
        config.mode,
        config.max_segment_area,
        lights.len()
    )
    .to_lowercase();
    let geo = &geometry;
    let baked: Baked = cx.bakes.bake(&name, &key, |progress| {
        let (s, polygons) = bake_scene(scene, geo, config, limit, progress)?;
        let p = s.phases;
        let per_light = s.vertices() as u64 * config.storage.bytes_per_entry();
        crate::errln!(
            "{NAME} set-up: {} polygons -> {} BSP fragments -> {} vertices; {} lights at {per_light} bytes each ({:.2} MiB); BSP {:.1} ms, segmentation {:.1} ms, colouring {:.1} ms CPU, shadows {:.1} ms CPU ({:.1} ms wall for the lights)",
            polygons.len(),
            s.tree.fragments.len(),
            s.vertices(),
            s.lights,
            (per_light * s.lights as u64) as f64 / (1u64 << 20) as f64,
            p.bsp_ms,
            p.segment_ms,
            p.colour_cpu_ms,
            p.shadow_cpu_ms,
            p.lights_wall_ms
        );
        Ok(Baked::from_setup(&s, &polygons))
    })?;
    // A cached bake may have been made for the other storage: check the limit again.
    setup::check_matrix(
        baked.vertices.len(),
        baked.lights,
        config.storage.bytes_per_entry(),
        limit,
    )
    .map_err(|m| field_error(scene, "max_segment_area", m))?;
    if baked.lights != lights.len()
        || baked.colours.len() != 3 * baked.vertices.len() * baked.lights
        || baked.vertices.is_empty()
    {
        return Err(Error::Internal(format!(
            "{}: {NAME}: the baked set-up does not match the scene",
            scene.source
        )));
    }
    Ok(baked)
}

/// The segments' mesh, the light matrix in its layout and the vertex colours on the device.
struct MatrixBuffers {
    layout: Layout,
    vertices: BufferId,
    indices: BufferId,
    matrix: BufferId,
    rows: Option<BufferId>,
    colours: BufferId,
}

impl MatrixBuffers {
    fn upload(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        scene: &Scene,
        config: &Config,
        baked: &Baked,
        limit: u64,
    ) -> Result<MatrixBuffers> {
        let vertices = gpu.create_buffer_init(
            &format!("{NAME} vertices"),
            vk::BufferUsageFlags::VERTEX_BUFFER,
            bytemuck::cast_slice(&baked.vertices),
        )?;
        let indices = gpu.create_buffer_init(
            &format!("{NAME} indices"),
            vk::BufferUsageFlags::INDEX_BUFFER,
            bytemuck::cast_slice(&baked.indices),
        )?;
        let non_zero = baked.colours.chunks(3).filter(|c| c.iter().any(|&x| x != 0.0)).count();
        let layout = choose_layout(
            config.layout,
            baked.vertices.len(),
            baked.lights,
            non_zero,
            config.storage,
        );
        let (matrix_words, rows) = match layout {
            Layout::Sparse => {
                let (rows, words) = sparse_words(baked, config.storage);
                let (_, bytes) = layout_bytes(baked.vertices.len(), baked.lights, non_zero, config.storage);
                if bytes > limit {
                    return Err(field_error(scene, "layout", format!("the sparse matrix takes {bytes} bytes, over the {limit} this device binds as one storage buffer")));
                }
                (
                    words,
                    Some(gpu.create_storage_buffer(&format!("{NAME} matrix rows"), bytemuck::cast_slice(&rows))?),
                )
            }
            _ => (dense_words(baked, config.storage), None),
        };
        crate::errln!(
            "{NAME}: {} of {} matrix entries non-zero ({:.1} %); {} layout, {:.2} MiB on the GPU",
            non_zero,
            baked.vertices.len() * baked.lights,
            100.0 * non_zero as f64 / (baked.vertices.len() * baked.lights).max(1) as f64,
            if layout == Layout::Sparse { "sparse" } else { "dense" },
            (4 * matrix_words.len() + rows.map_or(0, |_| 4 * (baked.vertices.len() + 1))) as f64 / (1u64 << 20) as f64
        );
        let matrix = gpu.create_storage_buffer(&format!("{NAME} matrix"), bytemuck::cast_slice(&matrix_words))?;
        let colours = gpu.create_buffer(&BufferDesc {
            name: format!("{NAME} vertex colours"),
            size: 16 * baked.vertices.len() as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_SRC
                | vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuOnly,
        })?;
        for b in [vertices, indices, matrix, colours].into_iter().chain(rows) {
            states.forget_buffer(b);
        }
        Ok(MatrixBuffers {
            layout,
            vertices,
            indices,
            matrix,
            rows,
            colours,
        })
    }
}

/// The GEMV that relights the vertices and the pipelines that draw the segments.
struct SegmentPipelines {
    gemv: PipelineId,
    both: PipelineId,
    base: PipelineId,
    direct: PipelineId,
    painter: Option<(PipelineId, PipelineId)>,
}

impl SegmentPipelines {
    fn new(gpu: &mut Gpu, shaders: &ShaderLibrary, config: &Config, layout: Layout) -> Result<SegmentPipelines> {
        let half = SpecConstant {
            id: 0,
            bits: u32::from(config.storage == Storage::F16),
        };
        let shader = if layout == Layout::Sparse {
            "bsp_lights/gemv_sparse.comp"
        } else {
            "bsp_lights/gemv.comp"
        };
        let gemv = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: format!("{NAME} gemv"),
                shader: shader.into(),
                specialization: vec![half],
            },
            shaders,
        )?;
        let ds_format = gpu.caps().depth_stencil_format;
        let mut pipeline = |terms: Terms, painter: bool| {
            let vert = if terms.has(Term::Direct) {
                "bsp_lights/segments.vert"
            } else {
                "bsp_lights/segments_base.vert"
            };
            let name = if painter {
                format!("{NAME} {terms} painter")
            } else {
                format!("{NAME} {terms}")
            };
            let mut desc = term_pipeline_desc(&name, vert, "bsp_lights/segments.frag", terms, ds_format);
            if painter {
                // The draw order decides what is seen; the depth is still written for the
                // passes after this one (a disabled test would write nothing).
                desc.depth = crate::backend::DepthState {
                    test: true,
                    write: true,
                    compare: vk::CompareOp::ALWAYS,
                };
            }
            let attr = |location: u32| VertexAttribute {
                location,
                binding: 0,
                format: if location < 4 {
                    vk::Format::R32G32B32_SFLOAT
                } else {
                    vk::Format::R32_UINT
                },
                offset: 12 * location,
            };
            desc.vertex_layout = VertexLayout {
                buffers: vec![(0, std::mem::size_of::<SegmentVertex>() as u32)],
                attributes: (0..5).map(attr).collect(),
            };
            if !terms.has(Term::Base) {
                // Over another method's base: the segments' interior vertices are not the
                // base's, so their depths differ by rounding; a small bias toward the eye keeps
                // the base's depth deciding what is seen without the surfaces fighting.
                desc.raster.depth_bias = Some((-16.0, -1.0));
            }
            gpu.create_graphics_pipeline(&desc, shaders)
        };
        let (both, base, direct) = (
            pipeline(Terms::BASE_DIRECT, false)?,
            pipeline(Terms::BASE, false)?,
            pipeline(Terms::DIRECT, false)?,
        );
        let painter = if config.hidden == Hidden::Depth {
            None
        } else {
            Some((pipeline(Terms::BASE_DIRECT, true)?, pipeline(Terms::BASE, true)?))
        };
        Ok(SegmentPipelines {
            gemv,
            both,
            base,
            direct,
            painter,
        })
    }
}

/// One line naming the scene file and the method's field.
fn field_error(scene: &Scene, field: &str, message: String) -> Error {
    match scene.methods.iter().find(|d| d.name == NAME) {
        Some(decl) => scene.method_param_error(decl, field, message).into(),
        None => Error::Usage(format!("{}: {NAME}.{field}: {message}", scene.source)),
    }
}

impl Baked {
    pub fn from_setup(s: &setup::Setup, polygons: &[crate::lighting::many_lights::ScenePolygon]) -> Baked {
        let seg = &s.segments;
        let vertices = (0..seg.positions.len())
            .map(|v| {
                let p = &polygons[s.fragment_source[seg.vertex_polygon[v] as usize] as usize];
                SegmentVertex {
                    position: seg.positions[v].as_vec3().to_array(),
                    normal: seg.normals[v].as_vec3().to_array(),
                    albedo: p.albedo.as_vec3().to_array(),
                    emission: p.emission.as_vec3().to_array(),
                    back: s.back_row.get(v).copied().unwrap_or(NO_BACK),
                }
            })
            .collect();
        Baked {
            vertices,
            indices: seg.triangles.iter().flatten().copied().collect(),
            lights: s.lights,
            colours: s.colours.iter().flatten().copied().collect(),
            polygons: polygons.len(),
            fragments: s.tree.fragments.len(),
            painter: painter::PainterTree::new(&s.tree, &s.segments.triangle_polygon),
        }
    }
}

/// Matches `Active` in glsl/bsp_lights/gemv.comp: the count and vertex count, then (light,
/// scale bits) pairs.
fn active_words(active: &[(u32, f32)], vertices: usize) -> Vec<u32> {
    let mut words = vec![active.len() as u32, vertices as u32, 0, 0];
    for &(l, s) in active {
        words.extend([l, s.to_bits()]);
    }
    words
}

/// Matches `Scales` in glsl/bsp_lights/gemv_sparse.comp: the light count and vertex count,
/// then every light's scale (0 where it is below `threshold`).
fn scale_words(scales: &[f32], threshold: f32, vertices: usize) -> Vec<u32> {
    let mut words = vec![scales.len() as u32, vertices as u32, 0, 0];
    words.extend(
        scales
            .iter()
            .map(|&s| if s >= threshold && s > 0.0 { s.to_bits() } else { 0 }),
    );
    words
}

fn half_bits(x: f32) -> u32 {
    u32::from(half::f16::from_f32(x).to_bits())
}

/// The dense layout (light-major, as `Baked::colours`) as `glsl/bsp_lights/gemv.comp` reads it.
fn dense_words(baked: &Baked, storage: Storage) -> Vec<u32> {
    match storage {
        Storage::F32 => baked.colours.iter().map(|c| c.to_bits()).collect(),
        Storage::F16 => baked
            .colours
            .chunks(2)
            .map(|p| half_bits(p[0]) | half_bits(p.get(1).copied().unwrap_or(0.0)) << 16)
            .collect(),
    }
}

/// The sparse layout as `glsl/bsp_lights/gemv_sparse.comp` reads it: per vertex, its non-zero
/// entries in light order (row starts in entries, then the entries' words).
pub fn sparse_words(baked: &Baked, storage: Storage) -> (Vec<u32>, Vec<u32>) {
    let n = baked.vertices.len();
    let mut rows = Vec::with_capacity(n + 1);
    let mut words = Vec::new();
    let mut entries = 0u32;
    for v in 0..n {
        rows.push(entries);
        for l in 0..baked.lights {
            let c = &baked.colours[3 * (l * n + v)..3 * (l * n + v) + 3];
            if c.iter().all(|&x| x == 0.0) {
                continue;
            }
            entries += 1;
            match storage {
                Storage::F32 => words.extend([l as u32, c[0].to_bits(), c[1].to_bits(), c[2].to_bits()]),
                Storage::F16 => words.extend([
                    l as u32 | half_bits(c[0]) << 16,
                    half_bits(c[1]) | half_bits(c[2]) << 16,
                ]),
            }
        }
    }
    rows.push(entries);
    (rows, words)
}

pub struct BspLights {
    pub config: Config,
    pub baked: Baked,
    /// Largest channel of each light's baked intensity.
    full: Vec<f32>,
    vertices: BufferId,
    indices: BufferId,
    matrix: BufferId,
    colours: BufferId,
    gemv: PipelineId,
    both: PipelineId,
    base: PipelineId,
    direct: PipelineId,
    /// With `hidden` other than `depth`: the base pipelines (with and without the direct term)
    /// that draw in painter's order, depth always written and never tested.
    painter_pipelines: Option<(PipelineId, PipelineId)>,
    /// This frame's painter's order as index ranges (empty with `hidden = "depth"`).
    draws: Vec<(u32, u32)>,
    /// The layout the matrix took (`config.layout` resolved).
    pub layout: Layout,
    /// The sparse layout's row starts (one per vertex and one at the end).
    rows: Option<BufferId>,
    /// This frame's active lights (index, scale), as `active_words` lays them out (the dense
    /// GEMV's input).
    active: Vec<u32>,
    /// This frame's scale of every light, 0 below the threshold, as `scale_words` lays them out
    /// (the sparse GEMV's input).
    scales: Vec<u32>,
}

impl BspLights {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<BspLights> {
        let scene = cx.scene;
        let config = Config::from_decl(decl, Some(scene))?;
        for w in Params::new(decl, Some(scene)).inert_warnings(&config.inert()) {
            crate::errln!("{w}");
        }
        let lights = ManyLight::from_scene(scene, NAME)?;
        if lights.len() > MAX_LIGHTS {
            return Err(Error::Usage(format!(
                "{}: lights: {} lights, over the {MAX_LIGHTS} {NAME} relights in one pass",
                scene.source,
                lights.len()
            )));
        }
        let limit = matrix_limit(cx.gpu.caps());
        let baked = bake_setup(cx, &config, &lights, limit)?;
        let full = lights.iter().map(|l| l.intensity.max_element() as f32).collect();
        let buffers = MatrixBuffers::upload(cx.gpu, cx.states, scene, &config, &baked, limit)?;
        let pipelines = SegmentPipelines::new(cx.gpu, cx.shaders, &config, buffers.layout)?;
        let all: Vec<(u32, f32)> = (0..baked.lights as u32).map(|l| (l, 1.0)).collect();
        let active = active_words(&all, baked.vertices.len());
        let scales = scale_words(&vec![1.0; baked.lights], 0.0, baked.vertices.len());
        Ok(BspLights {
            config,
            layout: buffers.layout,
            baked,
            full,
            vertices: buffers.vertices,
            indices: buffers.indices,
            matrix: buffers.matrix,
            rows: buffers.rows,
            colours: buffers.colours,
            gemv: pipelines.gemv,
            both: pipelines.both,
            base: pipelines.base,
            direct: pipelines.direct,
            painter_pipelines: pipelines.painter,
            draws: Vec::new(),
            active,
            scales,
        })
    }

    /// Sets each light's scale from its current intensity (RGB, as the frame's lights carry
    /// it): `s_l` = largest current channel / largest baked channel; lights below the threshold
    /// are left out of the GEMV.
    pub fn set_intensities(&mut self, current: &[[f32; 3]]) {
        let scales: Vec<f32> = self
            .full
            .iter()
            .enumerate()
            .map(|(l, &full)| {
                current.get(l).map_or(0.0, |c| {
                    if full > 0.0 {
                        c[0].max(c[1]).max(c[2]) / full
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        self.set_scales(&scales);
    }

    /// Sets the lights' scales `s_l` directly (lights below the threshold skipped).
    pub fn set_scales(&mut self, scales: &[f32]) {
        let threshold = self.config.threshold as f32;
        let active: Vec<(u32, f32)> = scales
            .iter()
            .enumerate()
            .filter(|(_, &s)| s >= threshold && s > 0.0)
            .map(|(l, &s)| (l as u32, s))
            .collect();
        self.active = active_words(&active, self.baked.vertices.len());
        let mut all = vec![0.0; self.baked.lights];
        for &(l, s) in &active {
            all[l as usize] = s;
        }
        self.scales = scale_words(&all, 0.0, self.baked.vertices.len());
    }

    /// Sets the painter's order for an eye at `eye` (`hidden = "painter"`: every frame;
    /// `"fixed"`: the first frame only).
    pub fn set_eye(&mut self, eye: glam::DVec3) {
        let take = match self.config.hidden {
            Hidden::Depth => false,
            Hidden::Painter => true,
            Hidden::Fixed => self.draws.is_empty(),
        };
        if take {
            let order = self.baked.painter.back_to_front(eye);
            self.draws = self.baked.painter.draws(&order);
        }
    }

    /// This frame's draws as `(first index, index count)`, back to front (empty with
    /// `hidden = "depth"`).
    pub fn painter_draws(&self) -> &[(u32, u32)] {
        &self.draws
    }

    /// Lights in this frame's GEMV.
    pub fn active_lights(&self) -> usize {
        self.active[0] as usize
    }

    /// The per-vertex colour buffer the GEMV writes (`vec4` per segment vertex).
    pub fn colour_buffer(&self) -> BufferId {
        self.colours
    }

    /// The GEMV pass: `colour(v) = Σ_active s_l·C_l(v)`, one invocation per vertex.
    pub fn add_gemv<'a>(&'a self, graph: &mut RenderGraph<'a>) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let n = self.baked.vertices.len() as u32;
        let mut pass = graph
            .pass(&format!("{NAME} gemv"))
            .buffer(self.matrix, Access::StorageRead { stages: compute }, Some("matrix"))
            .buffer(self.colours, Access::StorageWrite { stages: compute }, Some("colours"));
        let input: &[u32] = match self.rows {
            Some(rows) => {
                pass = pass.buffer(rows, Access::StorageRead { stages: compute }, Some("rows"));
                &self.scales
            }
            None => &self.active,
        };
        pass.record(move |ctx| {
            ctx.rec.bind_pipeline(self.gemv)?;
            ctx.bind(&[("enabled", Bind::StorageData(bytemuck::cast_slice(input)))])?;
            ctx.rec.dispatch([n, 1, 1])
        });
    }

    /// Reads the vertex colour buffer back (after the frames that wrote it finished).
    pub fn read_colours(&self, gpu: &mut crate::backend::Gpu) -> Result<Vec<[f32; 4]>> {
        let bytes = crate::graph::read_back_buffer(gpu, self.colours, NAME)?;
        let size = 16 * self.baked.vertices.len();
        let colours = bytes.get(..size).ok_or_else(|| {
            Error::Internal(format!(
                "{NAME}: the vertex colours read back {} bytes of {size}",
                bytes.len()
            ))
        })?;
        Ok(bytemuck::pod_collect_to_vec(colours))
    }
}

impl LightingMethod for BspLights {
    fn name(&self) -> &'static str {
        NAME
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        let current: Vec<[f32; 3]> = frame
            .scene
            .lights
            .iter()
            .map(|l| [l.intensity[0], l.intensity[1], l.intensity[2]])
            .collect();
        self.set_intensities(&current);
        let eye = frame.uniforms.camera_pos;
        self.set_eye(glam::DVec3::new(eye[0] as f64, eye[1] as f64, eye[2] as f64));
        Ok(())
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        let (base, direct) = (frame.terms.has(Term::Base), frame.terms.has(Term::Direct));
        // Over another method's base its depth decides what is seen: the painter's order
        // applies only where this method draws the base.
        let painter = self.painter_pipelines.filter(|_| base);
        let pipeline = match (base, direct, painter) {
            (true, true, Some((both, _))) => both,
            (true, false, Some((_, base))) => base,
            (true, true, None) => self.both,
            (true, false, None) => self.base,
            (false, true, _) => self.direct,
            (false, false, _) => return Ok(()),
        };
        let draws: &[(u32, u32)] = if painter.is_some() { &self.draws } else { &[] };
        if direct {
            self.add_gemv(graph);
        }
        let t = frame.targets;
        let uniforms = frame.uniforms;
        let count = self.baked.indices.len() as u32;
        let mut pass = term_pass(graph, &format!("{NAME} segments"), t, base);
        pass = pass
            .buffer(self.vertices, Access::VertexRead, None)
            .buffer(self.indices, Access::IndexRead, None);
        if direct {
            pass = pass.buffer(
                self.colours,
                Access::StorageRead {
                    stages: vk::PipelineStageFlags2::VERTEX_SHADER,
                },
                Some("colours"),
            );
        }
        pass.record(move |ctx| {
            let _ = begin_term_rendering(ctx.rec, t, base)?;
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms)))])?;
            ctx.rec.bind_vertex_buffers(&[(self.vertices, 0)])?;
            ctx.rec.bind_index_buffer(self.indices, 0)?;
            if painter.is_some() {
                for &(first, n) in draws {
                    ctx.rec.draw_indexed(n, first, 0)?;
                }
            } else {
                ctx.rec.draw_indexed(count, 0, 0)?;
            }
            ctx.rec.end_rendering();
            Ok(())
        });
        Ok(())
    }
}
