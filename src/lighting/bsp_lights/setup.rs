//! The BSP shadow system's set-up (Ridderhof 2002 §1.5), pure CPU: the BSP of the scene polygons with
//! the first polygon as splitter, the fragments segmented after the build (the thesis's order),
//! and per light the full-intensity vertex colours `C_l(v)` with the painter's shadow pass from
//! the light: polygons back to front, each projected centrally from the light onto the plane of
//! every polygon before it, the target's segment vertices inside the projection zeroed.
//!
//! The result is a vertices × lights matrix, light-major (one column of `V` RGB values per
//! light): the modern form of the thesis's per-light tree clones, which shared positions and
//! topology and copied only the colours ("fast clone", §5.5).

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::DVec3;

use crate::lighting::many_lights::geometry::point_in_convex_polygon;
use crate::lighting::many_lights::{LightModel, ManyLight, ScenePolygon, Segments};
use crate::util::progress::Progress;
use crate::world::bsp::{Fragment, Tree};
use crate::world::polygon::clip_points_front;
use crate::world::{Plane, Polygon, Side, SplitHeuristic, Tolerance};

/// Which projection the shadow pass uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// The digest's validity checks (§3.3 item 1): the occluder clipped to the slab between the
    /// target's plane and the plane through the light parallel to it, so only points with
    /// `t ≥ 1` (between the light and the target) cast, and nothing is projected through the
    /// light (no inverted shadow).
    Valid,
    /// The thesis as written: every vertex projected, whatever side of the light it is on.
    Thesis,
}

/// How far short of the plane through the light (parallel to the target) the valid projection
/// stops, as a fraction of the light's height over the target: points closer to that plane
/// would project beyond `1e6` times the light's height, i.e. to infinity for any scene.
const PARALLEL_SLACK: f64 = 1e-6;

/// A projected polygon smaller than this (m²) shadows nothing: it is an occluder touching the
/// target along an edge or a point, whose clipped part has no area (the thesis's "zero-width
/// slivers").
const MIN_SHADOW_AREA: f64 = 1e-12;

/// Wall and CPU times of the set-up's phases, milliseconds. Colouring and shadowing run per
/// light on every core: their CPU time is summed over threads, and `lights_wall_ms` is the wall
/// time of both together.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Phases {
    pub bsp_ms: f64,
    pub segment_ms: f64,
    pub colour_cpu_ms: f64,
    pub shadow_cpu_ms: f64,
    pub lights_wall_ms: f64,
}

/// The set-up's inputs besides the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub model: LightModel,
    pub projection: Projection,
    pub max_segment_area: f64,
    /// The numeric policy: f64 with thin planes (corrected), or the thesis's rounding of every
    /// coordinate to 1e-4 — the input polygons, the BSP's cuts, the segment vertices and the
    /// projected shadows — with planes as thick (faithful).
    pub tolerance: Tolerance,
    /// Light both sides of a surface (penumbra's thin-surface convention): a fragment with a
    /// light behind its plane gets a second row per vertex, its back, with the normal turned.
    /// The thesis lights the front only (one colour per vertex).
    pub two_sided: bool,
    /// Threads for the per-light phase (0: every core).
    pub threads: usize,
    /// Skip the shadow pass's occluder-target pairs whose cones from the light are apart (with
    /// the valid projection only); false projects every pair, the check that the skip changes
    /// nothing.
    pub cull_by_cones: bool,
    /// Bytes the matrix may take at `bytes_per_entry` per vertex and light: checked after the
    /// segmentation, before any light is shaded.
    pub max_matrix_bytes: u64,
    pub bytes_per_entry: u64,
}

