//! CaLight's surface-to-surface visibility matrix (the Ca3D-Engine thesis §3.3.1, digest §1.2 step A): for
//! every pair of charts NONE (they cannot exchange light: one lies wholly behind the other's
//! plane, or one is sky), FULL (nothing intrudes into the convex hull of the two, so no ray
//! between them can be blocked: the shooting skips its rays) or PARTIAL (ray-test each patch
//! pair). Symmetric, stored as CaLight's packed lower triangle of 2-bit entries.
//!
//! The document's first step starts PARTIAL only the pairs in each other's leaf PVS: where the scene
//! has a BSP world with a PVS ([`ChartPvs`]), pairs of charts no leaf of which sees a leaf of the
//! other start NONE; arbitrary static geometry has no PVS, and there every pair starts PARTIAL.

use glam::{DVec2, DVec3, Vec3};

use super::patches::{Chart, Patches, Triangle};
use crate::error::{Error, Result};
use crate::scene::Scene;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Vis {
    None = 0,
    Partial = 1,
    Full = 2,
}

pub struct Matrix {
    n: usize,
    /// Packed entries; `None` when the charts are too many for the matrix to pay
    /// ([`MAX_MATRIX_CHARTS`]): every pair of distinct charts is then PARTIAL.
    bits: Option<Vec<u8>>,
}

/// Charts over which the matrix is not built. It holds and classifies every pair, so its cost
/// grows with the square of the chart count, while a triangle soup has a chart per triangle: at
/// 55,000 charts (the Stanford bunny's planar ones) it would be 1.5 billion pairs and 380 MB. Without
/// it every pair is ray-tested (PARTIAL), which is what the matrix only saves: NONE pairs get
/// nothing from the form factor's cosines either, bar a corrected block square's overhang.
pub const MAX_MATRIX_CHARTS: usize = 4096;

/// Charts over which no pair is marked FULL: the intrusion test costs about 20 µs a pair (the
/// hull's faces of up to 24 points), so on a curved mesh of 3,777 charts, most pairs of them
/// facing, the matrix took 145 s, and at 793 charts 3.8 s (release build, 2-core AMD EPYC).
/// Over it the matrix keeps NONE, whose test is cheap, and leaves every other pair PARTIAL.
pub const MAX_FULL_CHARTS: usize = 1024;

/// Which charts may see each other by a leaf PVS: chart pairs (i, j) none of whose leaves sees
/// a leaf of the other are out. Conservative as the PVS is, and as the leaves a chart is given
/// are (every leaf its bounds reach).
#[derive(Clone, Debug)]
pub struct ChartPvs {
    n: usize,
    visible: Vec<bool>,
}

impl ChartPvs {
    /// From each chart's leaves and the leaf PVS `visible(a, b)`.
    pub fn new(leaves: &[Vec<u32>], visible: impl Fn(u32, u32) -> bool) -> ChartPvs {
        let n = leaves.len();
        let mut out = ChartPvs {
            n,
            visible: vec![true; n * n],
        };
        for i in 0..n {
            for j in 0..i {
                // A chart in no leaf (outside the world) is given every pair, as without a PVS.
                let seen = leaves[i].is_empty()
                    || leaves[j].is_empty()
                    || leaves[i].iter().any(|&a| leaves[j].iter().any(|&b| visible(a, b)));
                out.visible[i * n + j] = seen;
                out.visible[j * n + i] = seen;
            }
        }
        out
    }

    pub fn sees(&self, i: usize, j: usize) -> bool {
        self.visible[i * self.n + j]
    }
}

/// The scene's BSP world, if it has one, and where it sits (world point `w` is scene point
/// `world_to_scene(w) + translate`).
pub fn bsp_world(scene: &Scene) -> Result<Option<(std::sync::Arc<crate::world::CompiledWorld>, Vec3)>> {
    for obj in &scene.objects {
        if let crate::scene::MeshSource::World { level, .. } = &obj.mesh {
            let compiled = crate::scene::world_mesh::compiled(level).map_err(|e| {
                Error::Usage(format!(
                    "{}: {}: the world does not compile: {e}",
                    scene.source,
                    level.mesh_name()
                ))
            })?;
            return Ok(Some((compiled, obj.transform.w_axis.truncate())));
        }
    }
    Ok(None)
}

