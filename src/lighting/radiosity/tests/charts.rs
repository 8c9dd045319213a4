//! Chart grouping: the hashed lookup groups exactly as a scan of every chart does, with work
//! that grows with the triangle count, not its square.

use glam::DVec3;

use crate::lighting::lightmap::patches::{group_charts, Triangle};
use crate::world::level_gen::Rng;

/// The grouping by the definition: each triangle joins the first chart (in creation order)
/// that matches it, found by scanning them all.
fn grouped_by_scan(triangles: &[Triangle]) -> Vec<Vec<usize>> {
    let scale = triangles
        .iter()
        .flat_map(|t| t.p)
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()))
        .max(1.0);
    let mut charts: Vec<(DVec3, Vec<usize>)> = Vec::new();
    for (ti, t) in triangles.iter().enumerate() {
        let n = t.normal();
        if n == DVec3::ZERO {
            continue;
        }
        let same = charts.iter_mut().find(|(cn, members)| {
            let tc = &triangles[members[0]];
            tc.object == t.object
                && cn.dot(n) > 1.0 - 1e-4
                && (cn.dot(t.p[0]) - cn.dot(tc.p[0])).abs() < 1e-5 * scale
                && tc.albedo == t.albedo
                && tc.emission == t.emission
                && tc.sky == t.sky
                && tc.part == t.part
        });
        match same {
            Some((_, members)) => members.push(ti),
            None => charts.push((n, vec![ti])),
        }
    }
    charts.into_iter().map(|(_, m)| m).collect()
}

fn triangle(p: [DVec3; 3], object: usize, part: u64) -> Triangle {
    Triangle {
        p,
        object,
        albedo: DVec3::splat(0.5),
        emission: DVec3::ZERO,
        sky: false,
        part,
    }
}

/// Small triangles on `planes` random planes far from the origin, each plane's triangles
/// tilted and shifted by amounts around the grouping's tolerances (some just inside, some just
/// outside), over two objects and two wall sides.
fn near_coplanar(planes: usize, per_plane: usize, seed: u64) -> Vec<Triangle> {
    let mut rng = Rng::new(seed);
    let mut out = Vec::new();
    for _ in 0..planes {
        let n = DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5).normalize();
        let centre = DVec3::new(rng.unit(), rng.unit(), rng.unit()) * 40.0 - 20.0;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        for _ in 0..per_plane {
            // Tilts of up to twice the normal tolerance, shifts up to twice the offset's.
            let tilt = (u * (rng.unit() - 0.5) + v * (rng.unit() - 0.5)) * 0.04 * rng.unit().powi(4);
            let shift = (rng.unit() - 0.5) * 4e-4 * rng.unit().powi(2);
            let m = (n + tilt).normalize();
            let (a, b) = (m.any_orthonormal_vector(), m.cross(m.any_orthonormal_vector()));
            let at = centre + (u * (rng.unit() - 0.5) + v * (rng.unit() - 0.5)) * 6.0 + n * shift;
            let p = [at, at + a * 0.3, at + b * 0.3];
            out.push(triangle(p, (rng.unit() * 2.0) as usize, (rng.unit() * 2.0) as u64));
        }
    }
    out
}

/// A sphere's tessellation: every triangle its own plane (a curved mesh).
fn sphere(rings: usize) -> Vec<Triangle> {
    sphere_of(rings, 3.0)
}

pub(super) fn sphere_of(rings: usize, radius: f64) -> Vec<Triangle> {
    let at = |i: usize, j: usize| {
        let (th, ph) = (
            std::f64::consts::PI * i as f64 / rings as f64,
            std::f64::consts::TAU * j as f64 / (2 * rings) as f64,
        );
        DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * radius
    };
    let mut out = Vec::new();
    for i in 0..rings {
        for j in 0..2 * rings {
            let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            out.push(triangle([q[0], q[1], q[2]], 0, 0));
            out.push(triangle([q[0], q[2], q[3]], 0, 0));
        }
    }
    out
}

#[test]
fn the_hashed_grouping_is_the_scan_by_definition() {
    for tris in [near_coplanar(40, 30, 1), near_coplanar(300, 4, 2), sphere(24)] {
        let hashed: Vec<Vec<usize>> = group_charts(&tris).into_iter().map(|c| c.triangles).collect();
        let scanned = grouped_by_scan(&tris);
        // Both cases must exercise both outcomes: triangles joining charts and starting them.
        assert!(scanned.len() > 1 && scanned.len() < tris.len() || tris.len() > 2000);
        assert!(
            hashed == scanned,
            "{} triangles: {} charts hashed, {} scanned",
            tris.len(),
            hashed.len(),
            scanned.len()
        );
    }
}

