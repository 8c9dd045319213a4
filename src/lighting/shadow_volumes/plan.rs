//! What a frame draws, decided on the CPU: the faces and entities the camera's PVS keeps, and
//! per light the receivers it lights and the casters whose volumes it extrudes (seed §4.3.1,
//! §4.1.5). Pure CPU, so tests can assert the counts the GPU passes are built from.
//!
//! World coordinates here are the world module's (z up, f64); entities and lights arrive in
//! scene coordinates and are mapped with [`WorldFrame`].

use std::sync::Arc;

use glam::{DVec3, Mat4, Vec3, Vec4};

use super::config::{Casters, Config};
use super::volumes::Topology;
use crate::scene::world_mesh::{scene_to_world, world_to_scene};
use crate::scene::Animation;
use crate::world::polygon::{clip_points_front, Aabb, Plane};
use crate::world::{CompiledWorld, FaceId, LeafId};

/// Slack of the entity pyramids (as the world's PSCS): touching counts as meeting.
const PYRAMID_SLACK: f64 = 1e-6;

/// A compiled world placed in the scene: world point `p` is scene point `world_to_scene(p) + translate`.
#[derive(Clone)]
pub struct WorldFrame {
    pub world: Arc<CompiledWorld>,
    pub translate: Vec3,
}

impl WorldFrame {
    pub fn to_world(&self, p: Vec3) -> DVec3 {
        scene_to_world(p - self.translate)
    }

    pub fn to_scene(&self, p: DVec3) -> Vec3 {
        world_to_scene(p) + self.translate
    }
}

/// A light as the method uses it (scene coordinates): a point light, a spot light (one with a
/// cone), or a directional light (one with `toward`).
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeLight {
    pub name: String,
    /// Unused for a directional light.
    pub position: Vec3,
    /// W/sr, or a directional light's irradiance in W/m².
    pub intensity: Vec3,
    /// 0: infinite.
    pub radius: f32,
    pub spot: Option<Spot>,
    /// A directional light (the sun): the unit vector toward it. Its volumes are extruded along
    /// the direction it travels, to a single point at infinity, so they have no far cap.
    pub toward: Option<Vec3>,
}

impl VolumeLight {
    /// The light in homogeneous coordinates, as the silhouette pass takes it: `(position, 1)`,
    /// or `(toward, 0)` for a directional light, the point at infinity it shines from.
    pub fn homogeneous(&self) -> Vec4 {
        match self.toward {
            Some(t) => t.extend(0.0),
            None => self.position.extend(1.0),
        }
    }
}

/// A spot light's cone: its contribution is scaled by `brdf::spot_falloff` (the
/// forward method's), and its shadow volumes are those of a point light at its position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    /// Unit axis, the direction the light travels (scene space).
    pub direction: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl Spot {
    /// Whether the cone (apex `apex`) may meet the ball of centre `c` and radius `r`: false
    /// only when the ball lies wholly beyond the outer angle, where the falloff is 0. Nothing
    /// outside the cone receives light, and a caster outside it can only shadow points along
    /// rays from the apex through it, which are outside the cone too — so both can be culled.
    pub fn may_reach(&self, apex: Vec3, c: Vec3, r: f32) -> bool {
        let d = c - apex;
        let dist = d.length();
        if dist <= r {
            return true;
        }
        let angle = (d.dot(self.direction) / dist).clamp(-1.0, 1.0).acos();
        // A small slack keeps float rounding on the safe (drawn) side.
        angle <= self.cos_outer.clamp(-1.0, 1.0).acos() + (r / dist).asin() + 1e-4
    }

    /// [`Spot::may_reach`] for a box (its bounding ball).
    pub fn may_reach_box(&self, apex: Vec3, (lo, hi): (Vec3, Vec3)) -> bool {
        self.may_reach(apex, 0.5 * (lo + hi), 0.5 * (hi - lo).length())
    }
}