/// The charts' leaves in `world` (every empty leaf a chart's bounds reach, a hair enlarged so a
/// face on a leaf's boundary is in the leaf in front of it) and the world's leaf PVS over them:
/// the document's start of the surface-visibility matrix.
pub fn chart_pvs(
    p: &Patches,
    triangles: &[Triangle],
    world: &crate::world::CompiledWorld,
    translate: Vec3,
) -> ChartPvs {
    let to_world = |x: DVec3| crate::scene::world_mesh::scene_to_world(x.as_vec3() - translate);
    let leaves: Vec<Vec<u32>> = p
        .charts
        .iter()
        .map(|c| {
            let mut b = crate::world::Aabb::EMPTY;
            for q in c.triangles.iter().flat_map(|&t| triangles[t].p) {
                let w = to_world(q);
                b.min = b.min.min(w);
                b.max = b.max.max(w);
            }
            if c.triangles.is_empty() {
                return Vec::new();
            }
            let margin = 1e-3 * (b.max - b.min).max_element().max(1.0);
            b.min -= DVec3::splat(margin);
            b.max += DVec3::splat(margin);
            world.box_leaves(&b)
        })
        .collect();
    ChartPvs::new(&leaves, |a, b| world.is_visible(a, b))
}

/// The charts' leaf PVS where the scene is a BSP world with one; `None` for other geometry.
pub fn scene_chart_pvs(scene: &Scene, p: &Patches, triangles: &[Triangle]) -> Result<Option<ChartPvs>> {
    // It starts the matrix, and like it holds every pair.
    if p.charts.len() > MAX_MATRIX_CHARTS {
        return Ok(None);
    }
    Ok(bsp_world(scene)?.map(|(world, translate)| chart_pvs(p, triangles, &world, translate)))
}

/// A chart's polygon as the test sees it: the convex hull of its vertices (in its plane), its
/// plane, its triangles and bounds.
struct Surface {
    hull: Vec<DVec3>,
    normal: DVec3,
    offset: f64,
    sky: bool,
    triangles: Vec<usize>,
    lo: DVec3,
    hi: DVec3,
}

/// Hulls of two charts with more points than this together are left PARTIAL (the face search
/// is cubic in the point count); real charts (quads, BSP faces) have a handful.
const MAX_HULL_POINTS: usize = 24;

