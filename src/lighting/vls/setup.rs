//! VLS set-up (digest §1.4): for every segment, the ≤ K lights it will shade with, chosen once
//! at full intensity and kept whatever the intensities do at run time. Pure CPU; the method runs
//! it through the bake stage and its tests call it directly.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;

use crate::bake::{BakeData, Progress};
use crate::lighting::many_lights::geometry::{point_in_convex_polygon, segment_plane};
use crate::lighting::many_lights::occluders::clearance;
use crate::lighting::many_lights::{LightModel, ManyLight, Occluders, ScenePolygon, Segments};

/// Marks an empty slot of a segment's light set (fewer than K lights passed).
pub const EMPTY: u32 = u32::MAX;

/// How a segment's K lights are picked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// The thesis: by distance, the closest lights whose feeler is unblocked.
    Closest,
    /// By potential contribution at full intensity (spot cone and N·L aware), unblocked.
    Contribution,
}

/// The shadow feeler from a segment's point to a light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feeler {
    /// The thesis's: a plane intersection and a point-in-polygon test against every other
    /// polygon, O(segments × lights × polygons).
    Thesis,
    /// A ray cast over the reference renderer's BVH ([`Occluders`]).
    Bvh,
    /// No feeler at all (every light counts as unblocked): for measuring what shadows cost.
    None,
}

/// Where a segment's light sets are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Point {
    /// One set per segment, from its centroid (the thesis's "segment as a point").
    Centroid,
    /// One set per segment vertex (shared by the segments of a polygon meeting there), shaded
    /// per vertex and interpolated: OpenGL's per-vertex lighting, which the thesis drew with.
    Vertex,
}

/// What the set-up depends on besides the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetupParams {
    pub k: usize,
    pub selection: Selection,
    /// `closest` only: skip lights that cannot reach the segment's front (N·L ≤ 0 or outside
    /// the null cone), which the thesis's words ask for and its pseudocode omits.
    pub can_illuminate: bool,
    pub feeler: Feeler,
    /// The model `contribution` ranks by (and `can_illuminate` asks about the cone of).
    pub model: LightModel,
    pub point: Point,
}

/// Per point (segment or segment vertex, see [`Point`]), K light indices (into the scene's lights), [`EMPTY`] after the last.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightSets {
    pub k: usize,
    pub indices: Vec<u32>,
    /// Points where a light beyond the k kept would also have lit them (found among the next k
    /// candidates in order of preference): light the frame drops.
    pub crowded: u32,
}

impl LightSets {
    pub fn segments(&self) -> usize {
        self.indices.len().checked_div(self.k).unwrap_or(0)
    }

    /// The same sets `width` slots wide, `width` at least the most lights any set holds: the
    /// shader stops at the first empty slot, so only memory changes.
    fn narrowed(self, width: usize) -> LightSets {
        if width >= self.k || width == 0 {
            return self;
        }
        let indices = self
            .indices
            .chunks(self.k)
            .flat_map(|set| set[..width].iter().copied())
            .collect();
        LightSets {
            k: width,
            indices,
            crowded: self.crowded,
        }
    }

    /// The lights of segment `s`, in the order they were chosen.
    pub fn of(&self, s: usize) -> impl Iterator<Item = usize> + '_ {
        self.indices[s * self.k..(s + 1) * self.k]
            .iter()
            .take_while(|&&i| i != EMPTY)
            .map(|&i| i as usize)
    }
}

impl BakeData for LightSets {
    fn encode(&self) -> Vec<u8> {
        [self.k as u32, self.crowded]
            .into_iter()
            .chain(self.indices.iter().copied())
            .flat_map(u32::to_le_bytes)
            .collect()
    }
    fn decode(bytes: &[u8]) -> Option<Self> {
        if !bytes.len().is_multiple_of(4) || bytes.len() < 8 {
            return None;
        }
        let words: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        let (k, crowded) = (words[0] as usize, words[1]);
        let indices = words[2..].to_vec();
        (k > 0 && indices.len().is_multiple_of(k)).then_some(LightSets { k, indices, crowded })
    }
}