/// A scene object that is not part of the world: it receives light and casts volumes.
#[derive(Clone, Debug)]
pub struct Entity {
    /// Index into the scene's draws (= its object index).
    pub draw: usize,
    pub name: String,
    pub topology: Topology,
    /// Object-space bounds.
    pub bounds: (Vec3, Vec3),
    pub base: Mat4,
    pub animation: Option<Animation>,
    /// Its material's opacity: below 1 the entity is translucent — neither lit nor shadowing in
    /// the opaque path, drawn afterwards by the translucent path.
    pub opacity: f32,
}

impl Entity {
    pub fn transform_at(&self, t: f32) -> Mat4 {
        match &self.animation {
            Some(a) => a.transform_at(self.base, t),
            None => self.base,
        }
    }

    /// Scene-space bounds under `m`.
    pub fn world_bounds(&self, m: &Mat4) -> (Vec3, Vec3) {
        let (lo, hi) = self.bounds;
        let mut out = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let p = m.transform_point3(c);
            out = (out.0.min(p), out.1.max(p));
        }
        out
    }
}

/// Per light, what does not change while the light stands still: its receivers and casters
/// among the world's faces, before the camera's PVS and the entity pyramids.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightWorldSets {
    /// World position, leaf (None: inside solid or no world).
    pub leaf: Option<LeafId>,
    /// Front-facing faces the light can reach (light PVS, radius): the lit receivers.
    pub receivers: Vec<FaceId>,
    /// Back-facing faces of the caster strategy (radius applied).
    pub casters: Vec<FaceId>,
}

/// The effective culling radius (infinite without culling or without a radius).
pub fn culling_radius(config: &Config, light: &VolumeLight) -> f64 {
    if config.radius_culling && light.radius > 0.0 && light.toward.is_none() {
        f64::from(light.radius)
    } else {
        f64::INFINITY
    }
}

/// The world sets of one light under `config`.
pub fn light_world_sets(config: &Config, frame: &WorldFrame, light: &VolumeLight) -> LightWorldSets {
    let w = &frame.world;
    let p = frame.to_world(light.position);
    let r = culling_radius(config, light);
    let leaf = w.leaf_of(p);
    if w.is_solid(leaf) {
        return LightWorldSets {
            leaf: None,
            ..Default::default()
        };
    }
    let in_radius = |f: &FaceId| w.faces[*f as usize].bounds.touches_sphere(p, r);
    let all_in_radius: Vec<FaceId> = (0..w.faces.len() as FaceId).filter(in_radius).collect();
    let reachable = if config.pvs {
        w.casters_light_pvs(p, r)
    } else {
        all_in_radius.clone()
    };
    let candidates = match (config.casters, config.pvs) {
        (Casters::Naive, _) | (_, false) => all_in_radius,
        (Casters::Pvs, true) => reachable.clone(),
        (Casters::Pscs, true) => w.casters_with_pscs(p, r),
    };
    let mut receivers = w.front_facing(&reachable, p);
    let mut casters = w.back_facing(&candidates, p);
    receivers.retain(|&f| face_in_cone(config, frame, light, f));
    casters.retain(|&f| face_in_cone(config, frame, light, f));
    LightWorldSets {
        leaf: Some(leaf),
        receivers,
        casters,
    }
}

/// Whether world face `f` may be within the light's cone (always for a point light, and
/// without culling).
fn face_in_cone(config: &Config, frame: &WorldFrame, light: &VolumeLight, f: FaceId) -> bool {
    let Some(spot) = cone_culling(config, light) else {
        return true;
    };
    let b = &frame.world.faces[f as usize].bounds;
    let (a, c) = (frame.to_scene(b.min), frame.to_scene(b.max));
    spot.may_reach_box(light.position, (a.min(c), a.max(c)))
}

/// The light's cone when culling by it (with `radius_culling`, which it goes with: both only
/// drop what the light cannot reach).
pub fn cone_culling(config: &Config, light: &VolumeLight) -> Option<Spot> {
    light.spot.filter(|_| config.radius_culling)
}