impl Matrix {
    pub fn len(&self) -> usize {
        self.n
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    fn index(i: usize, j: usize) -> usize {
        let (a, b) = if i >= j { (i, j) } else { (j, i) };
        a * (a + 1) / 2 + b
    }

    /// Whether the matrix was built (see [`MAX_MATRIX_CHARTS`]).
    pub fn is_built(&self) -> bool {
        self.bits.is_some()
    }

    pub fn get(&self, i: usize, j: usize) -> Vis {
        let Some(bits) = &self.bits else {
            return if i == j { Vis::None } else { Vis::Partial };
        };
        let k = Self::index(i, j);
        match (bits[k / 4] >> (2 * (k % 4))) & 3 {
            0 => Vis::None,
            1 => Vis::Partial,
            _ => Vis::Full,
        }
    }

    fn set(&mut self, i: usize, j: usize, v: Vis) {
        let k = Self::index(i, j);
        let shift = 2 * (k % 4);
        if let Some(bits) = &mut self.bits {
            bits[k / 4] = (bits[k / 4] & !(3 << shift)) | ((v as u8) << shift);
        }
    }

    /// Pairs (i ≤ j) in each state: (none, partial, full).
    pub fn counts(&self) -> (usize, usize, usize) {
        if self.bits.is_none() {
            return (self.n, self.n * self.n.saturating_sub(1) / 2, 0);
        }
        let mut c = (0, 0, 0);
        for i in 0..self.n {
            for j in 0..=i {
                match self.get(i, j) {
                    Vis::None => c.0 += 1,
                    Vis::Partial => c.1 += 1,
                    Vis::Full => c.2 += 1,
                }
            }
        }
        c
    }

    /// The matrix of `p`'s charts over the static `triangles` they were built from; `full`
    /// false leaves every visible pair PARTIAL (CaLight's `-NoFullVis`).
    pub fn build(triangles: &[Triangle], p: &Patches, full: bool) -> Matrix {
        Matrix::build_for(triangles, &p.charts, full)
    }

    /// [`Matrix::build`] from the charts alone.
    pub fn build_for(triangles: &[Triangle], charts: &[Chart], full: bool) -> Matrix {
        Matrix::build_in(triangles, charts, full, None)
    }

    /// [`Matrix::build_for`] started from a leaf PVS where there is one: pairs it rules out are
    /// NONE without the geometric tests.
    pub fn build_in(triangles: &[Triangle], charts: &[Chart], full: bool, pvs: Option<&ChartPvs>) -> Matrix {
        Matrix::build_up_to(triangles, charts, full, pvs, MAX_MATRIX_CHARTS)
    }

    /// [`Matrix::build_in`] where there are at most `max_charts` charts; over that, not built.
    pub fn build_up_to(
        triangles: &[Triangle],
        charts: &[Chart],
        full: bool,
        pvs: Option<&ChartPvs>,
        max_charts: usize,
    ) -> Matrix {
        let n = charts.len();
        if n > max_charts {
            crate::errln!(
                "light-map: {n} charts: over {max_charts} the surface-visibility matrix is not built, and every pair of patches is ray-tested"
            );
            return Matrix { n, bits: None };
        }
        if full && n > MAX_FULL_CHARTS {
            crate::errln!(
                "light-map: {n} charts: over {MAX_FULL_CHARTS} the surface-visibility matrix marks no pair FULL, and every visible pair of patches is ray-tested"
            );
        }
        let full = full && n <= MAX_FULL_CHARTS;
        let mut m = Matrix {
            n,
            bits: Some(vec![0; (n * (n + 1) / 2).div_ceil(4)]),
        };
        let test = Tester::of_charts(triangles, charts);
        for i in 0..n {
            for j in 0..=i {
                let v = match pvs {
                    Some(pvs) if pvs.n == n && !pvs.sees(i, j) => Vis::None,
                    _ => test.classify(i, j, full),
                };
                m.set(i, j, v);
            }
        }
        m
    }
}

/// The pairwise classification, exposed so that tests can check it in both orders.
pub struct Tester<'a> {
    triangles: &'a [Triangle],
    /// Over the triangles, so that a pair's intrusion test visits only those near the pair.
    bvh: crate::raytrace::bvh::Bvh,
    surfaces: Vec<Surface>,
    /// Distances below this (a millionth of the scene's extent) are contact, not intrusion.
    tol: f64,
}