/// The thesis's feeler over the scene polygons, with the digest's corrections (§3.3 item 7):
/// the segment's own polygon and polygons coplanar with it are skipped, and crossings within
/// the scene's [`clearance`] of either end do not block (as for [`Occluders`], so both agree).
pub struct ThesisFeeler<'a> {
    polygons: &'a [ScenePolygon],
    clearance: f64,
}

impl<'a> ThesisFeeler<'a> {
    pub fn new(polygons: &'a [ScenePolygon]) -> Self {
        let corners = polygons.iter().flat_map(|q| q.polygon.vertices.iter().copied());
        ThesisFeeler {
            polygons,
            clearance: clearance(corners),
        }
    }

    /// Whether a polygon other than `own` (and its coplanar neighbours) lies between `p` and
    /// `light`.
    pub fn blocked(&self, own: usize, p: DVec3, light: DVec3) -> bool {
        let len = (light - p).length();
        if len <= 2.0 * self.clearance {
            return false;
        }
        let own_plane = self.polygons.get(own).map(|q| q.polygon.plane);
        for (i, q) in self.polygons.iter().enumerate() {
            if i == own || own_plane.is_some_and(|o| o.coplanar_facing(&q.polygon.plane).is_some()) {
                continue;
            }
            let Some(hit) = segment_plane(p, light, &q.polygon.plane) else {
                continue;
            };
            let t = (hit - p).length();
            if t < self.clearance || t > len - self.clearance {
                continue;
            }
            if point_in_convex_polygon(hit, &q.polygon.vertices, q.polygon.plane.normal) {
                return true;
            }
        }
        false
    }
}

/// The points the set-up chooses lights for, as (point, its polygon's normal, its polygon).
pub fn points(segments: &Segments, point: Point) -> Vec<(DVec3, DVec3, usize)> {
    match point {
        Point::Centroid => (0..segments.triangles.len())
            .map(|t| {
                (
                    segments.centroid(t),
                    segments.normals[segments.triangles[t][0] as usize],
                    segments.triangle_polygon[t] as usize,
                )
            })
            .collect(),
        Point::Vertex => (0..segments.positions.len())
            .map(|i| {
                (
                    segments.positions[i],
                    segments.normals[i],
                    segments.vertex_polygon[i] as usize,
                )
            })
            .collect(),
    }
}

/// Whether `light` can reach the front of a surface at `p` with normal `n`: N·L > 0 and inside
/// the null cone.
pub fn can_illuminate(light: &ManyLight, p: DVec3, n: DVec3) -> bool {
    let to_light = light.position - p;
    if n.dot(to_light) <= 0.0 {
        return false;
    }
    match light.cone {
        None => true,
        Some((_, null)) => {
            let d = (-to_light).normalize_or_zero();
            d.dot(light.direction) > null.cos()
        }
    }
}

/// Luminance-weighted potential contribution of `light` at full intensity (unit albedo), on the
/// better lit of the surface's two sides: the shader lights a surface from the viewer's side
/// (thin surfaces, and closed meshes seen from inside), so a light behind the polygon's normal
/// lights it for a viewer on that side and must be kept as forward and clustered keep it.
pub fn potential(model: &LightModel, light: &ManyLight, p: DVec3, n: DVec3) -> f64 {
    let side = |n: DVec3| {
        light
            .shade(model, p, n, DVec3::ONE)
            .dot(DVec3::new(0.2126, 0.7152, 0.0722))
    };
    side(n).max(side(-n))
}

