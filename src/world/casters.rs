//! Which world faces the stencil shadow-volume path must extrude for a point light (the Ca3D-Engine thesis
//! §4.3.1, Fig. 8). Pure CPU set queries returning face ids:
//!
//! * (a) [`casters_naive`](CompiledWorld::casters_naive): every face;
//! * (b) [`casters_light_pvs`](CompiledWorld::casters_light_pvs): faces of the leaves in the
//!   light's PVS, within the light radius;
//! * (c) [`casters_with_pscs`](CompiledWorld::casters_with_pscs): (b) plus the seed's Potential
//!   Shadow-Casters Set.
//!
//! These letters are the issue's, not the seed's. The seed's approaches are, over the set (b):
//! its (a) the front-facing faces as independent casters ([`front_facing`]), its (b) the same
//! with shared edges, its (c) the *back-facing* faces ([`back_facing`]), which it chooses: for
//! each ray from the light that meets a solid, the face where it leaves the solid again is
//! back-facing, and an empty room has none. The weakness of its (c) is Fig. 8(c): a back-facing
//! face whose leaves are all outside the light's PVS can still shadow a receiver that is in it.
//! The PSCS repairs that: pyramids from the light over every front-facing (lit) face of the
//! PVS, and every back-facing face of the world that meets one is added.
//!
//! Scope of the repair: the pyramids stand on *world faces*, so the set is complete for world
//! receivers (tested against brute force). A receiver that is not a world face, such as an
//! entity in a leaf the light sees, can be shadowed along a ray that ends on a face outside the
//! PVS; such an entity needs pyramids over its own bounds as well.
//!
//! [`front_facing`]: CompiledWorld::front_facing
//! [`back_facing`]: CompiledWorld::back_facing

use glam::DVec3;

use super::polygon::{clip_points_front, Aabb, Plane};
use super::{CompiledWorld, FaceId, PLANE_EPSILON};

/// Slack of the pyramid test: touching a pyramid counts as meeting it, so the set errs towards
/// more casters (an extra caster costs fill rate; a missing one costs a shadow).
const PYRAMID_SLACK: f64 = 1e-6;

/// A pyramid with its apex at the light and a lit face as its base, as bounding planes whose
/// front side is the inside.
struct Pyramid {
    planes: Vec<Plane>,
    bounds: Aabb,
}

impl CompiledWorld {
    /// (a): every face of the world.
    pub fn casters_naive(&self) -> Vec<FaceId> {
        (0..self.faces.len() as FaceId).collect()
    }

    /// (b): the faces of the leaves in the PVS of the light's leaf whose bounds touch the light's
    /// sphere (a face outside it is unlit and casts into unlit space). Empty for a light inside
    /// solid. Ascending ids.
    pub fn casters_light_pvs(&self, light: DVec3, radius: f64) -> Vec<FaceId> {
        let leaf = self.leaf_of(light);
        let mut taken = vec![false; self.faces.len()];
        for l in self.visible_leaves(leaf) {
            for &f in &self.tree.leaves[l as usize].faces {
                taken[f as usize] |= self.faces[f as usize].bounds.touches_sphere(light, radius);
            }
        }
        (0..self.faces.len())
            .filter(|&f| taken[f])
            .map(|f| f as FaceId)
            .collect()
    }

    /// (c): (b) together with the Potential Shadow-Casters Set. Ascending ids.
    pub fn casters_with_pscs(&self, light: DVec3, radius: f64) -> Vec<FaceId> {
        let mut set = self.casters_light_pvs(light, radius);
        set.extend(self.potential_shadow_casters(light, radius));
        set.sort_unstable();
        set.dedup();
        set
    }

    /// The seed's Potential Shadow-Casters Set, verbatim: (1) the back-facing faces of (b);
    /// (2) pyramids with apex at the light over each front-facing face of (b); (3) every
    /// back-facing face of the *world* (within the radius) that meets any pyramid. Ascending.
    pub fn potential_shadow_casters(&self, light: DVec3, radius: f64) -> Vec<FaceId> {
        let in_pvs = self.casters_light_pvs(light, radius);
        let mut taken = vec![false; self.faces.len()];
        for &f in &self.back_facing(&in_pvs, light) {
            taken[f as usize] = true;
        }
        let pyramids: Vec<Pyramid> = self
            .front_facing(&in_pvs, light)
            .iter()
            .filter_map(|&f| self.pyramid(light, f))
            .collect();
        for (f, face) in self.faces.iter().enumerate() {
            if taken[f]
                || face.polygon.plane.distance(light) >= -PLANE_EPSILON
                || !face.bounds.touches_sphere(light, radius)
            {
                continue;
            }
            taken[f] = pyramids.iter().any(|p| {
                p.bounds.overlaps(&face.bounds) && {
                    let mut points = face.polygon.vertices.clone();
                    for plane in &p.planes {
                        points = clip_points_front(&points, plane, PYRAMID_SLACK);
                        if points.is_empty() {
                            break;
                        }
                    }
                    !points.is_empty()
                }
            });
        }
        (0..self.faces.len())
            .filter(|&f| taken[f])
            .map(|f| f as FaceId)
            .collect()
    }

    /// The faces of `faces` the light is behind (by more than the plane epsilon): the casters
    /// of the seed's approach (c). A light in a face's plane casts no volume from it.
    pub fn back_facing(&self, faces: &[FaceId], light: DVec3) -> Vec<FaceId> {
        self.facing(faces, |d| d < -PLANE_EPSILON, light)
    }

    /// The faces of `faces` the light is in front of: the lit receivers (and approach (a)'s
    /// casters).
    pub fn front_facing(&self, faces: &[FaceId], light: DVec3) -> Vec<FaceId> {
        self.facing(faces, |d| d > PLANE_EPSILON, light)
    }

    /// The ids of `faces` (unknown ids skipped) whose plane distance to the light passes `keep`.
    fn facing(&self, faces: &[FaceId], keep: impl Fn(f64) -> bool, light: DVec3) -> Vec<FaceId> {
        let distance = |f: FaceId| {
            self.faces
                .get(f as usize)
                .map(|face| face.polygon.plane.distance(light))
        };
        faces
            .iter()
            .copied()
            .filter(|&f| distance(f).is_some_and(&keep))
            .collect()
    }

    /// The pyramid from `light` over face `f` (which the light must be in front of).
    fn pyramid(&self, light: DVec3, f: FaceId) -> Option<Pyramid> {
        let base = &self.faces[f as usize].polygon;
        let center = base.center();
        let mut planes = vec![base.plane];
        let count = base.vertices.len();
        for i in 0..count {
            let side = Plane::from_points(light, base.vertices[i], base.vertices[(i + 1) % count])?;
            planes.push(if side.distance(center) < 0.0 {
                side.flipped()
            } else {
                side
            });
        }
        let mut bounds = base.bounds();
        bounds.include(light);
        Some(Pyramid {
            planes,
            bounds: bounds.expanded(PYRAMID_SLACK),
        })
    }
}