/// One light's share of a frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightPlan {
    /// Index into the method's lights.
    pub light: usize,
    /// World faces lit (after the camera's PVS), ascending.
    pub receiver_faces: Vec<FaceId>,
    pub receiver_entities: Vec<usize>,
    /// World faces whose volumes are drawn, ascending.
    pub caster_faces: Vec<FaceId>,
    pub caster_entities: Vec<usize>,
    /// Back-facing faces the entity pyramids added to the strategy's set.
    pub added_by_entity_pyramids: usize,
    /// Translucent entities the light reaches, back to front (the translucent path's
    /// receivers; they are in neither `receiver_entities` nor `caster_entities`).
    pub translucent_receivers: Vec<usize>,
}

/// Everything one frame draws.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FramePlan {
    /// World faces the camera's PVS keeps (all without a PVS), ascending.
    pub visible_faces: Vec<FaceId>,
    pub visible_entities: Vec<usize>,
    /// Lights that light something visible, in light order.
    pub lights: Vec<LightPlan>,
    /// Entity transforms of this frame (scene space), by entity.
    pub entity_transforms: Vec<Mat4>,
    /// Visible translucent entities, back to front (not in `visible_entities`).
    pub translucent_entities: Vec<usize>,
}

/// The empty leaves an entity's box reaches: the leaves it is taken to occupy. The box is pulled
/// in by 1 mm first, so an entity resting on a floor or against a wall does not also count the
/// leaf on the plane's far side.
fn occupied_leaves(w: &CompiledWorld, b: &Aabb) -> Vec<LeafId> {
    let inner = b.expanded(-1e-3);
    w.box_leaves(if inner.is_empty() { b } else { &inner })
}

fn world_aabb(frame: &WorldFrame, (lo, hi): (Vec3, Vec3)) -> Aabb {
    let (a, b) = (frame.to_world(lo), frame.to_world(hi));
    Aabb {
        min: a.min(b),
        max: a.max(b),
    }
}

/// Bounding planes (front = inside) of the pyramid from `apex` over a convex polygon that faces
/// it, with the base's plane; `None` if degenerate.
fn pyramid(apex: DVec3, base: &[DVec3]) -> Option<(Vec<Plane>, Aabb)> {
    let center = base.iter().copied().sum::<DVec3>() / base.len() as f64;
    let base_plane = Plane::from_points(base[0], base[1], base[2])?;
    let base_plane = if base_plane.distance(apex) < 0.0 {
        base_plane.flipped()
    } else {
        base_plane
    };
    let mut planes = vec![base_plane];
    for i in 0..base.len() {
        let side = Plane::from_points(apex, base[i], base[(i + 1) % base.len()])?;
        planes.push(if side.distance(center) < 0.0 {
            side.flipped()
        } else {
            side
        });
    }
    let mut bounds = Aabb::from_points(base);
    bounds.include(apex);
    Some((planes, bounds.expanded(PYRAMID_SLACK)))
}