/// The light sets of every segment (or segment vertex, per `params.point`). `polygons` are the
/// scene polygons the segments were built from (`segments.triangle_polygon` indexes them);
/// `occluders` is used by the BVH feeler.
pub fn select(
    polygons: &[ScenePolygon],
    segments: &Segments,
    lights: &[ManyLight],
    params: &SetupParams,
    occluders: Option<&Occluders>,
    progress: &mut Progress,
) -> LightSets {
    let points = points(segments, params.point);
    let count = points.len();
    let k = params.k.max(1);
    let mut indices = vec![EMPTY; count * k];
    let thesis = ThesisFeeler::new(polygons);
    let done = AtomicU64::new(0);
    let crowded = AtomicU64::new(0);
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(count.max(1));
    let chunk = count.div_ceil(threads).max(1);
    let cancel = progress.cancellation();
    std::thread::scope(|scope| {
        let mut handles = Vec::new();
        for (c, out) in indices.chunks_mut(chunk * k).enumerate() {
            let (thesis, done, crowded, points, cancel) = (&thesis, &done, &crowded, &points, &cancel);
            handles.push(scope.spawn(move || {
                for (j, slots) in out.chunks_mut(k).enumerate() {
                    // Cancelled: the bake stops after the loop and caches nothing.
                    if cancel.as_ref().is_some_and(|c| c.is_cancelled()) {
                        break;
                    }
                    let s = c * chunk + j;
                    let (p, n, own) = points[s];
                    let blocked = |l: &ManyLight| match params.feeler {
                        Feeler::Thesis => thesis.blocked(own, p, l.position),
                        Feeler::Bvh => occluders.is_some_and(|o| o.blocked(p, l.position)),
                        Feeler::None => false,
                    };
                    let (chosen, more) = choose(lights, params, p, n, k, blocked);
                    if more {
                        crowded.fetch_add(1, Ordering::Relaxed);
                    }
                    for (slot, l) in slots.iter_mut().zip(chosen) {
                        *slot = l as u32;
                    }
                    done.fetch_add(1, Ordering::Relaxed);
                }
            }));
        }
        // The caller's progress line, fed from the workers' count until all have finished.
        while !handles.iter().all(|h| h.is_finished()) {
            progress.update(done.load(Ordering::Relaxed), count as u64);
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    });
    progress.update(count as u64, count as u64);
    // As wide as the fullest set: a scene whose points each see a few lights pays for those few.
    let fullest = indices
        .chunks(k)
        .map(|set| set.iter().take_while(|&&i| i != EMPTY).count())
        .max()
        .unwrap_or(0);
    LightSets {
        k,
        indices,
        crowded: crowded.into_inner().min(u64::from(u32::MAX)) as u32,
    }
    .narrowed(fullest.max(1))
}

/// The ≤ k lights one point keeps, in the order of preference, feelers cast only until k pass;
/// and whether one more light would have passed: the next k candidates are tried after the k
/// kept (at most twice the feelers), so a point a crowd of lights reaches is told from one whose
/// other lights are all shadowed.
pub fn choose(
    lights: &[ManyLight],
    params: &SetupParams,
    p: DVec3,
    n: DVec3,
    k: usize,
    blocked: impl Fn(&ManyLight) -> bool,
) -> (Vec<usize>, bool) {
    let mut order: Vec<(f64, usize)> = match params.selection {
        Selection::Closest => lights
            .iter()
            .enumerate()
            .filter(|(_, l)| !params.can_illuminate || can_illuminate(l, p, n))
            .map(|(i, l)| (l.position.distance(p), i))
            .collect(),
        Selection::Contribution => lights
            .iter()
            .enumerate()
            .map(|(i, l)| (-potential(&params.model, l, p, n), i))
            .filter(|&(c, _)| c < 0.0)
            .collect(),
    };
    // Ties by index: the same scene always gives the same sets.
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut out = Vec::with_capacity(k);
    let mut past = 0;
    for (_, i) in order {
        if out.len() == k {
            if past == k {
                break;
            }
            past += 1;
            if !blocked(&lights[i]) {
                return (out, true);
            }
        } else if !blocked(&lights[i]) {
            out.push(i);
        }
    }
    (out, false)
}
