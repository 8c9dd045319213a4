//! Patches (the Ca3D-Engine thesis §3, digest §1.2 step B): static triangles grouped into planar charts, each
//! chart covered by a regular square grid of patches — one patch per light-map texel — with a
//! one-patch border frame for bilinear filtering. Grids are aligned to the world origin (as
//! CaLight's are), so the grids of coplanar charts overlap cell for cell, or not at all: border
//! pass 2 ([`super::border`]) matches them up by index.

use glam::{DVec2, DVec3};

/// A static triangle as the baker sees it.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    pub p: [DVec3; 3],
    /// The scene object (or emitter) it belongs to: charts never mix objects.
    pub object: usize,
    /// Diffuse reflectance, RGB.
    pub albedo: DVec3,
    /// Emitted radiance, RGB (W/(m²·sr)); emits toward its normal only.
    pub emission: DVec3,
    /// A sky surface (the material's `sky` flag): it occludes, is never lit and never shoots,
    /// and the sun reaches what sees it (digest §1.2 steps A and C).
    pub sky: bool,
    /// Which side of the thin walls standing on its surface it lies on (a bit per wall, set by
    /// the cut along them): pieces of one surface on different sides never share a chart.
    pub part: u64,
}

impl Triangle {
    pub fn normal(&self) -> DVec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0]).normalize_or_zero()
    }
    pub fn area(&self) -> f64 {
        0.5 * (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0]).length()
    }
}

/// A planar group of triangles of one object and material, with its patch grid.
#[derive(Clone, Debug)]
pub struct Chart {
    pub object: usize,
    pub normal: DVec3,
    /// The grid's frame: patch (i, j) (border included) covers origin + [i, i+1)·size·u + [j, j+1)·size·v.
    pub origin: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    /// Patches per side, border included.
    pub width: usize,
    pub height: usize,
    /// First patch in [`Patches::patches`] (row-major).
    pub first: usize,
    pub triangles: Vec<usize>,
    /// The world grid's index of patch (0, 0): `origin = n·d + cell.0·size·u + cell.1·size·v`,
    /// so coplanar charts' patches (i, j) and (i', j') coincide when their cell indices do.
    pub cell: (i64, i64),
    /// The polygon's bounds in the grid's frame (metres from `origin` along `u` and `v`): a
    /// block of edge patches shoots from its cells clipped to them (never narrower than a patch).
    pub extent: (DVec2, DVec2),
    /// A sky chart: a single black texel, no patch inside.
    pub sky: bool,
    /// The plane's offset along `normal`: the patches lie on the plane `normal·x = offset`.
    pub offset: f64,
    /// Charts of a curved surface merged (`group_charts_within`): its triangles lie on or
    /// below the plane, within the grouping's sag of it, and each patch takes the normal of the
    /// triangles under it.
    pub curved: bool,
}

impl Chart {
    /// The chart's triangles in its grid's frame: metres from `origin` along `u` and `v`.
    pub(crate) fn flat_triangles(&self, triangles: &[Triangle]) -> Vec<[DVec2; 3]> {
        self.triangles
            .iter()
            .map(|&t| {
                triangles[t]
                    .p
                    .map(|q| DVec2::new((q - self.origin).dot(self.u), (q - self.origin).dot(self.v)))
            })
            .collect()
    }

    /// The grid cell (i, j) of patch `k`, one of this chart's.
    pub(crate) fn cell_of(&self, k: usize) -> (usize, usize) {
        ((k - self.first) % self.width, (k - self.first) / self.width)
    }

    /// Sub-sample (`si`, `sj`) of patch (`i`, `j`) on the [`COVERAGE_SAMPLES`]² grid, on the
    /// chart's plane.
    pub(crate) fn sub_sample(&self, size: f64, (i, j): (usize, usize), (si, sj): (usize, usize)) -> DVec3 {
        let n = COVERAGE_SAMPLES as f64;
        self.origin
            + self.u * ((i as f64 + (si as f64 + 0.5) / n) * size)
            + self.v * ((j as f64 + (sj as f64 + 0.5) / n) * size)
    }