/// Back-facing world faces (within `r`) meeting a pyramid from the light over a face of the box
/// that faces the light: the casters that can shadow an entity inside the box (the world's PSCS
/// stands on world faces only).
fn entity_pyramid_casters(w: &CompiledWorld, light: DVec3, r: f64, b: &Aabb) -> Vec<FaceId> {
    if b.contains(light) {
        return Vec::new();
    }
    let (lo, hi) = (b.min, b.max);
    let corner = |x: bool, y: bool, z: bool| {
        DVec3::new(
            if x { hi.x } else { lo.x },
            if y { hi.y } else { lo.y },
            if z { hi.z } else { lo.z },
        )
    };
    let mut pyramids = Vec::new();
    for axis in 0..3 {
        for high in [false, true] {
            let outside = if high {
                light[axis] > hi[axis]
            } else {
                light[axis] < lo[axis]
            };
            if !outside {
                continue;
            }
            let quad: Vec<DVec3> = [(false, false), (true, false), (true, true), (false, true)]
                .iter()
                .map(|&(s, t)| {
                    let mut c = [false; 3];
                    c[axis] = high;
                    c[(axis + 1) % 3] = s;
                    c[(axis + 2) % 3] = t;
                    corner(c[0], c[1], c[2])
                })
                .collect();
            pyramids.extend(pyramid(light, &quad));
        }
    }
    let mut out = Vec::new();
    for (f, face) in w.faces.iter().enumerate() {
        if face.polygon.plane.distance(light) >= -crate::world::PLANE_EPSILON || !face.bounds.touches_sphere(light, r) {
            continue;
        }
        let meets = pyramids.iter().any(|(planes, bounds)| {
            bounds.overlaps(&face.bounds) && {
                let mut points = face.polygon.vertices.clone();
                for plane in planes {
                    points = clip_points_front(&points, plane, PYRAMID_SLACK);
                    if points.is_empty() {
                        break;
                    }
                }
                !points.is_empty()
            }
        });
        if meets {
            out.push(f as FaceId);
        }
    }
    out
}

/// Plans a frame: `sets[i]` are light `i`'s world sets (from [`light_world_sets`]; ignored
/// without a world), `camera` the eye (scene space), `t` the animation time. Translucent
/// entities are taken out of the opaque path (the seed's compromise: light shines through
/// them) and listed back to front for the translucent path.
pub fn plan_frame(
    config: &Config,
    world: Option<&WorldFrame>,
    sets: &[LightWorldSets],
    lights: &[VolumeLight],
    entities: &[Entity],
    camera: Vec3,
    t: f32,
) -> FramePlan {
    let mut plan = plan_all(config, world, sets, lights, entities, camera, t);
    if !entities.iter().any(|e| e.opacity < 1.0) {
        return plan;
    }
    let translucent = |e: &usize| entities[*e].opacity < 1.0;
    // Back to front by the distance of the bounding box's centre: one order per entity, which is
    // exact for disjoint panes stacked along the view and the usual approximation otherwise
    // (the world's faces are opaque, so the BSP order is not needed).
    let depth: Vec<f32> = entities
        .iter()
        .zip(&plan.entity_transforms)
        .map(|(e, m)| {
            let (lo, hi) = e.world_bounds(m);
            (0.5 * (lo + hi)).distance(camera)
        })
        .collect();
    let back_to_front = |list: &mut Vec<usize>| list.sort_by(|a, b| depth[*b].total_cmp(&depth[*a]).then(a.cmp(b)));
    plan.translucent_entities = plan.visible_entities.iter().copied().filter(translucent).collect();
    back_to_front(&mut plan.translucent_entities);
    plan.visible_entities.retain(|e| !translucent(e));
    for lp in &mut plan.lights {
        lp.translucent_receivers = lp.receiver_entities.iter().copied().filter(translucent).collect();
        back_to_front(&mut lp.translucent_receivers);
        lp.receiver_entities.retain(|e| !translucent(e));
        lp.caster_entities.retain(|e| !translucent(e));
    }
    plan
}

/// The frame's plan before translucent entities are set apart: what the eye sees and, per
/// light, its receivers and casters.
fn plan_all(
    config: &Config,
    world: Option<&WorldFrame>,
    sets: &[LightWorldSets],
    lights: &[VolumeLight],
    entities: &[Entity],
    camera: Vec3,
    t: f32,
) -> FramePlan {
    let entity_transforms: Vec<Mat4> = entities.iter().map(|e| e.transform_at(t)).collect();
    let entity_bounds: Vec<(Vec3, Vec3)> = entities
        .iter()
        .zip(&entity_transforms)
        .map(|(e, m)| e.world_bounds(m))
        .collect();
    let Some(frame) = world else {
        return plan_without_world(config, lights, &entity_bounds, entity_transforms);
    };
    let view = WorldView::new(config, frame, &entity_bounds, camera);
    let plans = lights
        .iter()
        .enumerate()
        .filter_map(|(i, light)| view.light_plan(sets.get(i)?, i, light))
        .collect();
    let visible_faces: Vec<FaceId> = (0..frame.world.faces.len() as FaceId)
        .filter(|&f| view.face_visible[f as usize])
        .collect();
    FramePlan {
        visible_faces,
        visible_entities: view.visible_entities,
        lights: plans,
        entity_transforms,
        ..Default::default()
    }
}

