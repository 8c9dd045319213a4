//! Form factors from a differential receiver to a patch (the Ca3D-Engine thesis §3, digest §1.2 step E).
//!
//! *Faithful*: CaLight's point-sampled `A·cos θ_i·cos θ_j / (π r²)` with its near-field clamp
//! (r² replaced by the patch size² when r is shorter than a patch), which does not converge to
//! the true value near the shooter and does not close energy. *Corrected*: the exact form factor
//! from a differential area to a polygon (Lambert's formula, the contour integral), which sums to
//! 1 over any set of polygons covering the receiver's hemisphere, so the solution's energy closes.

use glam::DVec3;

/// CaLight's point-sampled form factor from a differential receiver at `x` (normal `nx`) to a
/// patch of area `area` at `y` (normal `ny`): `area·cos·cos/(π·max(r², patch_size²))`, 0 when
/// either faces away.
pub fn point_sampled(x: DVec3, nx: DVec3, y: DVec3, ny: DVec3, area: f64, patch_size: f64) -> f64 {
    let d = y - x;
    let r2 = d.length_squared();
    if r2 <= 0.0 {
        return 0.0;
    }
    let dir = d / r2.sqrt();
    let (ci, cj) = (nx.dot(dir), -ny.dot(dir));
    if ci <= 0.0 || cj <= 0.0 {
        return 0.0;
    }
    area * ci * cj / (std::f64::consts::PI * r2.max(patch_size * patch_size))
}

/// The exact form factor from a differential area at `x` with normal `n` to the planar polygon
/// `corners` (any winding; the part of it below the receiver's plane is clipped away):
/// `F = 1/(2π) Σ_k γ_k · n·(R_k × R_{k+1})/|R_k × R_{k+1}|`, with γ_k the angle the edge subtends.
pub fn point_to_polygon(x: DVec3, n: DVec3, corners: &[DVec3]) -> f64 {
    let clipped = clip_below(x, n, corners);
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 0..clipped.len() {
        let a = (clipped[k] - x).normalize_or_zero();
        let b = (clipped[(k + 1) % clipped.len()] - x).normalize_or_zero();
        let c = a.cross(b);
        let len = c.length();
        if len < 1e-15 {
            continue;
        }
        let gamma = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += gamma * n.dot(c / len);
    }
    // The sign follows the winding; the magnitude is the form factor.
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

/// The polygon clipped to the half-space in front of the receiver's plane (Sutherland–Hodgman),
/// so that a patch straddling the plane counts only its visible part.
fn clip_below(x: DVec3, n: DVec3, corners: &[DVec3]) -> Vec<DVec3> {
    let side = |p: DVec3| n.dot(p - x);
    let mut out = Vec::with_capacity(corners.len() + 2);
    for k in 0..corners.len() {
        let (p, q) = (corners[k], corners[(k + 1) % corners.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp > 0.0 {
            out.push(p);
        }
        if (sp > 0.0) != (sq > 0.0) && (sp - sq).abs() > 0.0 {
            out.push(p + (q - p) * (sp / (sp - sq)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of side `side` at height `h` above the origin, facing down.
    fn square(side: f64, h: f64) -> [DVec3; 4] {
        let s = side / 2.0;
        [
            DVec3::new(-s, -s, h),
            DVec3::new(s, -s, h),
            DVec3::new(s, s, h),
            DVec3::new(-s, s, h),
        ]
    }

    /// The digest's unit test: a differential patch to a coaxial parallel square of side 2 at
    /// distance 1 is 0.554126.
    #[test]
    fn coaxial_square_exact_and_point_sampled() {
        let exact = point_to_polygon(DVec3::ZERO, DVec3::Z, &square(2.0, 1.0));
        assert!((exact - 0.554126).abs() < 1e-6, "{exact}");
        // The point-sampled sum over patches of size p converges to it (the digest's table:
        // 0.5659, 0.5631, 0.5564, 0.5545, 0.55414 for p = 1, 0.5, 0.25, 0.1, 0.02).
        let sum = |p: f64| {
            let n = (2.0 / p).round() as usize;
            let mut f = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let y = DVec3::new(-1.0 + (i as f64 + 0.5) * p, -1.0 + (j as f64 + 0.5) * p, 1.0);
                    f += point_sampled(DVec3::ZERO, DVec3::Z, y, -DVec3::Z, p * p, 0.0);
                }
            }
            f
        };
        let errors: Vec<f64> = [1.0, 0.5, 0.25, 0.1].iter().map(|&p| (sum(p) - exact).abs()).collect();
        for (p, want) in [(1.0, 0.5659), (0.5, 0.5631), (0.25, 0.5564), (0.1, 0.5545)] {
            assert!(
                (sum(p) - want).abs() < 6e-4,
                "p = {p}: {} against the digest's {want}",
                sum(p)
            );
        }
        // Second order: halving p divides the error by about 4.
        let order = (errors[1] / errors[2]).log2();
        assert!((1.7..2.3).contains(&order), "convergence order {order} ({errors:?})");
    }

    #[test]
    fn disk_and_clipping() {
        // A disk of radius R at height h: R²/(R² + h²); a 720-gon is within 2e-5 of it.
        for (r, h) in [(1.0, 1.0), (0.5, 2.0), (3.0, 0.7)] {
            let ring: Vec<DVec3> = (0..720)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 720.0;
                    DVec3::new(r * a.cos(), r * a.sin(), h)
                })
                .collect();
            let f = point_to_polygon(DVec3::ZERO, DVec3::Z, &ring);
            assert!((f - r * r / (r * r + h * h)).abs() < 2e-5, "R = {r}, h = {h}: {f}");
        }
        // A polygon entirely behind the receiver sees nothing; one crossing its plane only its
        // front half (a vertical square centred on the plane: half of the full-square value).
        assert_eq!(point_to_polygon(DVec3::ZERO, DVec3::Z, &square(2.0, -1.0)), 0.0);
        let wall = [
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(1.0, 1.0, -1.0),
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-1.0, 1.0, 1.0),
        ];
        let top = [
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-1.0, 1.0, 1.0),
        ];
        assert!(
            (point_to_polygon(DVec3::ZERO, DVec3::Z, &wall) - point_to_polygon(DVec3::ZERO, DVec3::Z, &top)).abs()
                < 1e-12
        );
        // The five inner faces of a unit cube around a receiver on the sixth add up to 1.
        let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let faces = [
            [
                c(-0.5, -0.5, 1.0),
                c(0.5, -0.5, 1.0),
                c(0.5, 0.5, 1.0),
                c(-0.5, 0.5, 1.0),
            ],
            [
                c(-0.5, -0.5, 0.0),
                c(0.5, -0.5, 0.0),
                c(0.5, -0.5, 1.0),
                c(-0.5, -0.5, 1.0),
            ],
            [c(-0.5, 0.5, 0.0), c(0.5, 0.5, 0.0), c(0.5, 0.5, 1.0), c(-0.5, 0.5, 1.0)],
            [
                c(-0.5, -0.5, 0.0),
                c(-0.5, 0.5, 0.0),
                c(-0.5, 0.5, 1.0),
                c(-0.5, -0.5, 1.0),
            ],
            [c(0.5, -0.5, 0.0), c(0.5, 0.5, 0.0), c(0.5, 0.5, 1.0), c(0.5, -0.5, 1.0)],
        ];
        let x = DVec3::new(0.2, -0.1, 0.0);
        let total: f64 = faces.iter().map(|f| point_to_polygon(x, DVec3::Z, f)).sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
    }
}