    /// The sub-grid index (bit of [`Patch::samples`]) of `x`, a point of patch (`i`, `j`).
    pub(crate) fn sub_sample_bit(&self, size: f64, (i, j): (usize, usize), x: DVec3) -> u16 {
        let n = COVERAGE_SAMPLES;
        let at = |d: DVec3, cell: usize| {
            (((x - self.origin).dot(d) / size - cell as f64) * n as f64)
                .floor()
                .clamp(0.0, (n - 1) as f64) as usize
        };
        1 << (at(self.v, j) * n + at(self.u, i))
    }

    /// Patch (i, j)'s sub-samples on an `n`×`n` grid that fall inside the polygon (`flat`, from
    /// [`Chart::flat_triangles`]), as points on the chart's plane.
    pub(crate) fn inside_samples(&self, flat: &[[DVec2; 3]], size: f64, i: usize, j: usize, n: usize) -> Vec<DVec3> {
        let mut out = Vec::new();
        for sj in 0..n {
            for si in 0..n {
                let q = DVec2::new(
                    i as f64 + (si as f64 + 0.5) / n as f64,
                    j as f64 + (sj as f64 + 0.5) / n as f64,
                ) * size;
                if flat.iter().any(|t| inside_triangle(q, t)) {
                    out.push(self.origin + self.u * q.x + self.v * q.y);
                }
            }
        }
        out
    }
}

#[derive(Clone, Copy, Debug, Default)]
pub struct Patch {
    pub chart: usize,
    pub centre: DVec3,
    pub normal: DVec3,
    /// The area of the chart's polygon inside the patch (0 for border patches).
    pub area: f64,
    /// The fraction of the patch's sub-samples inside the polygon: 1 INNER, 0 OUTER, else PARTIAL.
    pub coverage: f64,
    /// The sub-samples the patch keeps, one bit each (bit `sj·4 + si` of the 4×4 grid
    /// `Chart::sub_sample` places): inside the polygon, and once the corrected bake has left
    /// buried parts out ([`super::buried::exclude`]), seen. A receiver near a shooter gathers over
    /// them.
    pub samples: u16,
    pub albedo: DVec3,
    /// Emitted radiosity π·L_e.
    pub emission: DVec3,
    /// Radiosity (W/m²): emitted plus reflected.
    pub total: DVec3,
    /// Radiosity received but not yet shot.
    pub unshot: DVec3,
}

impl Patch {
    pub fn inside(&self) -> bool {
        self.area > 0.0
    }
}

#[derive(Clone, Debug)]
pub struct Patches {
    pub size: f64,
    pub charts: Vec<Chart>,
    pub patches: Vec<Patch>,
}

/// Coverage of a patch by its chart's triangles is estimated on this many sub-samples per side
/// (the bits of [`Patch::samples`]).
pub const COVERAGE_SAMPLES: usize = 4;