/// Whether an entity with world bounds `b` is within `r` of the light and inside its cone (a
/// directional light reaches everything).
fn in_reach(config: &Config, light: &VolumeLight, r: f64, b: (Vec3, Vec3)) -> bool {
    if light.toward.is_some() {
        return true;
    }
    let (lo, hi) = b;
    let nearest = light.position.clamp(lo, hi);
    f64::from(nearest.distance_squared(light.position)) <= r * r
        && cone_culling(config, light).is_none_or(|s| s.may_reach_box(light.position, b))
}

/// The plan with no world: every entity is drawn, lit within the radius and casts within it.
fn plan_without_world(
    config: &Config,
    lights: &[VolumeLight],
    entity_bounds: &[(Vec3, Vec3)],
    entity_transforms: Vec<Mat4>,
) -> FramePlan {
    let visible_entities: Vec<usize> = (0..entity_bounds.len()).collect();
    let plans = lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| {
            let r = culling_radius(config, l);
            let near: Vec<usize> = (0..entity_bounds.len())
                .filter(|&e| in_reach(config, l, r, entity_bounds[e]))
                .collect();
            (!near.is_empty()).then(|| LightPlan {
                light: i,
                receiver_entities: near.clone(),
                caster_entities: near,
                ..Default::default()
            })
        })
        .collect();
    FramePlan {
        visible_faces: Vec::new(),
        visible_entities,
        lights: plans,
        entity_transforms,
        ..Default::default()
    }
}

/// What the eye sees of a world frame, and where the entities are in it.
struct WorldView<'a> {
    config: &'a Config,
    frame: &'a WorldFrame,
    entity_bounds: &'a [(Vec3, Vec3)],
    /// Per entity: the leaves its bounds overlap.
    entity_leaves: Vec<Vec<LeafId>>,
    face_visible: Vec<bool>,
    visible_entities: Vec<usize>,
}

impl<'a> WorldView<'a> {
    fn new(config: &'a Config, frame: &'a WorldFrame, entity_bounds: &'a [(Vec3, Vec3)], camera: Vec3) -> Self {
        let w = &frame.world;
        let cam_leaf = w.leaf_of(frame.to_world(camera));
        // Without a PVS, or with the eye outside the world, everything is potentially visible.
        let cull = config.pvs && !w.is_solid(cam_leaf);
        let mut face_visible = vec![!cull; w.faces.len()];
        let mut leaf_visible = vec![!cull; w.leaves().len()];
        if cull {
            for l in w.visible_leaves(cam_leaf) {
                leaf_visible[l as usize] = true;
                for &f in &w.leaves()[l as usize].faces {
                    face_visible[f as usize] = true;
                }
            }
        }
        let entity_leaves: Vec<Vec<LeafId>> = entity_bounds
            .iter()
            .map(|&b| occupied_leaves(w, &world_aabb(frame, b)))
            .collect();
        let visible_entities: Vec<usize> = (0..entity_bounds.len())
            .filter(|&e| !cull || entity_leaves[e].iter().any(|&l| leaf_visible[l as usize]))
            .collect();
        WorldView {
            config,
            frame,
            entity_bounds,
            entity_leaves,
            face_visible,
            visible_entities,
        }
    }

