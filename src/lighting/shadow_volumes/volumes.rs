//! Shadow-volume geometry, on the CPU: the per-polygon volumes of world casters (built once as
//! templates the vertex shader extrudes), the edge adjacency of entity meshes that the
//! silhouette compute pass reads, and a CPU mirror of that pass for tests.
//!
//! Every volume is a closed, outward-oriented (counter-clockwise seen from outside) surface
//! whose vertices are homogeneous: `w = 1` for points, `w = 0` for points at infinity, stored as
//! the direction away from the light. The near cap is always made of *dark* faces (facing away
//! from the light): a lit face is never part of a volume boundary, so lit surfaces cannot
//! shadow themselves through depth ties, and a dark face is unlit anyway (the light pass gives
//! no light to a surface whose geometric normal faces away from the light). The far cap is the
//! same dark faces projected to infinity, the sides are the dark region's boundary edges
//! extruded to infinity. z-fail counts these (Everitt & Kilgard); z-pass would need no caps but
//! uses the same geometry.

use std::collections::HashMap;

use glam::{Vec3, Vec4};

use crate::scene::Mesh;

/// The `w` of near-cap vertices: points (like `w = 1`) whose depth the vertex shader moves back
/// by [`NEAR_CAP_DEPTH_OFFSET`]. A lit surface lying on its own volume's near cap (a triangle of
/// an open mesh, two-sided) then tests as outside its volume instead of depending on rounding.
/// Only the caps move: the sides, which make the shadow's edges, stay exact. (Pushing the cap
/// away from the light in world space does not work: far from the camera one depth step is
/// larger than any sensible push — 13 cm at 330 m with a 5 cm near plane.)
pub const NEAR_CAP_W: f32 = 2.0;

/// Depth offset of near caps in normalised depth (2^-20, about 16 steps of a 32-bit float depth
/// near 1).
pub const NEAR_CAP_DEPTH_OFFSET: f32 = 1.0 / 1_048_576.0;

/// A world caster polygon's volume for any light behind its plane: `vertices` are a convex
/// polygon, counter-clockwise seen from the front (the side away from the light). The template
/// stores `w = 0` vertices as the plain position; the vertex shader subtracts the light.
/// 4n − 4 triangles: near cap (reversed fan), far cap (fan at infinity), 2 per edge.
pub fn polygon_volume_template(vertices: &[Vec3]) -> Vec<Vec4> {
    let n = vertices.len();
    let mut out = Vec::with_capacity(3 * (4 * n).saturating_sub(4));
    if n < 3 {
        return out;
    }
    let p = |i: usize| vertices[i].extend(1.0);
    let cap = |i: usize| vertices[i].extend(NEAR_CAP_W);
    let inf = |i: usize| vertices[i].extend(0.0);
    for k in 1..n - 1 {
        out.extend_from_slice(&[cap(0), cap(k + 1), cap(k)]);
    }
    for k in 1..n - 1 {
        out.extend_from_slice(&[inf(0), inf(k), inf(k + 1)]);
    }
    for i in 0..n {
        let j = (i + 1) % n;
        out.extend_from_slice(&[p(i), p(j), inf(j), p(i), inf(j), inf(i)]);
    }
    out
}

/// Resolves a template vertex for a light at `light`: `w = 0` becomes the direction from the
/// light (what `glsl/shadow_volumes/volume.vert` does); near-cap vertices keep their marker.
pub fn resolve_template(v: Vec4, light: Vec3) -> Vec4 {
    if v.w == 0.0 {
        (v.truncate() - light).extend(0.0)
    } else {
        v
    }
}