impl Patches {
    /// Groups `triangles` into charts (planar ones, then a curved surface's merged within a
    /// quarter of `size` of one plane: `group_charts_within`) and lays a grid of `size`
    /// patches on each.
    pub fn build(triangles: &[Triangle], size: f64) -> Patches {
        let mut charts = group_charts_within(triangles, size * CURVED_SAG);
        let mut patches = Vec::new();
        for (ci, c) in charts.iter_mut().enumerate() {
            let t0 = &triangles[c.triangles[0]];
            let plane = c.normal * c.offset;
            // Coordinates from the world origin's projection, so that every chart of a plane
            // shares one grid.
            let flat = |p: DVec3| DVec2::new(p.dot(c.u), p.dot(c.v));
            let (lo, hi) = flat_bounds(c, triangles);
            c.origin = plane;
            c.first = patches.len();
            if c.sky {
                // Sky is not patched: one black texel that its triangles all map to.
                c.width = 1;
                c.height = 1;
                c.origin = plane + c.u * lo.x + c.v * lo.y;
                patches.push(Patch {
                    chart: ci,
                    centre: c.origin,
                    normal: c.normal,
                    ..Patch::default()
                });
                continue;
            }
            let (lo_cell, cells) = grid_cells(lo, hi, size);
            let polygon = (lo, hi);
            let lo = lo_cell * size;
            c.width = cells.x as usize + 2;
            c.height = cells.y as usize + 2;
            // One border patch on every side.
            c.cell = (lo_cell.x as i64 - 1, lo_cell.y as i64 - 1);
            c.origin = plane + c.u * (lo.x - size) + c.v * (lo.y - size);
            c.extent = (polygon.0 - lo + size, polygon.1 - lo + size);
            let tris2d: Vec<[DVec2; 3]> = c.triangles.iter().map(|&ti| triangles[ti].p.map(flat)).collect();
            for j in 0..c.height {
                for i in 0..c.width {
                    let corner = DVec2::new(lo.x + (i as f64 - 1.0) * size, lo.y + (j as f64 - 1.0) * size);
                    let (mut covered, mut sum, mut samples) = (0usize, DVec2::ZERO, 0u16);
                    let mut normals = DVec3::ZERO;
                    for sj in 0..COVERAGE_SAMPLES {
                        for si in 0..COVERAGE_SAMPLES {
                            let q = corner
                                + DVec2::new(
                                    (si as f64 + 0.5) / COVERAGE_SAMPLES as f64,
                                    (sj as f64 + 0.5) / COVERAGE_SAMPLES as f64,
                                ) * size;
                            let under = if c.curved {
                                tris2d.iter().position(|t| inside_triangle(q, t))
                            } else {
                                tris2d.iter().any(|t| inside_triangle(q, t)).then_some(0)
                            };
                            if let Some(slot) = under {
                                if c.curved {
                                    normals += triangles[c.triangles[slot]].normal();
                                }
                                covered += 1;
                                sum += q;
                                samples |= 1 << (sj * COVERAGE_SAMPLES + si);
                            }
                        }
                    }
                    let coverage = covered as f64 / (COVERAGE_SAMPLES * COVERAGE_SAMPLES) as f64;
                    let area = size * size * coverage;
                    let mut centre = c.origin + c.u * ((i as f64 + 0.5) * size) + c.v * ((j as f64 + 0.5) * size);
                    if covered > 0 && coverage < 1.0 {
                        // A partial patch samples at the centroid of its covered part: its cell
                        // centre may lie beyond a wall the polygon ends at (a light leak), and
                        // every sample inside the polygon keeps shots inside the pair's convex
                        // hull (the visibility matrix's FULL relies on it).
                        let m = sum / covered as f64 - corner;
                        centre = c.origin + c.u * (i as f64 * size + m.x) + c.v * (j as f64 * size + m.y);
                    }
                    let emission = t0.emission * std::f64::consts::PI;
                    let e = if area > 0.0 { emission } else { DVec3::ZERO };
                    patches.push(Patch {
                        chart: ci,
                        centre,
                        normal: normals.try_normalize().unwrap_or(c.normal),
                        area,
                        coverage,
                        samples,
                        albedo: t0.albedo,
                        emission: e,
                        total: e,
                        unshot: e,
                    });
                }
            }
            fit_area(c, &mut patches[c.first..], triangles, &tris2d, lo, size);
        }
        Patches { size, charts, patches }
    }

    /// Σ area · radiosity: the power leaving every patch (W), per channel.
    pub fn power(&self, f: impl Fn(&Patch) -> DVec3) -> DVec3 {
        self.patches.iter().map(|p| f(p) * p.area).sum()
    }
}