    /// Light `i`'s plan from its world sets `s`: its visible receivers and its casters; `None`
    /// when it lights nothing visible or is outside the world.
    fn light_plan(&self, s: &LightWorldSets, i: usize, light: &VolumeLight) -> Option<LightPlan> {
        let (config, w) = (self.config, &self.frame.world);
        let light_leaf = s.leaf?;
        let r = culling_radius(config, light);
        let receiver_faces: Vec<FaceId> = s
            .receivers
            .iter()
            .copied()
            .filter(|&f| self.face_visible[f as usize])
            .collect();
        let receiver_entities: Vec<usize> = self
            .visible_entities
            .iter()
            .copied()
            .filter(|&e| in_reach(config, light, r, self.entity_bounds[e]))
            .filter(|&e| !config.pvs || self.entity_leaves[e].iter().any(|&l| w.is_visible(light_leaf, l)))
            .collect();
        if receiver_faces.is_empty() && receiver_entities.is_empty() {
            return None;
        }
        let mut caster_faces = s.casters.clone();
        let mut added = 0;
        if config.casters == Casters::Pscs && config.pvs {
            added = self.add_entity_pyramid_casters(light, r, &receiver_entities, &mut caster_faces);
        }
        let caster_entities: Vec<usize> = (0..self.entity_bounds.len())
            .filter(|&e| in_reach(config, light, r, self.entity_bounds[e]))
            .collect();
        Some(LightPlan {
            light: i,
            receiver_faces,
            receiver_entities,
            caster_faces,
            caster_entities,
            added_by_entity_pyramids: added,
            ..Default::default()
        })
    }

    /// Adds to `caster_faces` (kept sorted) the faces in the pyramids from the light to each
    /// receiving entity's box, within the cone; returns how many were added.
    fn add_entity_pyramid_casters(
        &self,
        light: &VolumeLight,
        r: f64,
        receiver_entities: &[usize],
        caster_faces: &mut Vec<FaceId>,
    ) -> usize {
        let (frame, w) = (self.frame, &self.frame.world);
        let p = frame.to_world(light.position);
        let mut added = 0;
        let mut taken = vec![false; w.faces.len()];
        for &f in caster_faces.iter() {
            taken[f as usize] = true;
        }
        for &e in receiver_entities {
            for f in entity_pyramid_casters(w, p, r, &world_aabb(frame, self.entity_bounds[e])) {
                if !taken[f as usize] && face_in_cone(self.config, frame, light, f) {
                    taken[f as usize] = true;
                    caster_faces.push(f);
                    added += 1;
                }
            }
        }
        caster_faces.sort_unstable();
        added
    }
}

/// Merges ascending `(first, count)` ranges that touch.
pub fn merge_ranges(ranges: impl IntoIterator<Item = (u32, u32)>) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = Vec::new();
    for (first, count) in ranges {
        if count == 0 {
            continue;
        }
        match out.last_mut() {
            Some(last) if last.0 + last.1 == first => last.1 += count,
            _ => out.push((first, count)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spot_cone_reaches_balls_that_meet_it_only() {
        let s = Spot {
            direction: Vec3::NEG_Y,
            cos_inner: 20f32.to_radians().cos(),
            cos_outer: 30f32.to_radians().cos(),
        };
        let apex = Vec3::new(0.0, 10.0, 0.0);
        // On the ground 10 m below: the outer edge is at 10 tan 30 = 5.77 m from the axis.
        assert!(s.may_reach(apex, Vec3::new(5.5, 0.0, 0.0), 0.0));
        assert!(!s.may_reach(apex, Vec3::new(6.0, 0.0, 0.0), 0.0));
        assert!(
            s.may_reach(apex, Vec3::new(6.0, 0.0, 0.0), 0.3),
            "a ball straddling the edge"
        );
        assert!(!s.may_reach(apex, Vec3::new(0.0, 12.0, 0.0), 1.0), "behind the light");
        assert!(s.may_reach(apex, Vec3::new(0.0, 10.5, 0.0), 1.0), "around the apex");
    }

    #[test]
    fn ranges_merge_only_when_contiguous() {
        assert_eq!(
            merge_ranges([(0, 3), (3, 6), (12, 3), (15, 0), (15, 3)]),
            vec![(0, 9), (12, 6)]
        );
    }
}