/// An entity mesh welded by position, with edge adjacency: what the silhouette pass reads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    /// Unique positions (object space).
    pub positions: Vec<Vec3>,
    /// Triangles over `positions`, as in the mesh (counter-clockwise from outside).
    pub triangles: Vec<[u32; 3]>,
    /// Closed meshes: every undirected edge once, as `[v0, v1, t_a, t_b]` where triangle `t_a`
    /// runs v0 → v1 and `t_b` runs v1 → v0. Open meshes: every edge exactly two triangles share
    /// as `[v0, v1, t_a, t_b]` with either running either way, and every other edge (a border,
    /// or one of three or more triangles) once per triangle, with `t_b =` [`NO_TRIANGLE`]; the
    /// records of two triangles come first.
    pub edges: Vec<[u32; 4]>,
    /// How many of `edges` have two triangles (all of a closed mesh's).
    pub shared_edges: usize,
    /// Whether the welded mesh is a closed, consistently oriented 2-manifold. If not, it casts
    /// from both sides: every triangle is a near cap, turned to face away from the light, and
    /// an edge gets a side only where the two triangles' turned windings do not cancel.
    pub closed: bool,
}

impl Topology {
    pub fn new(mesh: &Mesh) -> Topology {
        let weld = mesh.weld_map();
        let mut remap: HashMap<u32, u32> = HashMap::new();
        let mut positions = Vec::new();
        let mut index = |i: u32| -> u32 {
            let w = weld.get(i as usize).copied().unwrap_or(i);
            *remap.entry(w).or_insert_with(|| {
                positions.push(mesh.positions.get(w as usize).copied().unwrap_or(Vec3::ZERO));
                positions.len() as u32 - 1
            })
        };
        let mut triangles = Vec::with_capacity(mesh.triangle_count());
        for t in mesh.indices.chunks_exact(3) {
            let tri = [index(t[0]), index(t[1]), index(t[2])];
            // Degenerate after welding: no area, no volume (and it would break the manifold).
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                triangles.push(tri);
            }
        }
        let (edges, closed) = adjacency(&triangles);
        let (edges, shared_edges) = if closed {
            let n = edges.len();
            (edges, n)
        } else {
            open_edges(&triangles)
        };
        Topology {
            positions,
            edges,
            shared_edges,
            triangles,
            closed,
        }
    }

    /// Volume triangles the silhouette pass may write per light: the room it keeps (a slot for
    /// every cap and side, whether drawn or not).
    pub fn volume_triangles(&self) -> usize {
        2 * self.triangles.len() + self.edge_triangles(self.edges.len())
    }

    /// Output triangles of the first `e` edge slots: one side quad per edge, but two for an open
    /// mesh's edge of two triangles (both sides are drawn where the sheet folds over itself as
    /// the light sees it). A soup of separate triangles takes 8 per triangle, as a closed
    /// volume each would.
    pub fn edge_triangles(&self, e: usize) -> usize {
        if self.closed {
            2 * e
        } else {
            let shared = e.min(self.shared_edges);
            4 * shared + 2 * (e - shared)
        }
    }

    /// Work items of the silhouette pass: one per triangle and one per edge.
    pub fn items(&self) -> usize {
        self.triangles.len() + self.edges.len()
    }
}

/// The second triangle of an open mesh's edge record that has only one.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// An open mesh's edge records (see [`Topology::edges`]): those of two triangles, sorted, then
/// the others, sorted; and how many have two.
fn open_edges(triangles: &[[u32; 3]]) -> (Vec<[u32; 4]>, usize) {
    let mut sharing: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            sharing.entry((a.min(b), a.max(b))).or_default().push(t as u32);
        }
    }
    let (mut edges, mut single) = (Vec::new(), Vec::new());
    for ((a, b), ts) in sharing {
        match ts[..] {
            [t, u] => edges.push([a, b, t, u]),
            _ => single.extend(ts.iter().map(|&t| [a, b, t, NO_TRIANGLE])),
        }
    }
    edges.sort_unstable();
    single.sort_unstable();
    let shared = edges.len();
    edges.append(&mut single);
    (edges, shared)
}

