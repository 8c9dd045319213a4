//! Procedural meshes. All are counter-clockwise seen from the side their normals point to, have
//! unit normals, uvs in [0, 1] (v down) and tangents.
//!
//! Closed generators (box, sphere) produce bit-identical positions wherever two faces meet, so
//! [`Mesh::is_closed_manifold`] (which welds by exact position) sees them as closed.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::mesh::Mesh;

/// Largest accepted `subdivisions` of planes, quads and boxes (larger values are clamped).
pub const MAX_SUBDIVISIONS: u32 = 512;
/// Largest accepted sphere `segments` (larger values are clamped).
pub const MAX_SEGMENTS: u32 = 2048;
/// Largest accepted sphere `rings` (larger values are clamped).
pub const MAX_RINGS: u32 = 1024;

/// Appends a `(nu+1) × (nv+1)`-vertex grid: `pos(i, j)` for i along the face's "right", j along
/// its "up" (right × up = normal, so the triangles are counter-clockwise seen from the normal).
/// uv = (i/nu, 1 − j/nv): the image's top row lies at j = nv.
fn push_grid(mesh: &mut Mesh, nu: u32, nv: u32, normal: Vec3, pos: impl Fn(u32, u32) -> Vec3) {
    let base = mesh.positions.len() as u32;
    for j in 0..=nv {
        for i in 0..=nu {
            mesh.positions.push(pos(i, j));
            mesh.normals.push(normal);
            mesh.uvs.push(Vec2::new(i as f32 / nu as f32, 1.0 - j as f32 / nv as f32));
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let a = base + j * row + i;
            let (b, c, d) = (a + 1, a + row + 1, a + row);
            mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
}

/// `lo + (hi − lo)·k/n`, computed so that k = 0 and k = n give exactly `lo` and `hi`.
fn lerp_exact(lo: f32, hi: f32, k: u32, n: u32) -> f32 {
    if k == 0 {
        lo
    } else if k >= n {
        hi
    } else {
        lo + (hi - lo) * (k as f32 / n as f32)
    }
}

/// Square grid in the xz-plane (y = 0) facing +y, centred on the origin: x ∈ ±size.x/2,
/// z ∈ ±size.y/2, `subdivisions` (1 to [`MAX_SUBDIVISIONS`]) cells per side. u grows with x, v with z.
pub fn plane(size: Vec2, subdivisions: u32) -> Mesh {
    let n = subdivisions.clamp(1, MAX_SUBDIVISIONS);
    let h = size * 0.5;
    let mut m = Mesh::default();
    // right = +x, up = −z: (+x) × (−z) = +y.
    push_grid(&mut m, n, n, Vec3::Y, |i, j| Vec3::new(lerp_exact(-h.x, h.x, i, n), 0.0, lerp_exact(h.y, -h.y, j, n)));
    m.compute_tangents();
    m
}

/// Parallelogram `corner + s·edge_u + t·edge_v` facing `normalize(edge_u × edge_v)`;
/// uv = (s, 1 − t). A degenerate (zero-area) quad gets normal +y.
pub fn quad(corner: Vec3, edge_u: Vec3, edge_v: Vec3, subdivisions: u32) -> Mesh {
    let n = subdivisions.clamp(1, MAX_SUBDIVISIONS);
    let normal = edge_u.cross(edge_v).try_normalize().unwrap_or(Vec3::Y);
    let mut m = Mesh::default();
    push_grid(&mut m, n, n, normal, |i, j| corner + edge_u * (i as f32 / n as f32) + edge_v * (j as f32 / n as f32));
    m.compute_tangents();
    m
}

/// Axis-aligned box centred on the origin, 6 separately-textured faces (uvs cover 0..1 on each,
/// upright for the side faces), each split into `subdivisions²` cells. Closed 2-manifold.
pub fn cuboid(size: Vec3, subdivisions: u32) -> Mesh {
    let n = subdivisions.clamp(1, MAX_SUBDIVISIONS);
    let h = (size * 0.5).to_array();
    // (normal axis, normal sign, right axis, right sign, up axis, up sign), right × up = normal.
    const FACES: [(usize, f32, usize, f32, usize, f32); 6] = [
        (0, 1.0, 2, -1.0, 1, 1.0),  // +x
        (0, -1.0, 2, 1.0, 1, 1.0),  // −x
        (1, 1.0, 0, 1.0, 2, -1.0),  // +y
        (1, -1.0, 0, 1.0, 2, 1.0),  // −y
        (2, 1.0, 0, 1.0, 1, 1.0),   // +z
        (2, -1.0, 0, -1.0, 1, 1.0), // −z
    ];
    let mut m = Mesh::default();
    for (na, ns, ra, rs, ua, us) in FACES {
        let mut normal = [0.0f32; 3];
        normal[na] = ns;
        // Every face computes a coordinate from the same integer lattice index along that axis,
        // so shared edges get bit-identical positions.
        let coord = |axis: usize, k: u32| lerp_exact(-h[axis], h[axis], k, n);
        push_grid(&mut m, n, n, Vec3::from(normal), |i, j| {
            let mut lattice = [0u32; 3];
            lattice[na] = if ns > 0.0 { n } else { 0 };
            lattice[ra] = if rs > 0.0 { i } else { n - i };
            lattice[ua] = if us > 0.0 { j } else { n - j };
            Vec3::new(coord(0, lattice[0]), coord(1, lattice[1]), coord(2, lattice[2]))
        });
    }
    m.compute_tangents();
    m
}

/// UV sphere centred on the origin: `segments` (≥ 3) slices around +y, `rings` (≥ 2) stacks from
/// the north pole (+y, v = 0) to the south pole (v = 1); u grows eastward, starting (u = 0) at
/// +x and reaching −z at u = 0.25. The seam column and the pole vertices are duplicated for uvs
/// but share exact positions, so the sphere is a closed 2-manifold. No degenerate triangles.
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let (segs, rings) = (segments.clamp(3, MAX_SEGMENTS), rings.clamp(2, MAX_RINGS));
    let mut m = Mesh::default();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segs {
            // The seam column reuses column 0's angle so its positions are identical.
            let phi = TAU * (s % segs) as f32 / segs as f32;
            let n = if r == 0 {
                Vec3::Y
            } else if r == rings {
                Vec3::NEG_Y
            } else {
                Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
            };
            m.positions.push(n * radius);
            m.normals.push(n);
            m.uvs.push(Vec2::new(s as f32 / segs as f32, r as f32 / rings as f32));
        }
    }
    let row = segs + 1;
    for r in 0..rings {
        for s in 0..segs {
            let a = r * row + s; // (r, s), top-left seen from outside
            let (b, c, d) = (a + row, a + row + 1, a + 1); // below, below-right, right
            if r != rings - 1 {
                m.indices.extend_from_slice(&[a, b, c]);
            }
            if r != 0 {
                m.indices.extend_from_slice(&[a, c, d]);
            }
        }
    }
    m.compute_tangents();
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::tests::assert_well_formed;

    /// Every triangle's winding agrees with its vertex normals, and those point away from `centre`.
    fn assert_outward(m: &Mesh, centre: Vec3) {
        for tri in m.triangles() {
            let [a, b, c] = tri.map(|i| m.positions[i]);
            let face_n = (b - a).cross(c - a);
            for i in tri {
                assert!(face_n.dot(m.normals[i]) > 0.0, "winding disagrees with normal");
            }
            assert!(face_n.dot((a + b + c) / 3.0 - centre) > 0.0, "face points inward");
        }
    }

    #[test]
    fn plane_counts_area_orientation() {
        let m = plane(Vec2::new(4.0, 2.0), 3);
        assert_eq!(m.vertex_count(), 16);
        assert_eq!(m.triangle_count(), 18);
        assert_well_formed(&m);
        assert!((m.area() - 8.0).abs() < 1e-4);
        assert_outward(&m, Vec3::new(0.0, -1.0, 0.0));
        assert!(!m.is_closed_manifold());
        assert_eq!(m.boundary_edge_count(), 12);
        assert_eq!(m.bounds(), Some((Vec3::new(-2.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 1.0))));
        // Tangent along +x (u), bitangent toward −z (up in the image): w = +1.
        assert!(m.tangents.iter().all(|t| (t.truncate() - Vec3::X).length() < 1e-5 && t.w == 1.0));
    }

    #[test]
    fn quad_faces_edge_cross_product() {
        let m = quad(Vec3::new(1.0, 2.0, 0.0), Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 3.0, 0.0), 2);
        assert_eq!((m.vertex_count(), m.triangle_count()), (9, 8));
        assert_well_formed(&m);
        assert!((m.area() - 6.0).abs() < 1e-4);
        assert!(m.normals.iter().all(|&n| (n - Vec3::X).length() < 1e-6));
        assert_outward(&m, Vec3::new(0.0, 3.0, -1.0));
    }

    #[test]
    fn box_is_closed_outward_and_has_right_area() {
        for n in [1u32, 4] {
            let size = Vec3::new(1.0, 2.0, 3.0);
            let m = cuboid(size, n);
            assert_eq!(m.vertex_count(), 6 * ((n + 1) * (n + 1)) as usize);
            assert_eq!(m.triangle_count(), 12 * (n * n) as usize);
            assert_well_formed(&m);
            assert!(m.is_closed_manifold(), "box with {n} subdivisions not closed");
            assert_outward(&m, Vec3::ZERO);
            assert!((m.area() - 2.0 * (2.0 + 3.0 + 6.0)).abs() < 1e-3);
            assert_eq!(m.bounds(), Some((-size * 0.5, size * 0.5)));
            assert!(m.tangents.iter().all(|t| t.w == 1.0));
        }
    }

    #[test]
    fn sphere_is_closed_outward_and_area_converges() {
        let m = sphere(2.0, 16, 8);
        assert_eq!(m.vertex_count(), 17 * 9);
        assert_eq!(m.triangle_count(), 2 * 16 * 7);
        assert_well_formed(&m);
        assert!(m.is_closed_manifold());
        assert_outward(&m, Vec3::ZERO);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((*p / 2.0 - *n).length() < 1e-5);
        }
        let fine = sphere(1.5, 256, 128);
        assert!(fine.is_closed_manifold());
        let exact = 4.0 * PI * 1.5 * 1.5;
        assert!((fine.area() - exact).abs() / exact < 0.01, "{} vs {exact}", fine.area());
        // Minimal sphere is still a closed manifold.
        assert!(sphere(1.0, 3, 2).is_closed_manifold());
    }

    #[test]
    fn sphere_uv_directions() {
        let m = sphere(1.0, 8, 4);
        // Vertex at u = 0.25 on the equator lies at −z.
        let idx = 2 * 9 + 2;
        assert!((m.positions[idx] - Vec3::NEG_Z).length() < 1e-6);
        assert_eq!(m.uvs[idx], Vec2::new(0.25, 0.5));
        // Equator tangents point along +u (eastward), bitangent toward the north pole (−v).
        let t = m.tangents[idx];
        assert!((t.truncate() - Vec3::NEG_X).length() < 1e-3, "{t}");
        assert!(m.normals[idx].cross(t.truncate()).dot(Vec3::Y) * t.w > 0.99);
    }
}
