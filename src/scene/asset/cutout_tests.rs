//! The cut against areas known in closed form: what is kept is exactly the covered cells' share
//! of each triangle, placed where the uvs say.

use glam::{Vec2, Vec3};

use super::cutout::{cut, Mask, CELL_BUDGET};
use crate::scene::mesh::Mesh;

/// A `size`-metre square in the xy-plane, uv = (x, y) / size over `repeats` copies of the
/// texture, as two triangles.
fn square(size: f32, repeats: f32) -> Mesh {
    let p = [
        Vec3::ZERO,
        Vec3::new(size, 0.0, 0.0),
        Vec3::new(size, size, 0.0),
        Vec3::new(0.0, size, 0.0),
    ];
    let mut m = Mesh {
        positions: p.to_vec(),
        normals: vec![Vec3::Z; 4],
        uvs: p.iter().map(|q| Vec2::new(q.x, q.y) / size * repeats).collect(),
        tangents: Vec::new(),
        indices: vec![0, 1, 2, 0, 2, 3],
    };
    m.compute_tangents();
    m
}

fn mask(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Mask {
    Mask::new(w, h, (0..w * h).map(|i| f(i % w, i / w)).collect()).unwrap()
}

/// Every kept triangle lies on covered texels (its centre's uv, read back from its position),
/// up to slivers where the cut grazes a cell's corner (their area summed, against a millionth),
/// and its uvs follow its position.
fn assert_kept_points_are_covered(m: &Mesh, size: f32, repeats: f32, covered: impl Fn(Vec2) -> bool) {
    let mut stray = 0.0;
    for t in m.triangles() {
        let [a, b, c] = t.map(|i| m.positions[i]);
        let centre = (a + b + c) / 3.0;
        let uv = Vec2::new(centre.x, centre.y) / size * repeats;
        if !covered(uv) {
            stray += 0.5 * (b - a).cross(c - a).length();
        }
        let uv_centre = (m.uvs[t[0]] + m.uvs[t[1]] + m.uvs[t[2]]) / 3.0;
        assert!(
            (uv_centre - uv).length() < 1e-4,
            "uvs follow positions: {uv_centre} vs {uv}"
        );
    }
    assert!(stray < 1e-6 * m.area(), "{stray} of {} lies on cut texels", m.area());
}

#[test]
fn half_a_texture_keeps_half_the_area() {
    let quad = square(2.0, 1.0);
    // Left half opaque, right half clear.
    let m = mask(8, 8, |x, _| if x < 4 { 1.0 } else { 0.0 });
    let (kept, report) = cut(&quad, &m, 0.5);
    assert!((kept.area() - 2.0).abs() < 1e-5, "area {}", kept.area());
    assert_eq!(report.cell_texels, 1);
    assert!(kept.positions.iter().all(|p| p.x <= 1.0 + 1e-6));
    assert!(kept.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    // Facing is kept: every triangle's normal is +z as the source's.
    for t in kept.triangles() {
        let [a, b, c] = t.map(|i| kept.positions[i]);
        assert!((b - a).cross(c - a).z > 0.0);
    }
}

#[test]
fn a_checkerboard_over_repeats_keeps_the_covered_cells() {
    let (size, repeats) = (3.0, 2.5);
    let quad = square(size, repeats);
    let m = mask(4, 4, |x, y| ((x + y) % 2) as f32);
    let (kept, _) = cut(&quad, &m, 0.5);
    // 2.5 repeats of a 4x4 board make 10x10 cells over the square: half of them kept.
    assert!((kept.area() - 0.5 * size * size).abs() < 1e-4, "area {}", kept.area());
    assert_kept_points_are_covered(&kept, size, repeats, |uv| {
        let t = (uv.rem_euclid(Vec2::ONE) * 4.0).floor();
        (t.x + t.y) as usize % 2 == 1
    });
    // A cutoff above every texel keeps nothing, one at or below every texel keeps everything.
    assert!(cut(&quad, &m, 1.5).0.indices.is_empty());
    assert!((cut(&quad, &m, 0.0).0.area() - size * size).abs() < 1e-4);
}

#[test]
fn a_disc_keeps_its_area_to_within_its_cells() {
    let quad = square(1.0, 1.0);
    let n = 64;
    let inside = |x: usize, y: usize| {
        let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) / n as f32 - 0.5;
        if c.length() < 0.4 {
            1.0
        } else {
            0.0
        }
    };
    let (kept, report) = cut(&quad, &mask(n, n, inside), 0.5);
    let disc = std::f32::consts::PI * 0.16;
    // The staircase edge stays within one 1/64 cell of the circle: its length times a cell.
    let bound = 2.0 * std::f32::consts::PI * 0.4 / n as f32;
    assert!(
        (kept.area() - disc).abs() < bound,
        "area {} against {disc}",
        kept.area()
    );
    assert_eq!(report.triangles_before, 2);
}

#[test]
fn a_large_footprint_is_read_at_a_coarser_level_within_the_budget() {
    // 64 repeats of a 256x256 texture: 268 million texel cells at level 0.
    let quad = square(1.0, 64.0);
    let m = mask(256, 256, |x, _| if x < 128 { 1.0 } else { 0.0 });
    let (kept, report) = cut(&quad, &m, 0.5);
    let cells = (64.0 * 256.0 / report.cell_texels as f64).powi(2);
    assert!(cells <= CELL_BUDGET, "{cells} cells at {} texels", report.cell_texels);
    assert!(report.cell_texels > 1);
    // The halves survive the box filter at this level exactly (the edge falls on cell borders).
    assert!((kept.area() - 0.5).abs() < 1e-3, "area {}", kept.area());
}

#[test]
fn a_triangle_without_uv_extent_is_kept_or_dropped_whole() {
    let mut quad = square(1.0, 1.0);
    quad.uvs = vec![Vec2::new(0.1, 0.1); 4];
    let left = mask(2, 1, |x, _| if x == 0 { 1.0 } else { 0.0 });
    assert!((cut(&quad, &left, 0.5).0.area() - 1.0).abs() < 1e-6);
    quad.uvs = vec![Vec2::new(0.9, 0.1); 4];
    assert!(cut(&quad, &left, 0.5).0.indices.is_empty());
}

#[test]
fn wild_uvs_are_not_walked_cell_by_cell() {
    // A sliver whose uvs run a trillion repeats along one row: its box holds far more cells than
    // the walk allows (walking them would take hours), so the texel under its centre decides.
    let mut sliver = square(1.0, 1.0);
    sliver.uvs = vec![
        Vec2::new(0.1, 0.1),
        Vec2::new(1e12, 0.1),
        Vec2::new(1e12, 0.1 + 1e-3),
        Vec2::new(0.1, 0.1 + 1e-3),
    ];
    let m = mask(2, 2, |x, y| if (x + y) % 2 == 0 { 1.0 } else { 0.0 });
    let (kept, report) = cut(&sliver, &m, 0.5);
    assert_eq!(report.whole_by_centre, 2, "{report:?}");
    assert!(kept.triangle_count() <= 2);
    assert!(kept.area() <= 1.0 + 1e-6);
}