/// Pairs each directed edge with its reverse. Closed iff every directed edge occurs once and
/// its reverse once.
fn adjacency(triangles: &[[u32; 3]]) -> (Vec<[u32; 4]>, bool) {
    let mut directed: HashMap<(u32, u32), (u32, u32)> = HashMap::new(); // edge → (triangle, count)
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let e = directed.entry((tri[k], tri[(k + 1) % 3])).or_insert((t as u32, 0));
            e.1 += 1;
        }
    }
    let mut closed = !triangles.is_empty();
    let mut edges = Vec::new();
    for (&(a, b), &(t, count)) in &directed {
        match directed.get(&(b, a)) {
            Some(&(u, 1)) if count == 1 => {
                if a < b {
                    edges.push([a, b, t, u]);
                }
            }
            _ => closed = false,
        }
    }
    edges.sort_unstable();
    (edges, closed)
}

/// CPU mirror of `glsl/shadow_volumes/silhouette.comp`: the volume triangles (as homogeneous
/// vertices, 3 per triangle, near caps with `w =` [`NEAR_CAP_W`]) of a mesh with world-space
/// `positions` for the homogeneous `light` ([`super::VolumeLight::homogeneous`]). Every slot is
/// kept in order, those with nothing to draw as degenerate triangles (three `(0, 0, 0, 1)`),
/// where the pass leaves them out (with a directional light's degenerate far caps and side
/// halves), and draws the rest in an order of its own.
pub fn silhouette_volume(topo: &Topology, positions: &[Vec3], light: Vec4) -> Vec<Vec4> {
    let zero = [Vec4::W; 3];
    // The sides first, then the caps, as the pass lays them out.
    let mut out = Vec::with_capacity(3 * topo.volume_triangles());
    let mut caps = Vec::with_capacity(6 * topo.triangles.len());
    let toward = |p: Vec3| light.truncate() - p * light.w;
    let beyond = |p: Vec3| (p * light.w - light.truncate()).extend(0.0);
    let lit = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        (b - a).cross(c - a).dot(toward(a)) > 0.0
    };
    let at = |i: u32| positions[i as usize].extend(1.0);
    let cap = |i: u32| positions[i as usize].extend(NEAR_CAP_W);
    let inf = |i: u32| beyond(positions[i as usize]);
    if topo.closed {
        for t in &topo.triangles {
            if lit(t) {
                caps.extend_from_slice(&zero);
                caps.extend_from_slice(&zero);
            } else {
                caps.extend_from_slice(&[cap(t[0]), cap(t[2]), cap(t[1])]);
                caps.extend_from_slice(&[inf(t[0]), inf(t[1]), inf(t[2])]);
            }
        }
        for e in &topo.edges {
            let (la, lb) = (lit(&topo.triangles[e[2] as usize]), lit(&topo.triangles[e[3] as usize]));
            // The dark triangle's direction along the edge.
            let (u, v) = match (la, lb) {
                (false, true) => (e[0], e[1]),
                (true, false) => (e[1], e[0]),
                _ => {
                    out.extend_from_slice(&zero);
                    out.extend_from_slice(&zero);
                    continue;
                }
            };
            out.extend_from_slice(&[at(u), at(v), inf(v), at(u), inf(v), inf(u)]);
        }
    } else {
        // +1 when the triangle turned to face away from the light runs the edge a → b, -1 when
        // it runs b → a, 0 when it has no volume (edge on to the light, or no triangle).
        let dark_direction = |t: u32, a: u32, b: u32| -> i32 {
            let Some(tri) = topo.triangles.get(t as usize) else {
                return 0;
            };
            let [p, q, r] = tri.map(|i| positions[i as usize]);
            let facing = (q - p).cross(r - p).dot(toward(p));
            if facing == 0.0 || !facing.is_finite() {
                return 0;
            }
            let runs = (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b);
            if runs != (facing > 0.0) {
                1
            } else {
                -1
            }
        };
        for t in &topo.triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let facing = (b - a).cross(c - a).dot(toward(a));
            if facing == 0.0 || !facing.is_finite() {
                caps.extend(std::iter::repeat_n(Vec4::W, 6));
                continue;
            }
            // The dark orientation: as given if it faces away, reversed if it faces the light.
            let d = if facing > 0.0 { [a, c, b] } else { [a, b, c] };
            let near = d.map(|p| p.extend(NEAR_CAP_W));
            caps.extend_from_slice(&[near[0], near[2], near[1]]);
            caps.extend_from_slice(&d.map(beyond));
        }
        for e in &topo.edges {
            let (da, db) = (dark_direction(e[2], e[0], e[1]), dark_direction(e[3], e[0], e[1]));
            // An edge of one triangle has one side slot.
            let slots = if e[3] == NO_TRIANGLE { 1 } else { 2 };
            for d in [da, db].into_iter().take(slots) {
                // Two turned triangles running the edge opposite ways share a side that cancels.
                if d == 0 || da == -db {
                    out.extend_from_slice(&zero);
                    out.extend_from_slice(&zero);
                    continue;
                }
                let (u, v) = if d > 0 { (e[0], e[1]) } else { (e[1], e[0]) };
                out.extend_from_slice(&[at(u), at(v), inf(v), at(u), inf(v), inf(u)]);
            }
        }
    }
    out.extend(caps);
    out
}