/// The sub-sampled coverage is coarse for a polygon smaller than a few patches (a light a patch
/// wide can be off by a third): chart `c`'s patches (`chart`) are scaled so that they add up to
/// its exact area, and the power it emits or receives is right. A sliver or a triangle smaller
/// than a sub-sample's spacing covers no sub-sample: the chart's largest triangle's centroid
/// stands for it, or its texel would stay black. `tris2d` is its triangles and `lo` its lowest
/// cell corner in its frame.
fn fit_area(c: &Chart, chart: &mut [Patch], triangles: &[Triangle], tris2d: &[[DVec2; 3]], lo: DVec2, size: f64) {
    let exact: f64 = c.triangles.iter().map(|&t| triangles[t].area()).sum();
    let sampled: f64 = chart.iter().map(|q| q.area).sum();
    if sampled > 0.0 {
        for q in chart.iter_mut() {
            q.area *= exact / sampled;
        }
    } else if exact > 0.0 {
        cover_by_centroid(c, chart, triangles, tris2d, lo, size);
    }
}

/// [`fit_area`] where no sub-sample is covered.
fn cover_by_centroid(
    c: &Chart,
    chart: &mut [Patch],
    triangles: &[Triangle],
    tris2d: &[[DVec2; 3]],
    lo: DVec2,
    size: f64,
) {
    // Every chart holds a triangle; one without would simply keep no patch.
    let Some(slot) = (0..tris2d.len()).max_by(|&a, &b| {
        triangles[c.triangles[a]]
            .area()
            .total_cmp(&triangles[c.triangles[b]].area())
    }) else {
        return;
    };
    let q = (tris2d[slot][0] + tris2d[slot][1] + tris2d[slot][2]) / 3.0;
    let at = (q - lo) / size;
    let (i, j) = (at.x.floor().max(0.0) as usize + 1, at.y.floor().max(0.0) as usize + 1);
    let (i, j) = (i.min(c.width - 2), j.min(c.height - 2));
    let n = COVERAGE_SAMPLES as f64;
    let sub = |x: f64, cell: usize| ((x - cell as f64) * n).floor().clamp(0.0, n - 1.0) as usize;
    let t = &triangles[c.triangles[slot]];
    let patch = &mut chart[j * c.width + i];
    patch.area = c.triangles.iter().map(|&t| triangles[t].area()).sum();
    patch.coverage = 1.0 / (COVERAGE_SAMPLES * COVERAGE_SAMPLES) as f64;
    patch.samples = 1 << (sub(at.y + 1.0, j) * COVERAGE_SAMPLES + sub(at.x + 1.0, i));
    patch.centre = c.origin + c.u * ((at.x + 1.0) * size) + c.v * ((at.y + 1.0) * size);
    patch.normal = if c.curved { t.normal() } else { c.normal };
    let e = triangles[c.triangles[0]].emission * std::f64::consts::PI;
    (patch.emission, patch.total, patch.unshot) = (e, e, e);
}

/// The patches [`Patches::build`] would make of `triangles` at `size`, border frames included,
/// counted without making them (what a bake's memory is estimated from).
pub fn count(triangles: &[Triangle], size: f64) -> u64 {
    count_in(&group_charts_within(triangles, size * CURVED_SAG), triangles, size)
}

/// [`count`] over charts already grouped.
pub(crate) fn count_in(charts: &[Chart], triangles: &[Triangle], size: f64) -> u64 {
    charts
        .iter()
        .map(|c| {
            if c.sky {
                return 1;
            }
            let (lo, hi) = flat_bounds(c, triangles);
            let (_, cells) = grid_cells(lo, hi, size);
            (cells.x + 2.0) as u64 * (cells.y + 2.0) as u64
        })
        .sum()
}

/// Groups `triangles` into charts (same object, normal within 1e-4, plane offset within 1e-5
/// of the scene's size, same material, same side of any thin wall); their grids are not laid
/// yet. A triangle joins the first chart (in creation order) it matches, so the grouping does
/// not depend on how charts are looked up: here through a hash of their planes
/// ([`PlaneGrid`]), so that a curved mesh's tens of thousands of small charts take linear time.
pub(crate) fn group_charts(triangles: &[Triangle]) -> Vec<Chart> {
    group_charts_counted(triangles).0
}