/// The work is counted, not timed: how many charts a triangle is compared with. A scan of every
/// chart compares a sphere's 25,600 triangles with about 144 million (11,230 charts, each
/// triangle with all made before it); the hash with 2.2 each.
#[test]
fn grouping_compares_each_triangle_with_a_few_charts_not_all() {
    use crate::lighting::lightmap::patches::group_charts_counted;
    for rings in [40, 80] {
        let tris = sphere(rings);
        let (charts, compared) = group_charts_counted(&tris);
        let scan: usize = (0..tris.len()).map(|t| t * charts.len() / tris.len()).sum();
        println!(
            "{} triangles, {} charts: {compared} comparisons ({:.2} a triangle; a scan: about {scan})",
            tris.len(),
            charts.len(),
            compared as f64 / tris.len() as f64
        );
        assert!(charts.len() > tris.len() / 3);
        assert!(
            compared <= 4 * tris.len(),
            "{compared} comparisons for {} triangles",
            tris.len()
        );
    }
}

/// A floor of `n`×`n` unit quads (one chart) with a sphere of `rings` and `radius` on it (a chart
/// per quad).
fn floor_and_sphere(n: usize, rings: usize, radius: f64) -> Vec<Triangle> {
    let h = n as f64 / 2.0;
    let c = |x: f64, z: f64| DVec3::new(x - h, -radius, z - h);
    let mut out = vec![
        triangle([c(0.0, 0.0), c(0.0, n as f64), c(n as f64, n as f64)], 1, 0),
        triangle([c(0.0, 0.0), c(n as f64, n as f64), c(n as f64, 0.0)], 1, 0),
    ];
    if rings > 0 {
        out.extend(sphere_of(rings, radius));
    }
    out
}

/// Each quad (two triangles) of `tris` after the first two (the floor) its own object.
fn tiled(mut tris: Vec<Triangle>) -> Vec<Triangle> {
    for (i, t) in tris.iter_mut().enumerate().skip(2) {
        t.object = 2 + i / 2;
    }
    tris
}

#[test]
fn the_default_patch_size_keeps_the_patches_near_the_budget() {
    use crate::lighting::lightmap::patches::count;
    use crate::lighting::plan::{lightmap_patch_size, patch_size_for};
    let budget = 4096.0;
    // Large planar faces: the size from the area, as before.
    let floor = floor_and_sphere(20, 0, 3.0);
    let (size, why) = lightmap_patch_size(&floor, budget);
    assert_eq!(size, patch_size_for(400.0, budget), "{why}");
    // 791 charts a few patches wide beside the floor (the sphere's quads, each its own object,
    // as tiles are): the area's size makes over four times the budget, and a larger one fewer,
    // so the size grows until they are at most four times.
    let mixed = tiled(floor_and_sphere(20, 20, 4.0));
    let from_area = patch_size_for(mixed.iter().map(Triangle::area).sum(), budget);
    assert!(count(&mixed, from_area) > 4 * budget as u64);
    let (size, why) = lightmap_patch_size(&mixed, budget);
    let patches = count(&mixed, size);
    println!("{size} m: {patches} patches ({why})");
    assert!(
        size > from_area && patches <= 4 * budget as u64,
        "{size}: {patches} patches"
    );
    assert!(why.contains("grown from"), "{why}");
    // 3,000 tiles make about as many patches at any size: the size stays the area's (a larger
    // one would coarsen the floor for nothing), and the reason says why there are so many.
    let tiles = tiled(floor_and_sphere(20, 40, 3.0));
    let (size, why) = lightmap_patch_size(&tiles, budget);
    let from_area = patch_size_for(tiles.iter().map(Triangle::area).sum(), budget);
    println!("{size} m: {} patches ({why})", count(&tiles, size));
    assert_eq!(size, from_area, "{why}");
    assert!(
        why.contains("charts") && why.contains("not four times the budget"),
        "{why}"
    );
    // The same sphere as one surface: its 3,000 planar charts merge into curved ones within a
    // quarter patch of a plane, and at the area's size they make at most four times the budget
    // (a fifth of the tiles' patches).
    let curved = floor_and_sphere(20, 40, 3.0);
    let (size, why) = lightmap_patch_size(&curved, budget);
    let patches = count(&curved, size);
    println!("{size} m: {patches} patches ({why})");
    assert_eq!(size, from_area, "{why}");
    assert!(
        patches <= 4 * budget as u64 && patches * 5 < count(&tiles, size),
        "{patches} patches"
    );
}
