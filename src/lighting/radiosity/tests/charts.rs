//! Chart grouping: the hashed lookup groups exactly as a scan of every chart does, and in time
//! that grows with the triangle count, not its square.

use glam::DVec3;

use crate::lighting::lightmap::patches::{group_charts, Triangle};

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

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
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
    let mut rng = Rng(seed);
    let mut out = Vec::new();
    for _ in 0..planes {
        let n = DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5).normalize();
        let centre = DVec3::new(rng.next(), rng.next(), rng.next()) * 40.0 - 20.0;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        for _ in 0..per_plane {
            // Tilts of up to twice the normal tolerance, shifts up to twice the offset's.
            let tilt = (u * (rng.next() - 0.5) + v * (rng.next() - 0.5)) * 0.04 * rng.next().powi(4);
            let shift = (rng.next() - 0.5) * 4e-4 * rng.next().powi(2);
            let m = (n + tilt).normalize();
            let (a, b) = (m.any_orthonormal_vector(), m.cross(m.any_orthonormal_vector()));
            let at = centre + (u * (rng.next() - 0.5) + v * (rng.next() - 0.5)) * 6.0 + n * shift;
            let p = [at, at + a * 0.3, at + b * 0.3];
            out.push(triangle(p, (rng.next() * 2.0) as usize, (rng.next() * 2.0) as u64));
        }
    }
    out
}

/// A sphere's tessellation: every triangle its own plane (a curved mesh).
fn sphere(rings: usize) -> Vec<Triangle> {
    let at = |i: usize, j: usize| {
        let (th, ph) = (
            std::f64::consts::PI * i as f64 / rings as f64,
            std::f64::consts::TAU * j as f64 / (2 * rings) as f64,
        );
        DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * 3.0
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

#[test]
fn grouping_time_grows_with_the_triangle_count_not_its_square() {
    // A chart per quad of a sphere: a scan of every chart per triangle is quadratic.
    let (small, large) = (sphere(40), sphere(80));
    assert_eq!(large.len(), 4 * small.len());
    let fastest = |tris: &[Triangle]| {
        (0..3)
            .map(|_| {
                let start = std::time::Instant::now();
                assert!(group_charts(tris).len() > tris.len() / 3);
                start.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let (a, b) = (fastest(&small), fastest(&large));
    println!("{} triangles grouped in {a:.4} s, {} in {b:.4} s ({:.1}x)", small.len(), large.len(), b / a);
    assert!(b < 8.0 * a, "4x the triangles took {:.1}x the time", b / a);
}
