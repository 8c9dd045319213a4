//! The thesis's geometric primitives (§1.1, §1.4) with the digest's corrections: the line–line
//! intersection by a choice of two axes, the segment–plane intersection with `n·q` (the thesis
//! prints `nDotL`), the cone of a spotlight, and the point-in-convex-polygon test by
//! dominant-axis projection and a crossing count on the positive half-axis with a half-open
//! vertex rule (the thesis counts edges that merely straddle the axis line).

use glam::DVec3;

use crate::world::Plane;

/// Tolerance of the "third axis" check and of parallel tests, in world units.
pub const EPSILON: f64 = 1e-9;

/// The intersection of the segments `p0–p1` and `q0–q1`, with the parameters `(point, s, t)`
/// along each (`point = p0 + s·(p1 − p0) = q0 + t·(q1 − q0)`), or `None` when they are
/// parallel, skew (they miss each other in the third axis) or meet outside either segment.
pub fn line_line(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> Option<(DVec3, f64, f64)> {
    let (u, v, w) = (p1 - p0, q1 - q0, p0 - q0);
    if u.cross(v).length_squared() <= EPSILON * EPSILON * u.length_squared() * v.length_squared() {
        return None;
    }
    // The (p, q) pair with the largest 2-D determinant: the lines are then as far as possible
    // from parallel in that plane, and r is the remaining axis.
    let pairs = [(0usize, 1usize, 2usize), (0, 2, 1), (1, 2, 0)];
    let (p, q, r) = pairs
        .into_iter()
        .max_by(|a, b| det(u, v, a.0, a.1).abs().total_cmp(&det(u, v, b.0, b.1).abs()))?;
    let d = det(u, v, p, q);
    // Solving p0 + s·u = q0 + t·v in the (p, q) plane.
    let s = (v[p] * w[q] - v[q] * w[p]) / d;
    let t = (u[p] * w[q] - u[q] * w[p]) / d;
    let scale = 1.0 + p0.abs().max_element().max(q0.abs().max_element());
    if ((p0[r] + s * u[r]) - (q0[r] + t * v[r])).abs() > 1e-7 * scale {
        return None;
    }
    let inside = |x: f64| (-EPSILON..=1.0 + EPSILON).contains(&x);
    (inside(s) && inside(t)).then_some((p0 + s * u, s, t))
}

fn det(u: DVec3, v: DVec3, p: usize, q: usize) -> f64 {
    u[p] * v[q] - u[q] * v[p]
}

/// Where the segment `q–r` crosses `plane` (`n·x = dist`), or `None` when it is parallel to the
/// plane or both ends are on the same side. The thesis's formula with its `nDotQ`, in the
/// `n·x − dist` convention of [`Plane`].
pub fn segment_plane(q: DVec3, r: DVec3, plane: &Plane) -> Option<DVec3> {
    let direction = q - r;
    let n_dot_d = plane.normal.dot(direction);
    if n_dot_d.abs() <= EPSILON * direction.length() {
        return None;
    }
    let (dq, dr) = (plane.distance(q), plane.distance(r));
    if dq * dr > 0.0 {
        return None;
    }
    Some(q + direction * (-dq / n_dot_d))
}

/// A cone from `apex` along the unit `axis`, of half-angle `spread` (radians): a spotlight.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub apex: DVec3,
    pub axis: DVec3,
    pub spread: f64,
}

/// A point asked about that lies behind the apex of a cone (the thesis's "error").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BehindApex;

impl Cone {
    /// Angle between `p − apex` and the axis, radians (0 for the apex itself).
    pub fn angle(&self, p: DVec3) -> f64 {
        let d = p - self.apex;
        let len = d.length();
        if len == 0.0 {
            return 0.0;
        }
        (d.dot(self.axis) / len).clamp(-1.0, 1.0).acos()
    }

    pub fn contains(&self, p: DVec3) -> bool {
        self.angle(p) < self.spread
    }

    /// `spread − angle(p)`: how far inside the cone's edge `p` is, radians; an error for a
    /// point behind the apex's plane, where the fall-off is meaningless.
    pub fn angle_to_edge(&self, p: DVec3) -> Result<f64, BehindApex> {
        if (p - self.apex).dot(self.axis) < 0.0 {
            return Err(BehindApex);
        }
        Ok(self.spread - self.angle(p))
    }
}

/// Whether `p`, on or near the plane of the convex polygon `vertices` with normal `normal`, is
/// inside it: project on the plane of the two axes other than the normal's largest, move `p`
/// to the origin and count the edges crossing the positive half of the first axis (half-open
/// in the second coordinate, so an edge through a vertex on the axis counts once). Odd means
/// inside (Jordan); a convex polygon crosses at most twice.
pub fn point_in_convex_polygon(p: DVec3, vertices: &[DVec3], normal: DVec3) -> bool {
    let a = normal.abs();
    let (i, j) = if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    };
    let mut crossings = 0u32;
    let count = vertices.len();
    for k in 0..count {
        let (v0, v1) = (vertices[k] - p, vertices[(k + 1) % count] - p);
        let (x0, y0, x1, y1) = (v0[i], v0[j], v1[i], v1[j]);
        // Half-open: an endpoint with y == 0 counts as above the axis.
        if (y0 >= 0.0) != (y1 >= 0.0) {
            let x = x0 + (0.0 - y0) * (x1 - x0) / (y1 - y0);
            if x > 0.0 {
                crossings += 1;
            }
        }
    }
    crossings % 2 == 1
}