/// [`group_charts`] and how many charts it compared triangles with: the work that a scan of
/// every chart makes quadratic.
pub(crate) fn group_charts_counted(triangles: &[Triangle]) -> (Vec<Chart>, usize) {
    let mut compared = 0;
    let scale = triangles
        .iter()
        .flat_map(|t| t.p)
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()))
        .max(1.0);
    // Vertices lie within √3 of the scene's size of the origin.
    let grid = PlaneGrid::new(3f64.sqrt() * scale, 1e-5 * scale);
    let mut cells: std::collections::HashMap<ChartCell, Vec<usize>> = std::collections::HashMap::new();
    let mut charts: Vec<Chart> = Vec::new();
    for (ti, t) in triangles.iter().enumerate() {
        let n = t.normal();
        if n == DVec3::ZERO {
            continue;
        }
        let matches = |c: &Chart| {
            let tc = &triangles[c.triangles[0]];
            one_surface(tc, t)
                && c.normal.dot(n) > 1.0 - 1e-4
                && (c.normal.dot(t.p[0]) - c.normal.dot(tc.p[0])).abs() < 1e-5 * scale
        };
        let same = grid
            .around(n, t.p[0])
            .filter_map(|cell| cells.get(&(t.object, t.part, t.sky, cell)))
            .flatten()
            .copied()
            .inspect(|_| compared += 1)
            .filter(|&c| matches(&charts[c]))
            .min();
        match same {
            Some(c) => charts[c].triangles.push(ti),
            None => {
                cells
                    .entry((t.object, t.part, t.sky, grid.cell(n, t.p[0])))
                    .or_default()
                    .push(charts.len());
                let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
                let u = helper.cross(n).normalize();
                let v = n.cross(u);
                charts.push(Chart {
                    object: t.object,
                    normal: n,
                    origin: DVec3::ZERO,
                    u,
                    v,
                    width: 0,
                    height: 0,
                    first: 0,
                    triangles: vec![ti],
                    cell: (0, 0),
                    extent: (DVec2::ZERO, DVec2::ZERO),
                    sky: t.sky,
                    offset: n.dot(t.p[0]),
                    curved: false,
                });
            }
        }
    }
    (charts, compared)
}

/// Whether two triangles may share a chart, their planes aside: the same object, material
/// (albedo and emission), sky flag and side of every thin wall.
fn one_surface(a: &Triangle, b: &Triangle) -> bool {
    a.object == b.object
        && (a.albedo - b.albedo).abs().max_element() < 1e-9
        && (a.emission - b.emission).abs().max_element() < 1e-9
        && a.sky == b.sky
        && a.part == b.part
}

/// How far, in patches, a curved chart's triangles may lie below its plane: its patches lie on
/// the plane, so a receiver stands at most this far above the surface it stands for.
pub const CURVED_SAG: f64 = 0.25;

/// The cosine of the widest angle between a curved chart's normal (its seed's) and any of its
/// triangles' (30°): it bounds the stretch of a triangle's texels (1/cos 30° = 1.15) and
/// keeps a crease's two sides apart.
pub const CURVED_CONE_COS: f64 = 0.866_025_403_784_438_6;

/// [`group_charts`], then adjacent charts of one surface merged while their triangles stay
/// within [`CURVED_CONE_COS`] of one normal and within `max_sag` of one plane
/// ([`merge_curved`]). A scanned or tessellated mesh makes a planar chart of every triangle or
/// two, each at least a texel and its border frame (nine patches): the Stanford bunny's 69k
/// triangles made 608k patches, at any patch size. With `max_sag` 0 the planar charts are kept.
pub(crate) fn group_charts_within(triangles: &[Triangle], max_sag: f64) -> Vec<Chart> {
    merge_curved(group_charts(triangles), triangles, max_sag)
}