/// The set-up's result.
pub struct Setup {
    pub tree: Tree,
    /// Segments of the tree's fragments (`vertex_polygon` and `triangle_polygon` index
    /// `tree.fragments`).
    pub segments: Segments,
    /// Per fragment: the scene polygon it was cut from.
    pub fragment_source: Vec<u32>,
    /// Per fragment: its segment vertices (contiguous: `Segments` adds a polygon's vertices
    /// together).
    pub fragment_vertices: Vec<Range<u32>>,
    /// Rows of the matrix that are drawn vertices: `0..front_vertices`. The rows after them
    /// are back sides (`segments` holds them with the normal turned and no triangles).
    pub front_vertices: usize,
    /// Per front vertex: the row of its back side, or `u32::MAX` (no light is behind its
    /// fragment, or one-sided).
    pub back_row: Vec<u32>,
    /// Per fragment: its back-side rows (empty when it has none).
    pub fragment_back_vertices: Vec<Range<u32>>,
    pub lights: usize,
    /// `C_l(v)` light-major: entry `l · V + v`.
    pub colours: Vec<[f32; 3]>,
    pub phases: Phases,
}

impl Setup {
    pub fn vertices(&self) -> usize {
        self.segments.positions.len()
    }

    pub fn colour(&self, light: usize, vertex: usize) -> [f32; 3] {
        self.colours[light * self.vertices() + vertex]
    }
}

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// The BSP tree over the scene polygons, first polygon as splitter (§1.5, "no heuristic").
pub fn build_tree(polygons: &[ScenePolygon]) -> Tree {
    build_tree_in(polygons, &Tolerance::EXACT)
}

/// [`build_tree`] under `tolerance`: the input vertices rounded to its grid first (each
/// polygon keeps its plane), then its side tests and rounded cuts.
pub fn build_tree_in(polygons: &[ScenePolygon], tolerance: &Tolerance) -> Tree {
    let fragments = polygons
        .iter()
        .enumerate()
        .map(|(i, p)| Fragment {
            polygon: Polygon {
                vertices: p.polygon.vertices.iter().map(|&v| tolerance.round(v)).collect(),
                plane: p.polygon.plane,
            },
            source: i,
        })
        .collect();
    Tree::build_in(fragments, SplitHeuristic::FirstFace, tolerance)
}

/// One thread's columns (light, `C_l`) and its colouring and shadow CPU times.
type ThreadResult = (Vec<(usize, Vec<[f32; 3]>)>, f64, f64);

/// Runs the whole set-up. Errors are one sentence (the caller names the file and field).
pub fn run(
    polygons: &[ScenePolygon],
    lights: &[ManyLight],
    settings: &Settings,
    progress: &mut Progress,
) -> Result<Setup, String> {
    // Refused before any work when even the fewest vertices the segmentation can make are over.
    check_matrix(
        min_vertices(polygons, settings.max_segment_area),
        lights.len(),
        settings.bytes_per_entry,
        settings.max_matrix_bytes,
    )
    .map_err(|m| format!("at least {m}"))?;
    let start = Instant::now();
    let tolerance = settings.tolerance;
    let tree = build_tree_in(polygons, &tolerance);
    let bsp_ms = ms(start);

    let start = Instant::now();
    let segmented = segment_fragments(&tree, lights, settings)?;
    let segment_ms = ms(start);

    let segments = &segmented.segments;
    check_matrix(
        segments.positions.len(),
        lights.len(),
        settings.bytes_per_entry,
        settings.max_matrix_bytes,
    )?;
    let fragment_source: Vec<u32> = tree.fragments.iter().map(|(f, _)| f.source as u32).collect();
    let albedo: Vec<DVec3> = segments
        .vertex_polygon
        .iter()
        .map(|&f| polygons[fragment_source[f as usize] as usize].albedo)
        .collect();

    let start = Instant::now();
    let fragments: Vec<&Polygon> = tree.fragments.iter().map(|(f, _)| &f.polygon).collect();
    let spheres: Vec<(DVec3, f64)> = fragments.iter().map(|f| bounding_sphere(&f.vertices)).collect();
    let shared = Shared {
        fragments: &fragments,
        spheres: &spheres,
        tree: &tree,
        segments,
        fragment_vertices: &segmented.fragment_vertices,
        fragment_back_vertices: &segmented.fragment_back_vertices,
        albedo: &albedo,
        model: settings.model,
        projection: settings.projection,
        tolerance,
        cull_by_cones: settings.cull_by_cones,
    };
    let per_thread = shade_lights(&shared, lights, settings.threads, progress);
    let lights_wall_ms = ms(start);
    let phases = Phases {
        bsp_ms,
        segment_ms,
        lights_wall_ms,
        ..Phases::default()
    };
    let (colours, phases) = gather_columns(per_thread, segments.positions.len(), lights.len(), phases)?;
    Ok(Setup {
        tree,
        segments: segmented.segments,
        fragment_source,
        fragment_vertices: segmented.fragment_vertices,
        front_vertices: segmented.front_vertices,
        back_row: segmented.back_row,
        fragment_back_vertices: segmented.fragment_back_vertices,
        lights: lights.len(),
        colours,
        phases,
    })
}