/// For tests: replaces points at infinity by points at distance `k` along their direction from
/// the light, making the volume finite so its closedness and orientation can be measured.
pub fn finite(volume: &[Vec4], light: Vec3, k: f32) -> Vec<Vec3> {
    volume
        .iter()
        .map(|v| {
            if v.w == 0.0 {
                light + v.truncate() * k
            } else {
                v.truncate()
            }
        })
        .collect()
}

/// Signed volume of a triangle list (positive when the triangles face outward) and whether its
/// non-degenerate triangles close up (every directed edge matched by its reverse, positions
/// compared exactly).
pub fn signed_volume_and_closed(tris: &[Vec3]) -> (f64, bool) {
    let mut volume = 0.0f64;
    let mut edges: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    for t in tris.chunks_exact(3) {
        let area = (t[1] - t[0]).cross(t[2] - t[0]).length();
        if area == 0.0 {
            continue;
        }
        let [a, b, c] = [t[0], t[1], t[2]].map(|p| p.as_dvec3());
        volume += a.dot(b.cross(c)) / 6.0;
        for k in 0..3 {
            let (u, v) = (key(t[k]), key(t[(k + 1) % 3]));
            *edges.entry((u, v)).or_insert(0) += 1;
            *edges.entry((v, u)).or_insert(0) -= 1;
        }
    }
    (volume, edges.values().all(|&n| n == 0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::generators;

    #[test]
    fn polygon_volumes_are_closed_and_outward_for_a_light_behind() {
        // A square facing +y (counter-clockwise seen from +y), the light below it.
        let square = [
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(-1.0, 0.0, -1.0),
        ];
        let n = (square[1] - square[0]).cross(square[2] - square[0]);
        assert!(n.y > 0.0);
        let light = Vec3::new(0.3, -4.0, 0.2);
        let t = polygon_volume_template(&square);
        assert_eq!(t.len(), 3 * (4 * 4 - 4));
        let resolved: Vec<Vec4> = t.iter().map(|&v| resolve_template(v, light)).collect();
        let (vol, closed) = signed_volume_and_closed(&finite(&resolved, light, 8.0));
        assert!(closed);
        // The frustum between the square (4 m from the light, area 4) and its image 8× farther
        // out (area 256), 28 m apart: h/3 · (A1 + A2 + √(A1·A2)).
        let expected = 28.0 / 3.0 * (4.0 + 256.0 + 32.0);
        assert!(
            vol > 0.0 && ((vol - expected) / expected).abs() < 1e-4,
            "{vol} vs {expected}"
        );
    }

    #[test]
    fn closed_mesh_silhouette_volumes_are_closed_and_outward() {
        for mesh in [
            generators::cuboid(Vec3::new(1.0, 2.0, 0.5), 2),
            generators::sphere(0.7, 12, 7),
        ] {
            let topo = Topology::new(&mesh);
            assert!(topo.closed);
            assert_eq!(topo.edges.len() * 2, topo.triangles.len() * 3);
            for light in [Vec3::new(3.0, 4.0, 1.0), Vec3::new(-0.2, 0.1, 5.0)] {
                let v = silhouette_volume(&topo, &topo.positions, light.extend(1.0));
                assert_eq!(v.len(), 3 * topo.volume_triangles());
                let (vol, closed) = signed_volume_and_closed(&finite(&v, light, 50.0));
                assert!(closed && vol > 0.0, "{vol} {closed}");
            }
        }
    }

    /// A directional light's volumes run to one point at infinity: with that point placed far
    /// along the direction the light travels, each is a closed, outward solid (the far caps are
    /// degenerate), for closed meshes and open ones.
    #[test]
    fn directional_volumes_close_at_one_point_at_infinity() {
        let travel = Vec3::new(0.3, -0.85, 0.2).normalize();
        let light = (-travel).extend(0.0);
        let apex = |v: &[Vec4], light: Vec4| -> Vec<Vec3> {
            let travel = -light.truncate();
            v.iter()
                .map(|p| {
                    if p.w == 0.0 {
                        assert!(
                            (p.truncate() - travel).length() < 1e-6,
                            "every point at infinity is the sun's"
                        );
                        travel * 50.0
                    } else {
                        p.truncate()
                    }
                })
                .collect()
        };
        for mesh in [
            generators::cuboid(Vec3::new(1.0, 2.0, 0.5), 2),
            generators::sphere(0.7, 12, 7),
        ] {
            let topo = Topology::new(&mesh);
            let v = silhouette_volume(&topo, &topo.positions, light);
            let (vol, closed) = signed_volume_and_closed(&apex(&v, light));
            assert!(closed && vol > 0.0, "{vol} {closed}");
        }
        let quad = generators::quad(
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, 0.0),
            1,
        );
        let topo = Topology::new(&quad);
        for light in [light, -light] {
            let v = silhouette_volume(&topo, &topo.positions, light);
            let (vol, closed) = signed_volume_and_closed(&apex(&v, light));
            assert!(closed && vol > 0.0, "{vol} {closed}");
        }
    }

    /// The finite signed volume of each triangle's own volume, summed: what an open mesh's
    /// volume must enclose when its triangles do not overlap as the light sees them, and at
    /// least as a count when they do (a fold's layers add).
    fn per_triangle_volumes(topo: &Topology, light: Vec3, k: f32) -> f64 {
        topo.triangles
            .iter()
            .map(|t| {
                let (edges, shared_edges) = open_edges(&[*t]);
                let alone = Topology {
                    positions: topo.positions.clone(),
                    triangles: vec![*t],
                    edges,
                    shared_edges,
                    closed: false,
                };
                signed_volume_and_closed(&finite(
                    &silhouette_volume(&alone, &alone.positions, light.extend(1.0)),
                    light,
                    k,
                ))
                .0
            })
            .sum()
    }

    /// Non-degenerate triangles in the edge slots (the sides, which come first).
    fn sides(topo: &Topology, volume: &[Vec4]) -> usize {
        volume[..volume.len() - 6 * topo.triangles.len()]
            .chunks_exact(3)
            .filter(|t| t.iter().any(|&v| v != Vec4::W))
            .count()
    }

    fn mesh(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Mesh {
        Mesh {
            positions: positions.iter().map(|&p| Vec3::from(p)).collect(),
            indices: triangles.concat(),
            ..Mesh::default()
        }
    }

    /// A flat sheet casts one volume, closed and outward from either side, equal to its
    /// triangles' volumes summed, with sides on its border only: inner edges carry no pair of
    /// coincident faces.
    #[test]
    fn an_open_sheet_has_sides_on_its_border_only() {
        let sheet = generators::quad(
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, 0.0),
            3,
        );
        let topo = Topology::new(&sheet);
        assert!(!topo.closed);
        assert_eq!(topo.triangles.len(), 18);
        let border = topo.edges.iter().filter(|e| e[3] == NO_TRIANGLE).count();
        assert_eq!(border, 12);
        assert_eq!(topo.shared_edges, topo.edges.len() - border);
        assert!(topo.edges[..topo.shared_edges].iter().all(|e| e[3] != NO_TRIANGLE));
        // Caps, two slots per inner edge, one per border edge: no more than a closed volume per
        // triangle would take, for a sheet or a soup of separate triangles.
        assert_eq!(topo.volume_triangles(), 2 * 18 + 4 * 21 + 2 * 12);
        assert!(topo.volume_triangles() <= 8 * 18);
        let soup = mesh(
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [3.0, 0.0, 0.0],
                [4.0, 0.0, 0.0],
                [3.0, 0.0, 1.0],
            ],
            &[[0, 2, 1], [3, 5, 4]],
        );
        assert_eq!(Topology::new(&soup).volume_triangles(), 8 * 2);
        for light in [Vec3::new(0.1, 3.0, 0.2), Vec3::new(0.1, -3.0, 0.2)] {
            let v = silhouette_volume(&topo, &topo.positions, light.extend(1.0));
            assert_eq!(v.len(), 3 * topo.volume_triangles());
            let (vol, closed) = signed_volume_and_closed(&finite(&v, light, 20.0));
            let expected = per_triangle_volumes(&topo, light, 20.0);
            assert!(closed && vol > 0.0, "{vol} {closed}");
            assert!(((vol - expected) / expected).abs() < 1e-4, "{vol} vs {expected}");
            assert_eq!(sides(&topo, &v), 2 * border, "two triangles per border edge");
        }
    }

    /// A sheet folded over itself as the light sees it (a roof lit from the side), one with a
    /// triangle wound the other way, and three fins on one edge: each casts a closed volume
    /// that counts every layer (the sum of its triangles' volumes).
    #[test]
    fn folded_inconsistent_and_non_manifold_sheets_count_every_layer() {
        let roof = [
            [-1.0, 0.0, -1.0],
            [-1.0, 0.0, 1.0],
            [0.0, 1.0, -1.0],
            [0.0, 1.0, 1.0],
            [1.0, 0.0, -1.0],
            [1.0, 0.0, 1.0],
        ];
        let cases = [
            ("roof", mesh(&roof, &[[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]])),
            (
                "roof with a reversed triangle",
                mesh(&roof, &[[0, 1, 3], [0, 2, 3], [2, 3, 5], [2, 5, 4]]),
            ),
            (
                "fins",
                mesh(
                    &[
                        [0.0, 0.0, -1.0],
                        [0.0, 0.0, 1.0],
                        [1.0, 0.5, 0.0],
                        [-1.0, 0.5, 0.0],
                        [0.0, -1.0, 0.0],
                    ],
                    &[[0, 1, 2], [1, 0, 3], [0, 1, 4]],
                ),
            ),
        ];
        // From the side, low: the roof's far slope lies behind its near one.
        for (name, m) in cases {
            let topo = Topology::new(&m);
            assert!(!topo.closed, "{name}");
            for light in [
                Vec3::new(-6.0, 0.6, 0.3),
                Vec3::new(0.2, 5.0, 0.3),
                Vec3::new(0.3, -4.0, -0.2),
            ] {
                let v = silhouette_volume(&topo, &topo.positions, light.extend(1.0));
                let (vol, closed) = signed_volume_and_closed(&finite(&v, light, 20.0));
                let expected = per_triangle_volumes(&topo, light, 20.0);
                assert!(closed && vol > 0.0, "{name} from {light}: {vol} {closed}");
                assert!(
                    ((vol - expected) / expected).abs() < 1e-4,
                    "{name} from {light}: {vol} vs {expected}"
                );
            }
        }
    }
}