/// Grows regions over charts that share an edge (the same corner positions, bit for bit), each
/// seeded by the largest chart left: a chart joins its neighbour's region when it is of the same
/// object, material, side of the walls and not sky, every one of its triangles is within
/// [`CURVED_CONE_COS`] of the seed's normal, and the region's heights along that normal then
/// span at most `max_sag`. A region of more than one chart becomes one chart in the seed's
/// frame, its plane at the highest corner, so that every patch lies above the
/// surface (never inside a closed mesh). The cone keeps the projection one-to-one for a surface
/// that does not fold back over itself within the sag. Regions keep the order of their
/// smallest chart, so with nothing merged the charts are those given.
fn merge_curved(charts: Vec<Chart>, triangles: &[Triangle], max_sag: f64) -> Vec<Chart> {
    if max_sag <= 0.0 || charts.len() < 2 {
        return charts;
    }
    let neighbours = chart_neighbours(&charts, triangles);
    let area: Vec<f64> = charts
        .iter()
        .map(|c| c.triangles.iter().map(|&t| triangles[t].area()).sum())
        .collect();
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by(|&a, &b| area[b].total_cmp(&area[a]).then(a.cmp(&b)));
    let same_kind =
        |a: &Chart, b: &Chart| !a.sky && one_surface(&triangles[a.triangles[0]], &triangles[b.triangles[0]]);
    let mut taken = vec![false; charts.len()];
    // (seed, members, highest corner along the seed's normal)
    let mut regions: Vec<(usize, Vec<usize>, f64)> = Vec::new();
    for &seed in &order {
        if taken[seed] {
            continue;
        }
        taken[seed] = true;
        let n = charts[seed].normal;
        let heights = |c: &Chart| {
            c.triangles
                .iter()
                .flat_map(|&t| triangles[t].p)
                .map(|p| n.dot(p))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), h| (lo.min(h), hi.max(h)))
        };
        let (mut lo, mut hi) = heights(&charts[seed]);
        let mut members = vec![seed];
        let mut next = 0;
        while next < members.len() {
            let c = members[next];
            next += 1;
            for &d in &neighbours[c] {
                if taken[d]
                    || !same_kind(&charts[seed], &charts[d])
                    || charts[d]
                        .triangles
                        .iter()
                        .any(|&t| triangles[t].normal().dot(n) < CURVED_CONE_COS)
                {
                    continue;
                }
                let (l, h) = heights(&charts[d]);
                if hi.max(h) - lo.min(l) > max_sag {
                    continue;
                }
                (lo, hi) = (lo.min(l), hi.max(h));
                taken[d] = true;
                members.push(d);
            }
        }
        members.sort_unstable();
        regions.push((seed, members, hi));
    }
    regions.sort_by_key(|(_, members, _)| members[0]);
    let mut charts: Vec<Option<Chart>> = charts.into_iter().map(Some).collect();
    // Each chart is in exactly one region (the seed's), so every take finds it.
    regions
        .into_iter()
        .filter_map(|(seed, members, top)| {
            let mut chart = charts[seed].take()?;
            if members.len() == 1 {
                return Some(chart);
            }
            let mut all = Vec::new();
            for m in members {
                match charts[m].take() {
                    Some(c) => all.extend(c.triangles),
                    None => all.append(&mut chart.triangles),
                }
            }
            all.sort_unstable();
            chart.triangles = all;
            chart.offset = top;
            chart.curved = true;
            Some(chart)
        })
        .collect()
}

/// Per chart, the charts that share an edge with it (the same corner positions, bit for bit).
fn chart_neighbours(charts: &[Chart], triangles: &[Triangle]) -> Vec<Vec<usize>> {
    let mut chart_of = vec![usize::MAX; triangles.len()];
    for (c, chart) in charts.iter().enumerate() {
        for &t in &chart.triangles {
            chart_of[t] = c;
        }
    }
    let key = |p: DVec3| p.to_array().map(f64::to_bits);
    let mut edges: std::collections::HashMap<([u64; 3], [u64; 3]), Vec<usize>> = std::collections::HashMap::new();
    for (t, tri) in triangles.iter().enumerate().filter(|&(t, _)| chart_of[t] != usize::MAX) {
        for e in 0..3 {
            let (a, b) = (key(tri.p[e]), key(tri.p[(e + 1) % 3]));
            edges
                .entry(if a < b { (a, b) } else { (b, a) })
                .or_default()
                .push(chart_of[t]);
        }
    }
    let mut neighbours = vec![Vec::new(); charts.len()];
    for sharing in edges.values() {
        for &a in sharing {
            neighbours[a].extend(sharing.iter().copied().filter(|&b| b != a));
        }
    }
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    neighbours
}