/// The tree's fragments segmented, with the rows each fragment owns (see [`Setup`]).
struct Segmented {
    segments: Segments,
    fragment_vertices: Vec<Range<u32>>,
    front_vertices: usize,
    back_row: Vec<u32>,
    fragment_back_vertices: Vec<Range<u32>>,
}

/// Segments the tree's fragments (vertices on the tolerance's grid) and, when two-sided, adds
/// the back rows of fragments with a light behind them.
fn segment_fragments(tree: &Tree, lights: &[ManyLight], settings: &Settings) -> Result<Segmented, String> {
    let tolerance = settings.tolerance;
    let mut segments = Segments::build(
        tree.fragments.iter().map(|(f, _)| &f.polygon),
        settings.max_segment_area,
    )?;
    segments.positions.iter_mut().for_each(|p| *p = tolerance.round(*p));
    let fragment_vertices = owner_ranges(&segments.vertex_polygon, tree.fragments.len());
    let front_vertices = segments.positions.len();
    let planes: Vec<Plane> = tree.fragments.iter().map(|(f, _)| f.polygon.plane).collect();
    let (back_row, fragment_back_vertices) = if settings.two_sided {
        add_back_rows(&mut segments, &planes, &fragment_vertices, lights, &tolerance)
    } else {
        (vec![u32::MAX; front_vertices], vec![0..0; planes.len()])
    };
    Ok(Segmented {
        segments,
        fragment_vertices,
        front_vertices,
        back_row,
        fragment_back_vertices,
    })
}

/// Colours and shadows every light's column on `threads` threads (0: every core), lights dealt
/// round-robin, reporting progress while they run.
fn shade_lights(
    shared: &Shared<'_>,
    lights: &[ManyLight],
    threads: usize,
    progress: &mut Progress,
) -> Vec<ThreadResult> {
    let threads = if threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        threads
    }
    .clamp(1, lights.len().max(1));
    // Progress in pairs of the painter's pass (fragment pairs, per light), which is where the
    // time goes: a single light's set-up then has a rate too.
    let done = AtomicU64::new(0);
    let fragments = shared.fragments.len() as u64;
    let total = (lights.len() as u64 * (fragments * fragments.saturating_sub(1) / 2)).max(1);
    let cancel = progress.cancellation();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let (done, cancel) = (&done, &cancel);
                s.spawn(move || {
                    let (mut out, mut colour_ms, mut shadow_ms) = (Vec::new(), 0.0, 0.0);
                    for (l, light) in lights.iter().enumerate().skip(t).step_by(threads) {
                        // Cancelled: the bake stops after the loop and caches nothing.
                        if cancel.as_ref().is_some_and(|c| c.is_cancelled()) {
                            break;
                        }
                        let start = Instant::now();
                        let mut column = shared.colour(light);
                        colour_ms += ms(start);
                        let start = Instant::now();
                        shared.shadow(light.position, &mut column, done);
                        shadow_ms += ms(start);
                        out.push((l, column));
                    }
                    (out, colour_ms, shadow_ms)
                })
            })
            .collect();
        while handles.iter().any(|h| !h.is_finished()) {
            progress.update(done.load(Ordering::Relaxed).min(total), total);
            // Short: a small set-up finishes within a few of these.
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        handles.into_iter().map(|h| h.join().unwrap_or_default()).collect()
    })
}

