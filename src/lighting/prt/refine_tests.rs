//! Longest-edge bisection: edges within the limit, area and orientation kept, no T-junction
//! (every edge of a closed box is held by exactly two triangles, across its creases too),
//! attributes interpolated, and the budget obeyed.

use std::collections::HashMap;

use glam::{Mat4, Vec2, Vec3};

use super::refine::{refine, Target};
use crate::scene::generators::cuboid;
use crate::scene::Mesh;

fn triangles(m: &Mesh) -> Vec<[Vec3; 3]> {
    m.indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize]))
        .collect()
}

fn area_vector(m: &Mesh) -> Vec3 {
    triangles(m)
        .iter()
        .map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]))
        .sum()
}

fn longest_edge(m: &Mesh, model: Mat4) -> f32 {
    triangles(m)
        .iter()
        .flat_map(|t| {
            (0..3).map(move |k| {
                model
                    .transform_point3(t[k])
                    .distance(model.transform_point3(t[(k + 1) % 3]))
            })
        })
        .fold(0.0, f32::max)
}

/// How many triangles hold each edge, by its endpoints' positions.
fn edge_use(m: &Mesh) -> HashMap<([u32; 3], [u32; 3]), usize> {
    let mut out = HashMap::new();
    for t in triangles(m) {
        for k in 0..3 {
            let (a, b) = (
                t[k].to_array().map(f32::to_bits),
                t[(k + 1) % 3].to_array().map(f32::to_bits),
            );
            *out.entry(if a <= b { (a, b) } else { (b, a) }).or_insert(0) += 1;
        }
    }
    out
}

/// A 4 m square in two triangles with texture coordinates over it.
fn square() -> Mesh {
    Mesh {
        positions: vec![Vec3::ZERO, Vec3::X * 4.0, Vec3::new(4.0, 0.0, 4.0), Vec3::Z * 4.0],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        tangents: Vec::new(),
        indices: vec![0, 2, 1, 0, 3, 2],
    }
}

#[test]
fn edges_end_within_the_limit_keeping_area_orientation_and_attributes() {
    let mesh = square();
    let model = Mat4::from_scale(Vec3::splat(0.5));
    let out = refine(
        &[Target {
            mesh: &mesh,
            model,
            max_edge: 0.3,
        }],
        usize::MAX,
    );
    let m = &out.meshes[0];
    assert!(!out.budget_spent);
    assert_eq!(out.added, m.positions.len() - 4);
    assert!(longest_edge(m, model) <= 0.3, "{}", longest_edge(m, model));
    assert!(longest_edge(&mesh, model) > 1.0);
    assert!(m.triangle_count() >= 2 * 36, "{} triangles", m.triangle_count());
    // The same area, every triangle facing as before (none flipped or degenerate).
    assert!(
        (area_vector(m) - area_vector(&mesh)).length() < 1e-3,
        "{:?}",
        area_vector(m)
    );
    for t in triangles(m) {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        assert!(n.y > 0.0 && n.length() > 1e-6, "{t:?}");
    }
    // No T-junction: inner edges are held twice, the square's sides once.
    for (e, n) in edge_use(m) {
        let on_side = |p: [u32; 3]| {
            let p = Vec3::from_array(p.map(f32::from_bits));
            p.x == 0.0 || p.x == 4.0 || p.z == 0.0 || p.z == 4.0
        };
        let side = on_side(e.0) && on_side(e.1) && {
            let (a, b) = (
                Vec3::from_array(e.0.map(f32::from_bits)),
                Vec3::from_array(e.1.map(f32::from_bits)),
            );
            a.x == b.x || a.z == b.z
        };
        assert_eq!(n, if side { 1 } else { 2 }, "{e:?}");
    }
    // Attributes follow the position: uv = position / 4 on this square.
    for (p, uv) in m.positions.iter().zip(&m.uvs) {
        assert!((Vec2::new(p.x, p.z) / 4.0 - *uv).length() < 1e-5, "{p} {uv}");
    }
    assert!(m.normals.iter().all(|n| *n == Vec3::Y));
}

/// A box's faces share positions but not vertices: after splitting, every edge of the closed
/// surface, its creases included, is still held by exactly two triangles.
#[test]
fn a_boxs_faces_stay_joined_at_its_creases() {
    let mesh = cuboid(Vec3::new(3.0, 0.2, 1.0), 1);
    assert!(edge_use(&mesh).values().all(|&n| n == 2));
    let out = refine(
        &[Target {
            mesh: &mesh,
            model: Mat4::IDENTITY,
            max_edge: 0.25,
        }],
        usize::MAX,
    );
    let m = &out.meshes[0];
    assert!(longest_edge(m, Mat4::IDENTITY) <= 0.25);
    let uses = edge_use(m);
    let bad: Vec<_> = uses.iter().filter(|(_, &n)| n != 2).collect();
    assert!(
        bad.is_empty(),
        "{} of {} edges open or T-joined: {bad:?}",
        bad.len(),
        uses.len()
    );
}

/// The longest edges go first, across meshes, until the budget; an unlimited mesh is left alone.
#[test]
fn the_budget_stops_it_and_the_longest_edges_went_first() {
    let (big, small) = (square(), square());
    let small_model = Mat4::from_scale(Vec3::splat(0.25));
    let targets = [
        Target {
            mesh: &big,
            model: Mat4::IDENTITY,
            max_edge: 0.1,
        },
        Target {
            mesh: &small,
            model: small_model,
            max_edge: 0.1,
        },
        Target {
            mesh: &big,
            model: Mat4::IDENTITY,
            max_edge: f32::INFINITY,
        },
    ];
    let out = refine(&targets, 8);
    assert!(out.budget_spent);
    assert!((8..10).contains(&out.added), "{}", out.added);
    // Eight splits leave the 4 m square's edges longer than the 1 m square's longest (1.41 m),
    // so the small square waited.
    assert!(longest_edge(&out.meshes[0], Mat4::IDENTITY) > 1.5);
    assert_eq!(out.meshes[1].positions.len(), 4, "the small square waited");
    assert_eq!(out.meshes[0].positions.len(), 4 + out.added);
    assert_eq!(out.meshes[2], big);
}