/// A hash cell of chart planes: the object, side of the walls, sky flag, and the plane's
/// [`PlaneGrid`] cell.
type ChartCell = (usize, u64, bool, [i64; 4]);

/// Two unit normals with dot > 1 − 1e-4 differ by under 0.01415 (√(2·1e-4)) in every
/// component: cells this wide put them in the same or adjacent cells.
const NORMAL_CELL: f64 = 0.02;

/// Planes hashed by normal and offset, so that the planes within a tolerance of one lie in its
/// cell or the adjacent ones (81 in all): for normals within a dot of 1 − 1e-4 of each other,
/// and offsets within `offset_tolerance` once measured along the same normal.
pub(crate) struct PlaneGrid {
    /// The offset cells' width. Offsets are measured along each plane's own normal; measured
    /// along another within the tolerance, a point `r` from the origin shifts by under
    /// 0.01415·r, which the width covers for points within `radius`.
    offset_cell: f64,
}

impl PlaneGrid {
    pub(crate) fn new(radius: f64, offset_tolerance: f64) -> PlaneGrid {
        PlaneGrid {
            offset_cell: 0.01415 * radius + offset_tolerance,
        }
    }

    /// The cell of the plane of normal `n` through `at`.
    pub(crate) fn cell(&self, n: DVec3, at: DVec3) -> [i64; 4] {
        let q = [
            n.x / NORMAL_CELL,
            n.y / NORMAL_CELL,
            n.z / NORMAL_CELL,
            n.dot(at) / self.offset_cell,
        ];
        q.map(|x| x.floor() as i64)
    }

    /// The cells a plane within the tolerance of (`n`, `at`) can lie in.
    pub(crate) fn around(&self, n: DVec3, at: DVec3) -> impl Iterator<Item = [i64; 4]> {
        let base = self.cell(n, at);
        (0..81).map(move |k: i64| {
            let step = [k % 3 - 1, k / 3 % 3 - 1, k / 9 % 3 - 1, k / 27 - 1];
            std::array::from_fn(|a| base[a] + step[a])
        })
    }
}

/// A chart's triangles' bounds in its (u, v) plane coordinates.
fn flat_bounds(c: &Chart, triangles: &[Triangle]) -> (DVec2, DVec2) {
    let flat = |p: DVec3| DVec2::new(p.dot(c.u), p.dot(c.v));
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for &ti in &c.triangles {
        for p in triangles[ti].p {
            lo = lo.min(flat(p));
            hi = hi.max(flat(p));
        }
    }
    (lo, hi)
}

/// The world-grid cell of a chart's lowest corner and its cells per side, borders excluded:
/// snapped outward (a vertex on a grid line within 1e-9 of a cell stays on it).
fn grid_cells(lo: DVec2, hi: DVec2, size: f64) -> (DVec2, DVec2) {
    let lo_cell = (lo / size + 1e-9).floor();
    let hi_cell = (hi / size - 1e-9).ceil();
    (lo_cell, (hi_cell - lo_cell).max(DVec2::ONE))
}

pub(crate) fn inside_triangle(q: DVec2, t: &[DVec2; 3]) -> bool {
    let cross = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
    let (d0, d1, d2) = (cross(t[0], t[1], q), cross(t[1], t[2], q), cross(t[2], t[0], q));
    let neg = d0 < 0.0 || d1 < 0.0 || d2 < 0.0;
    let pos = d0 > 0.0 || d1 > 0.0 || d2 > 0.0;
    !(neg && pos)
}