/// The threads' columns placed light-major into one matrix of `vertices` rows, and their CPU
/// times added to `phases`; an error when a thread failed and left lights unshaded.
fn gather_columns(
    per_thread: Vec<ThreadResult>,
    vertices: usize,
    lights: usize,
    mut phases: Phases,
) -> Result<(Vec<[f32; 3]>, Phases), String> {
    let mut colours = vec![[0.0f32; 3]; vertices * lights];
    let mut filled = 0;
    for (columns, colour_ms, shadow_ms) in per_thread {
        phases.colour_cpu_ms += colour_ms;
        phases.shadow_cpu_ms += shadow_ms;
        for (l, column) in columns {
            colours[l * column.len()..(l + 1) * column.len()].copy_from_slice(&column);
            filled += 1;
        }
    }
    if filled != lights {
        return Err(format!("a set-up thread failed ({filled} of {lights} lights shaded)"));
    }
    Ok((colours, phases))
}

/// Appends a back-side row (same position, normal turned) for every vertex of each fragment
/// that has a light strictly behind its plane; returns each front vertex's back row
/// (`u32::MAX`: none) and each fragment's back rows. A fragment every light is in front of
/// gets none: its back side's direct light is zero, which the run time draws for a missing row.
fn add_back_rows(
    segments: &mut Segments,
    planes: &[Plane],
    fragment_vertices: &[Range<u32>],
    lights: &[ManyLight],
    tolerance: &Tolerance,
) -> (Vec<u32>, Vec<Range<u32>>) {
    let mut back_row = vec![u32::MAX; segments.positions.len()];
    let mut ranges = vec![0u32..0u32; planes.len()];
    for (f, plane) in planes.iter().enumerate() {
        if !lights
            .iter()
            .any(|l| plane.side_of_point_in(l.position, tolerance) == Side::Back)
        {
            continue;
        }
        let first = segments.positions.len() as u32;
        for v in fragment_vertices[f].clone() {
            back_row[v as usize] = segments.positions.len() as u32;
            segments.positions.push(segments.positions[v as usize]);
            segments.normals.push(-segments.normals[v as usize]);
            segments.vertex_polygon.push(f as u32);
        }
        ranges[f] = first..segments.positions.len() as u32;
    }
    (back_row, ranges)
}

/// The fewest vertices [`Segments::build`] can make over `polygons` (their BSP fragments cover
/// the same area): each fan triangle is cut into triangles of at most `max_area`, so a polygon
/// gets at least area / `max_area` triangles, and a triangulated polygon has at least half as
/// many vertices as triangles. Polygons without area count nothing.
pub fn min_vertices(polygons: &[ScenePolygon], max_area: f64) -> usize {
    if !(max_area.is_finite() && max_area > 0.0) {
        return 0;
    }
    polygons
        .iter()
        .map(|p| {
            let v = &p.polygon.vertices;
            let area: f64 = (1..v.len().saturating_sub(1))
                .map(|k| 0.5 * (v[k] - v[0]).cross(v[k + 1] - v[0]).length())
                .sum();
            (area / max_area / 2.0).floor() as usize
        })
        .sum()
}

/// `V·L·bytes` of vertex colours against the limit, as one sentence when over it.
pub fn check_matrix(vertices: usize, lights: usize, bytes_per_entry: u64, max_bytes: u64) -> Result<(), String> {
    let bytes = vertices as u64 * lights as u64 * bytes_per_entry;
    if bytes > max_bytes {
        return Err(format!(
            "{vertices} vertices × {lights} lights × {bytes_per_entry} bytes = {} MiB of vertex colours, over the device's {} MiB storage-buffer limit: raise max_segment_area, use storage = \"f16\" or fewer lights",
            bytes.div_ceil(1 << 20),
            max_bytes >> 20
        ));
    }
    Ok(())
}

/// Per owner (0..`owners`), the run of consecutive items it owns in `owner_of` (`Segments` adds
/// a polygon's vertices and its triangles together); an owner with none gets an empty range.
pub fn owner_ranges(owner_of: &[u32], owners: usize) -> Vec<Range<u32>> {
    let mut ranges = vec![0u32..0u32; owners];
    let mut i = 0usize;
    while i < owner_of.len() {
        let owner = owner_of[i];
        let first = i;
        while i < owner_of.len() && owner_of[i] == owner {
            i += 1;
        }
        if let Some(r) = ranges.get_mut(owner as usize) {
            *r = first as u32..i as u32;
        }
    }
    ranges
}

