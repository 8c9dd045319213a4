//! The ray-cast truth both systems are judged against, and VLS's shadow feeler when asked to
//! use it: every polygon fan-triangulated into the reference renderer's BVH, the segment
//! between two points tested for any hit strictly between them.

use glam::{DVec3, Vec3};

use crate::raytrace::bvh::Bvh;
use crate::world::Polygon;

pub struct Occluders {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
    clearance: f64,
}

/// Distance kept clear at both ends of a shadow ray in a scene of metres, world units: a
/// receiver lies on its own polygon and a light may sit on a wall. Far above f32 rounding at
/// metre scale (~1e-7 m), far below a modelled gap (the thesis's box floats "slightly" above
/// its floor: 1 cm here). [`clearance`] scales it for smaller and farther scenes.
pub const END_CLEARANCE: f64 = 1e-4;

/// The clearance for the polygons with corners `points`: [`END_CLEARANCE`], or under 1 m that
/// fraction of the scene's extent (a 3 mm model's gaps are smaller than 0.1 mm); and at least
/// four steps of an f32 position as far from the origin as the farthest corner (one step is
/// 2.4e-4 m at 3 km: a clearance under it starts the ray on the surface it leaves).
pub fn clearance(points: impl IntoIterator<Item = DVec3>) -> f64 {
    let (lo, hi) = points.into_iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    if !lo.is_finite() {
        return END_CLEARANCE;
    }
    let extent = (hi - lo).max_element();
    let reach = lo.abs().max(hi.abs()).max_element();
    let by_size = END_CLEARANCE * extent.clamp(1e-6, 1.0);
    by_size.max(4.0 * f64::from(f32::EPSILON) * reach)
}

impl Occluders {
    pub fn new<'a>(polygons: impl IntoIterator<Item = &'a Polygon>) -> Occluders {
        let mut triangles = Vec::new();
        let mut corners = Vec::new();
        for p in polygons {
            corners.extend_from_slice(&p.vertices);
            for k in 1..p.vertices.len().saturating_sub(1) {
                triangles.push([p.vertices[0], p.vertices[k], p.vertices[k + 1]].map(|v| v.as_vec3()));
            }
        }
        let bvh = Bvh::build(&triangles);
        let clearance = clearance(corners);
        Occluders {
            triangles,
            bvh,
            clearance,
        }
    }

    /// Whether any polygon lies strictly between `a` and `b` (the ends' clearance excluded).
    pub fn blocked(&self, a: DVec3, b: DVec3) -> bool {
        let d = b - a;
        let len = d.length();
        let clear = self.clearance;
        if len <= 2.0 * clear || self.triangles.is_empty() {
            return false;
        }
        let dir = d / len;
        let origin = a + dir * clear;
        match self.bvh.closest_hit(&self.triangles, origin.as_vec3(), dir.as_vec3()) {
            Some((t, _)) => (t as f64) < len - 2.0 * clear,
            None => false,
        }
    }
}
