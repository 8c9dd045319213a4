//! The ray-cast truth both systems are judged against, and VLS's shadow feeler when asked to
//! use it: every polygon fan-triangulated into the reference renderer's BVH, the segment
//! between two points tested for any hit strictly between them.

use glam::{DVec3, Vec3};

use crate::raytrace::bvh::Bvh;
use crate::world::Polygon;

pub struct Occluders {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
}

/// Distance kept clear at both ends of a shadow ray, world units: a receiver lies on its own
/// polygon and a light may sit on a wall. Far above f32 rounding at metre scale (~1e-7 m), far
/// below a modelled gap (the thesis's box floats "slightly" above its floor: 1 cm here).
pub const END_CLEARANCE: f64 = 1e-4;

impl Occluders {
    pub fn new<'a>(polygons: impl IntoIterator<Item = &'a Polygon>) -> Occluders {
        let mut triangles = Vec::new();
        for p in polygons {
            for k in 1..p.vertices.len().saturating_sub(1) {
                triangles.push([p.vertices[0], p.vertices[k], p.vertices[k + 1]].map(|v| v.as_vec3()));
            }
        }
        let bvh = Bvh::build(&triangles);
        Occluders { triangles, bvh }
    }

    /// Whether any polygon lies strictly between `a` and `b` (the ends' clearance excluded).
    pub fn blocked(&self, a: DVec3, b: DVec3) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 2.0 * END_CLEARANCE || self.triangles.is_empty() {
            return false;
        }
        let dir = d / len;
        let origin = a + dir * END_CLEARANCE;
        match self.bvh.closest_hit(&self.triangles, origin.as_vec3(), dir.as_vec3()) {
            Some((t, _)) => (t as f64) < len - 2.0 * END_CLEARANCE,
            None => false,
        }
    }
}