/// What every light's pass reads.
struct Shared<'a> {
    fragments: &'a [&'a Polygon],
    /// Each fragment's bounding sphere (centre, radius), for the shadow pass's cone test.
    spheres: &'a [(DVec3, f64)],
    tree: &'a Tree,
    segments: &'a Segments,
    fragment_vertices: &'a [Range<u32>],
    fragment_back_vertices: &'a [Range<u32>],
    albedo: &'a [DVec3],
    model: LightModel,
    projection: Projection,
    tolerance: Tolerance,
    cull_by_cones: bool,
}

impl Shared<'_> {
    /// `C_l(v)` at full intensity, unshadowed.
    fn colour(&self, light: &ManyLight) -> Vec<[f32; 3]> {
        let s = self.segments;
        (0..s.positions.len())
            .map(|v| {
                light
                    .shade(&self.model, s.positions[v], s.normals[v], self.albedo[v])
                    .as_vec3()
                    .to_array()
            })
            .collect()
    }

    /// The painter's pass from the light: every fragment, in back-to-front order, projected
    /// onto each fragment before it; that target's lit vertices inside the projection go dark.
    fn shadow(&self, light: DVec3, column: &mut [[f32; 3]], pairs_done: &AtomicU64) {
        let order: Vec<usize> = self
            .tree
            .faces_back_to_front(light)
            .into_iter()
            .map(|f| f as usize)
            .collect();
        let positions = &self.segments.positions;
        // Lit vertices left per fragment: a target gone dark is never projected onto again.
        let rows = |t: usize| {
            self.fragment_vertices[t]
                .clone()
                .chain(self.fragment_back_vertices[t].clone())
        };
        let mut lit: Vec<usize> = (0..self.fragments.len())
            .map(|t| rows(t).filter(|&v| column[v as usize] != [0.0; 3]).count())
            .collect();
        // The valid projection puts a shadow on rays from the light through the occluder, so
        // only a target whose cone from the light meets the occluder's can be darkened: pairs
        // whose cones are apart are skipped before projecting (most of them on a mesh of many
        // small fragments). The thesis's projection can cast through infinity, so every pair
        // is projected there.
        let cones: Vec<Cone> = self
            .spheres
            .iter()
            .map(|&(c, r)| Cone::from_light(light, c, r))
            .collect();
        let cull = self.cull_by_cones && self.projection == Projection::Valid;
        for (i, &o) in order.iter().enumerate() {
            pairs_done.fetch_add(i as u64, Ordering::Relaxed);
            let occluder = self.fragments[o];
            for &t in &order[..i] {
                if lit[t] == 0 || (cull && !cones[o].meets(&cones[t])) {
                    continue;
                }
                let target = self.fragments[t];
                let Some(shadow) = project(
                    light,
                    &occluder.vertices,
                    &target.plane,
                    self.projection,
                    &self.tolerance,
                ) else {
                    continue;
                };
                // The test on the projected polygon's bounds first: most pairs miss entirely.
                let (lo, hi) = bounds(&shadow);
                for v in rows(t) {
                    let (v, p) = (v as usize, positions[v as usize]);
                    if column[v] == [0.0; 3] || p.cmplt(lo).any() || p.cmpgt(hi).any() {
                        continue;
                    }
                    if point_in_convex_polygon(p, &shadow, target.plane.normal) {
                        column[v] = [0.0; 3];
                        lit[t] -= 1;
                    }
                }
            }
        }
    }
}

/// A fragment seen from a light: the cone of rays from the light through its bounding sphere.
struct Cone {
    axis: DVec3,
    /// Cosine and sine of the half-angle; a light inside the sphere sees it all around
    /// (`cos` −1).
    cos: f64,
    sin: f64,
}

impl Cone {
    fn from_light(light: DVec3, centre: DVec3, radius: f64) -> Cone {
        let d = centre - light;
        let distance = d.length();
        // Widened a hair beyond the sphere, so rounding never culls a touching pair.
        let radius = radius * (1.0 + 1e-9) + 1e-9 * distance;
        if distance <= radius {
            return Cone {
                axis: DVec3::Z,
                cos: -1.0,
                sin: 0.0,
            };
        }
        let sin = radius / distance;
        Cone {
            axis: d / distance,
            cos: (1.0 - sin * sin).sqrt(),
            sin,
        }
    }

