//! Ray casting through the BSP tree, front to back: the first solid leaf a ray enters is where it
//! hits, and the face it hits lies in the plane of the node it crossed to get there. Logarithmic
//! in the face count, as the seed's light-map sunlight and SH shadow feelers need.

use glam::DVec3;

use super::bsp::Child;
use super::{CompiledWorld, FaceId, NodeId};

/// The closest hit along `origin + t·dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// In units of `dir` (the distance if `dir` is unit length).
    pub t: f64,
    pub point: DVec3,
    /// The face hit; `None` only if the ray starts inside solid (then `t` is 0), or if rounding
    /// put the hit point outside every face of the crossed plane (not observed).
    pub face: Option<FaceId>,
}

/// Tolerance for "the hit point lies in this face" when naming the face hit.
const FACE_TOLERANCE: f64 = 1e-7;

impl CompiledWorld {
    /// The closest hit for `t` in `[0, max_t]`, or `None` if the ray stays in empty space.
    pub fn cast_ray(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<RayHit> {
        let root = self.tree.root?;
        if max_t.is_nan() || max_t < 0.0 {
            return None;
        }
        let (t, node) = self.trace(root, origin, dir, 0.0, max_t, None)?;
        let point = origin + dir * t;
        let face = node.and_then(|n| self.face_at(n, point, dir));
        Some(RayHit { t, point, face })
    }

    /// Whether solid lies strictly between `a` and `b`. Either end may lie on a face (a light
    /// on a wall, a receiver point): touching at the ends does not count.
    pub fn occluded(&self, a: DVec3, b: DVec3) -> bool {
        let length = a.distance(b);
        if length.is_nan() || length <= 2.0 * END_TOLERANCE {
            return false; // too short to hold anything
        }
        // Nudge the start off a surface it may lie on, towards b.
        let dir = (b - a) / length;
        let start = a + dir * END_TOLERANCE;
        let Some(root) = self.tree.root else {
            return false;
        };
        self.trace(root, start, dir, 0.0, length - 2.0 * END_TOLERANCE, None)
            .is_some()
    }

    /// The same as [`cast_ray`](Self::cast_ray) by testing every face: the reference for tests.
    pub fn cast_ray_brute_force(&self, origin: DVec3, dir: DVec3, max_t: f64) -> Option<RayHit> {
        let mut best: Option<RayHit> = None;
        for (i, f) in self.faces.iter().enumerate() {
            if let Some(t) = f.polygon.intersect_ray(origin, dir, 0.0, max_t) {
                if best.is_none_or(|b| t < b.t) {
                    best = Some(RayHit {
                        t,
                        point: origin + dir * t,
                        face: Some(i as FaceId),
                    });
                }
            }
        }
        best
    }

    /// The first solid leaf entered on `[t0, t1]`, with the node whose plane was crossed.
    fn trace(
        &self,
        child: Child,
        o: DVec3,
        dir: DVec3,
        t0: f64,
        t1: f64,
        entered: Option<NodeId>,
    ) -> Option<(f64, Option<NodeId>)> {
        let n = match child {
            Child::Leaf(l) => return self.tree.leaves[l as usize].solid.then_some((t0, entered)),
            Child::Node(n) => n,
        };
        let node = &self.tree.nodes[n as usize];
        let d0 = node.plane.distance(o + dir * t0);
        let d1 = node.plane.distance(o + dir * t1);
        if d0 >= 0.0 && d1 >= 0.0 {
            return self.trace(node.front, o, dir, t0, t1, entered);
        }
        if d0 < 0.0 && d1 < 0.0 {
            return self.trace(node.back, o, dir, t0, t1, entered);
        }
        // The signs differ, so the denominator is not zero. (max/min rather than clamp: no
        // panic on NaN input.)
        let tm = ((node.plane.dist - node.plane.normal.dot(o)) / node.plane.normal.dot(dir))
            .max(t0)
            .min(t1);
        let (near, far) = if d0 >= 0.0 {
            (node.front, node.back)
        } else {
            (node.back, node.front)
        };
        self.trace(near, o, dir, t0, tm, entered)
            .or_else(|| self.trace(far, o, dir, tm, t1, Some(n)))
    }

    /// The face of node `n` containing `point`: preferably one facing the ray, else the nearest.
    fn face_at(&self, n: NodeId, point: DVec3, dir: DVec3) -> Option<FaceId> {
        let faces = &self.tree.nodes[n as usize].faces;
        let containing = |f: &&FaceId| self.faces[**f as usize].polygon.contains_point(point, FACE_TOLERANCE);
        let facing = |f: &&FaceId| self.faces[**f as usize].polygon.plane.normal.dot(dir) < 0.0;
        faces
            .iter()
            .filter(containing)
            .find(facing)
            .or_else(|| faces.iter().find(containing))
            .or_else(|| {
                faces.iter().min_by(|a, b| {
                    let da = self.faces[**a as usize].polygon.distance_to_boundary(point);
                    let db = self.faces[**b as usize].polygon.distance_to_boundary(point);
                    da.total_cmp(&db)
                })
            })
            .copied()
    }
}

/// How close to an end point of [`CompiledWorld::occluded`] solid may start without counting.
const END_TOLERANCE: f64 = 1e-6;
