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
    /// runs v0 → v1 and `t_b` runs v1 → v0. Empty for open meshes.
    pub edges: Vec<[u32; 4]>,
    /// Whether the welded mesh is a closed, consistently oriented 2-manifold. If not, every
    /// triangle gets its own volume (correct for any triangle soup, at 4× the fill).
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
        Topology {
            positions,
            triangles,
            edges: if closed { edges } else { Vec::new() },
            closed,
        }
    }

    /// Volume triangles the silhouette pass writes per light (degenerate ones included).
    pub fn volume_triangles(&self) -> usize {
        if self.closed {
            2 * self.triangles.len() + 2 * self.edges.len()
        } else {
            8 * self.triangles.len()
        }
    }

    /// Work items of the silhouette pass: one per triangle, and one per edge when closed.
    pub fn items(&self) -> usize {
        self.triangles.len() + if self.closed { self.edges.len() } else { 0 }
    }
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
/// vertices, 3 per triangle, near caps with `w =` [`NEAR_CAP_W`], degenerate triangles as three
/// `(0, 0, 0, 1)`) of a mesh with
/// world-space `positions` for the homogeneous `light` ([`super::VolumeLight::homogeneous`]).
pub fn silhouette_volume(topo: &Topology, positions: &[Vec3], light: Vec4) -> Vec<Vec4> {
    let zero = [Vec4::W; 3];
    let mut out = Vec::with_capacity(3 * topo.volume_triangles());
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
                out.extend_from_slice(&zero);
                out.extend_from_slice(&zero);
            } else {
                out.extend_from_slice(&[cap(t[0]), cap(t[2]), cap(t[1])]);
                out.extend_from_slice(&[inf(t[0]), inf(t[1]), inf(t[2])]);
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
        for t in &topo.triangles {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let facing = (b - a).cross(c - a).dot(toward(a));
            if facing == 0.0 || !facing.is_finite() {
                out.extend(std::iter::repeat_n(Vec4::W, 24));
                continue;
            }
            // The dark orientation: as given if it faces away, reversed if it faces the light.
            let d = if facing > 0.0 { [a, c, b] } else { [a, b, c] };
            let near = d.map(|p| p.extend(1.0));
            let caps = d.map(|p| p.extend(NEAR_CAP_W));
            let far = d.map(beyond);
            out.extend_from_slice(&[caps[0], caps[2], caps[1]]);
            out.extend_from_slice(&far);
            for i in 0..3 {
                let j = (i + 1) % 3;
                out.extend_from_slice(&[near[i], near[j], far[j], near[i], far[j], far[i]]);
            }
        }
    }
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
    /// degenerate), for closed meshes and for each triangle of an open one.
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
            for tri_volume in v.chunks(24) {
                let (vol, closed) = signed_volume_and_closed(&apex(tri_volume, light));
                assert!(closed && vol > 0.0, "{vol} {closed}");
            }
        }
    }

    #[test]
    fn open_meshes_get_one_closed_volume_per_triangle() {
        let quad = generators::quad(
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, 0.0),
            1,
        );
        let topo = Topology::new(&quad);
        assert!(!topo.closed && topo.edges.is_empty());
        // From either side of the quad.
        for light in [Vec3::new(0.1, 3.0, 0.2), Vec3::new(0.1, -3.0, 0.2)] {
            let v = silhouette_volume(&topo, &topo.positions, light.extend(1.0));
            for tri_volume in v.chunks(24) {
                let (vol, closed) = signed_volume_and_closed(&finite(tri_volume, light, 20.0));
                assert!(closed && vol > 0.0);
            }
        }
    }
}