    /// Whether some ray from the light lies in both cones: the angle between the axes is at
    /// most the sum of the half-angles.
    fn meets(&self, other: &Cone) -> bool {
        if self.cos <= -1.0 || other.cos <= -1.0 {
            return true;
        }
        // cos(a + b); past a half turn the cones cover every direction between them.
        let cos_sum = self.cos * other.cos - self.sin * other.sin;
        let sum_past_half_turn = self.sin * other.cos + self.cos * other.sin < 0.0;
        sum_past_half_turn || self.axis.dot(other.axis) >= cos_sum
    }
}

/// A sphere holding `points`: their bounding box's centre and the farthest point from it.
fn bounding_sphere(points: &[DVec3]) -> (DVec3, f64) {
    let (lo, hi) = bounds(points);
    let centre = 0.5 * (lo + hi);
    (centre, points.iter().map(|&p| p.distance(centre)).fold(0.0, f64::max))
}

fn bounds(points: &[DVec3]) -> (DVec3, DVec3) {
    let pad = DVec3::splat(1e-9);
    let lo = points.iter().fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
    let hi = points.iter().fold(DVec3::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
    (lo - pad, hi + pad)
}

/// The occluder's shadow on the target's plane: its vertices projected centrally from the light
/// (`P = L + t·(x − L)`, `t = h_L / (h_L − h_x)` with `h` the signed heights over the plane), or
/// `None` where it casts nothing there. An occluder lying in the target's plane casts nothing in
/// either mode (it is beside the target, not in front of it; the thesis's rounding served the
/// same end). `tolerance` says what "in the plane" means and rounds the shadow's vertices.
pub fn project(
    light: DVec3,
    occluder: &[DVec3],
    target: &Plane,
    projection: Projection,
    tolerance: &Tolerance,
) -> Option<Vec<DVec3>> {
    let h_light = target.distance(light);
    if h_light.abs() <= tolerance.plane {
        return None;
    }
    let on_plane = occluder
        .iter()
        .all(|&x| target.side_of_point_in(x, tolerance) == Side::On);
    if on_plane {
        return None;
    }
    let points = match projection {
        Projection::Thesis => occluder.to_vec(),
        Projection::Valid => {
            // Keep s·h_x ∈ [0, |h_L|·(1 − slack)]: on the light's side of the target, and short
            // of the plane through the light.
            let s = h_light.signum();
            let toward_light = Plane {
                normal: target.normal * s,
                dist: target.dist * s,
            };
            let short_of_light = Plane {
                normal: -target.normal * s,
                dist: -(target.dist * s + h_light.abs() * (1.0 - PARALLEL_SLACK)),
            };
            let clipped = clip_points_front(occluder, &toward_light, 0.0);
            let clipped = clip_points_front(&clipped, &short_of_light, 0.0);
            if clipped.len() < 3 {
                return None;
            }
            clipped
        }
    };
    let mut out = Vec::with_capacity(points.len());
    for x in points {
        let denom = h_light - target.distance(x);
        if denom.abs() <= 1e-12 * h_light.abs() {
            // A vertex in the plane through the light projects to infinity: the thesis's pass
            // has no answer for it either, so the occluder casts nothing.
            return None;
        }
        out.push(tolerance.round(light + (x - light) * (h_light / denom)));
    }
    // Only the valid projection is a simple polygon whose area means something: the thesis's
    // can be a bow-tie through infinity, whose lobes cancel.
    (projection == Projection::Thesis || shadow_area(&out, target.normal) > MIN_SHADOW_AREA).then_some(out)
}

/// Area of a planar vertex loop (absolute value of its vector area along the normal).
fn shadow_area(points: &[DVec3], normal: DVec3) -> f64 {
    let mut sum = DVec3::ZERO;
    for (i, a) in points.iter().enumerate() {
        sum += a.cross(points[(i + 1) % points.len()]);
    }
    0.5 * sum.dot(normal).abs()
}