impl<'a> Tester<'a> {
    pub fn new(triangles: &'a [Triangle], p: &Patches) -> Tester<'a> {
        Tester::of_charts(triangles, &p.charts)
    }

    pub fn of_charts(triangles: &'a [Triangle], charts: &[Chart]) -> Tester<'a> {
        let scale = triangles
            .iter()
            .flat_map(|t| t.p)
            .fold(0.0f64, |m, q| m.max(q.abs().max_element()))
            .max(1.0);
        let surfaces = charts
            .iter()
            .map(|c| {
                let pts: Vec<DVec3> = c.triangles.iter().flat_map(|&t| triangles[t].p).collect();
                let flat: Vec<DVec2> = pts.iter().map(|q| DVec2::new(q.dot(c.u), q.dot(c.v))).collect();
                let offset = c.offset;
                let hull = hull_2d(flat)
                    .into_iter()
                    .map(|f| c.normal * offset + c.u * f.x + c.v * f.y)
                    .collect();
                let lo = pts.iter().fold(DVec3::splat(f64::INFINITY), |a, &q| a.min(q));
                let hi = pts.iter().fold(DVec3::splat(f64::NEG_INFINITY), |a, &q| a.max(q));
                Surface {
                    hull,
                    normal: c.normal,
                    offset,
                    sky: c.sky,
                    triangles: c.triangles.clone(),
                    lo,
                    hi,
                }
            })
            .collect();
        let corners: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.p.map(|q| q.as_vec3())).collect();
        Tester {
            triangles,
            bvh: crate::raytrace::bvh::Bvh::build(&corners),
            surfaces,
            tol: 1e-6 * scale,
        }
    }

    pub fn classify(&self, i: usize, j: usize, full: bool) -> Vis {
        let (a, b) = (&self.surfaces[i], &self.surfaces[j]);
        let behind = |s: &Surface, o: &Surface| o.hull.iter().all(|q| s.normal.dot(*q) - s.offset <= self.tol);
        if i == j || a.sky || b.sky || behind(a, b) || behind(b, a) {
            return Vis::None;
        }
        if full && !self.intruded(a, b) {
            Vis::Full
        } else {
            Vis::Partial
        }
    }

    /// Whether a triangle of another chart reaches into the interior of the convex hull of `a`
    /// and `b` (conservative: too many points counts as intruded).
    fn intruded(&self, a: &Surface, b: &Surface) -> bool {
        let pts: Vec<DVec3> = a.hull.iter().chain(&b.hull).copied().collect();
        if pts.len() > MAX_HULL_POINTS {
            return true;
        }
        let (lo, hi) = (a.lo.min(b.lo) + self.tol, a.hi.max(b.hi) - self.tol);
        let own = |t: &usize| a.triangles.contains(t) || b.triangles.contains(t);
        let mut axes: Option<Axes> = None;
        // The hierarchy's boxes are f32: the query is widened by more than their rounding.
        let margin = DVec3::splat(1e-5 * (hi - lo).abs().max_element().max(self.tol * 1e6));
        let (qlo, qhi) = ((lo - margin).as_vec3(), (hi + margin).as_vec3());
        self.bvh.any_in_box(qlo, qhi, |ti| {
            let (ti, t) = (ti as usize, &self.triangles[ti as usize]);
            let (tlo, thi) = (t.p[0].min(t.p[1]).min(t.p[2]), t.p[0].max(t.p[1]).max(t.p[2]));
            if thi.cmplt(lo).any() || tlo.cmpgt(hi).any() || own(&ti) || t.area() <= 0.0 {
                return false;
            }
            let axes = axes.get_or_insert_with(|| hull_axes(&pts));
            !separated(&pts, &t.p, axes, self.tol)
        })
    }
}

/// What the separating-axis test needs of the hull of `pts`: its face normals (every plane
/// through three points with all points on one side) and the directions between point pairs (a
/// superset of the hull's edges, crossed with the triangle's edges by [`separated`]).
struct Axes {
    faces: Vec<DVec3>,
    edges: Vec<DVec3>,
}

fn hull_axes(pts: &[DVec3]) -> Axes {
    let mut axes = Axes {
        faces: Vec::new(),
        edges: Vec::new(),
    };
    let n = pts.len();
    for a in 0..n {
        for b in a + 1..n {
            let e = pts[b] - pts[a];
            if e.length_squared() > 0.0 {
                axes.edges.push(e);
            }
            for c in b + 1..n {
                let f = e.cross(pts[c] - pts[a]);
                if f.length_squared() <= 1e-24 * e.length_squared() * e.length_squared() {
                    continue;
                }
                let f = f.normalize();
                let d: Vec<f64> = pts.iter().map(|q| f.dot(*q - pts[a])).collect();
                let (mn, mx) = d
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
                if mn >= -1e-9 || mx <= 1e-9 {
                    axes.faces.push(f);
                }
            }
        }
    }
    axes
}

/// The separating-axis test with contact allowed: true when some axis puts the triangle and
/// the hull on two sides, overlapping by at most `tol`. The axes are the hull's face normals,
/// the triangle's normal and every edge direction of one crossed with one of the other, which
/// suffices for two convex polytopes (a superset of them only finds more separations that are
/// real).
fn separated(pts: &[DVec3], tri: &[DVec3; 3], axes: &Axes, tol: f64) -> bool {
    let apart = |axis: DVec3| {
        let len = axis.length();
        if len <= 1e-12 {
            return false;
        }
        let axis = axis / len;
        let (hl, hh) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| {
            (l.min(axis.dot(*q)), h.max(axis.dot(*q)))
        });
        let (tl, th) = tri.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| {
            (l.min(axis.dot(*q)), h.max(axis.dot(*q)))
        });
        th <= hl + tol || hh <= tl + tol
    };
    let edges = [tri[1] - tri[0], tri[2] - tri[1], tri[0] - tri[2]];
    if apart(edges[0].cross(edges[1])) {
        return true;
    }
    axes.faces.iter().any(|&f| apart(f)) || axes.edges.iter().any(|&h| edges.iter().any(|&e| apart(h.cross(e))))
}

/// Andrew's monotone chain: the convex hull, counter-clockwise, without collinear points.
fn hull_2d(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup_by(|a, b| (*a - *b).length_squared() < 1e-24);
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}
