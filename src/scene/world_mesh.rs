//! World-level mesh sources: a compiled BSP world ([`crate::world`]) as scene geometry.
//!
//! `mesh = "bsp_rooms"` (generated rooms, corridors, doors and pillars, deterministic in `seed`)
//! and `mesh = "bsp_fig8c"` (the seed's Fig. 8(c) pillar room) expand, like `cornell_box`, into
//! one object per world material class (`<name>.floor`, `.ceiling`, `.wall`, `.pillar`,
//! `.corridor`), each a [`MeshSource::World`](super::MeshSource::World) holding the faces of that
//! class. Methods that need the world itself (the BSP tree, portals, PVS: the stencil shadow
//! volumes' caster selection) get the same compiled world from [`compiled`], which compiles each
//! level once per process.
//!
//! Axes: the world module is z up, scenes are y up; a world point `(x, y, z)` is the scene point
//! `(x, z, −y)` (a rotation, so handedness and face winding are kept), then the object's
//! translation. Faces keep their polygon winding (counter-clockwise seen from the empty side),
//! are fan-triangulated in face-id order, have flat normals, and planar texture coordinates of
//! one repeat per [`TEXTURE_METRES`] along the face's two dominant axes (v downward on walls).

use std::sync::{Arc, Mutex, OnceLock};

use glam::{DVec3, Vec2, Vec3};

use super::mesh::Mesh;
use crate::world::level_gen::{self, materials, RoomsParams};
use crate::world::{CompileError, CompiledWorld, FaceId, MaterialId};

/// Texture repeat length on world faces, metres.
pub const TEXTURE_METRES: f64 = 2.0;

/// Which world to build.
#[derive(Debug, Clone, PartialEq)]
pub enum WorldLevel {
    /// [`level_gen::generate_rooms`] with this seed and these parameters.
    Rooms { seed: u64, params: RoomsParams },
    /// [`level_gen::fig8c_case`]: the pillar room whose back face is outside the light's PVS.
    Fig8c,
}

impl WorldLevel {
    /// The mesh type name scenes use.
    pub fn mesh_name(&self) -> &'static str {
        match self {
            WorldLevel::Rooms { .. } => "bsp_rooms",
            WorldLevel::Fig8c => "bsp_fig8c",
        }
    }

    /// The light position the Fig. 8(c) case was built for (world coordinates), if this is it.
    pub fn fig8c(&self) -> Option<level_gen::Fig8Case> {
        matches!(self, WorldLevel::Fig8c).then(level_gen::fig8c_case)
    }
}

/// The material classes a world's faces carry, with the suffix of the object holding them.
pub const CLASSES: [(&str, MaterialId); 5] = [
    ("floor", materials::FLOOR),
    ("ceiling", materials::CEILING),
    ("wall", materials::WALL),
    ("pillar", materials::PILLAR),
    ("corridor", materials::CORRIDOR),
];

/// World (z up) to scene (y up) coordinates, before the object's translation.
pub fn world_to_scene(p: DVec3) -> Vec3 {
    Vec3::new(p.x as f32, p.z as f32, -p.y as f32)
}

/// Scene (y up, object space) to world (z up) coordinates: the inverse of [`world_to_scene`].
pub fn scene_to_world(p: Vec3) -> DVec3 {
    DVec3::new(f64::from(p.x), -f64::from(p.z), f64::from(p.y))
}

type Cache = Mutex<Vec<(WorldLevel, Arc<CompiledWorld>)>>;

/// The compiled world of `level`, compiled on first use and shared afterwards (compiling is
/// deterministic, so every user sees the same faces and ids).
pub fn compiled(level: &WorldLevel) -> Result<Arc<CompiledWorld>, CompileError> {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
    // A poisoned lock only means another thread panicked mid-insert; the list is still valid.
    let mut entries = cache.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, w)) = entries.iter().find(|(l, _)| l == level) {
        return Ok(w.clone());
    }
    let world = match level {
        WorldLevel::Rooms { seed, params } => level_gen::generate_rooms(*seed, params),
        WorldLevel::Fig8c => level_gen::fig8c_case().world,
    };
    let compiled = Arc::new(world.compile()?);
    entries.push((level.clone(), compiled.clone()));
    Ok(compiled)
}

/// Where one face's triangles lie in its class mesh's index list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceSpan {
    pub face: FaceId,
    /// First index (a multiple of 3) within the class mesh.
    pub first_index: u32,
    pub index_count: u32,
}

/// The faces of material `class`, in face-id order, as a mesh in scene axes (object space), and
/// where each face's triangles are.
pub fn class_mesh(world: &CompiledWorld, class: MaterialId) -> (Mesh, Vec<FaceSpan>) {
    let mut mesh = Mesh::default();
    let mut spans = Vec::new();
    for (id, face) in world.faces.iter().enumerate() {
        if face.material != class {
            continue;
        }
        let poly = &face.polygon;
        let n = poly.plane.normal;
        let base = mesh.positions.len() as u32;
        let first_index = mesh.indices.len() as u32;
        let (u_axis, v_axis) = planar_axes(n);
        for &p in &poly.vertices {
            mesh.positions.push(world_to_scene(p));
            mesh.normals.push(world_to_scene(n).normalize_or_zero());
            mesh.uvs.push(Vec2::new(
                (p.dot(u_axis) / TEXTURE_METRES) as f32,
                (p.dot(v_axis) / TEXTURE_METRES) as f32,
            ));
        }
        for k in 1..poly.vertices.len().saturating_sub(1) as u32 {
            mesh.indices.extend_from_slice(&[base, base + k, base + k + 1]);
        }
        spans.push(FaceSpan {
            face: id as FaceId,
            first_index,
            index_count: mesh.indices.len() as u32 - first_index,
        });
    }
    mesh.compute_tangents();
    (mesh, spans)
}

/// Texture axes (world coordinates) for a face with normal `n`: the two axes other than the
/// dominant one; on walls u runs horizontally and v downward.
fn planar_axes(n: DVec3) -> (DVec3, DVec3) {
    let a = n.abs();
    if a.z >= a.x && a.z >= a.y {
        (DVec3::X, DVec3::Y)
    } else if a.x >= a.y {
        (DVec3::Y * n.x.signum(), DVec3::NEG_Z)
    } else {
        (DVec3::NEG_X * n.y.signum(), DVec3::NEG_Z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_round_trip_and_keep_handedness() {
        let p = DVec3::new(1.5, -2.0, 3.25);
        assert_eq!(scene_to_world(world_to_scene(p)), p);
        let (x, y, z) = (
            world_to_scene(DVec3::X),
            world_to_scene(DVec3::Y),
            world_to_scene(DVec3::Z),
        );
        assert_eq!(z, Vec3::Y, "world up is scene up");
        assert!((x.cross(y) - z).length() < 1e-6, "a rotation, not a mirror");
    }

    #[test]
    fn class_meshes_cover_every_face_once_with_outward_winding() {
        let w = compiled(&WorldLevel::Fig8c).unwrap();
        let mut seen = vec![0; w.faces.len()];
        for (_, class) in CLASSES {
            let (mesh, spans) = class_mesh(&w, class);
            mesh.validate("test").unwrap();
            for s in &spans {
                seen[s.face as usize] += 1;
                let face = &w.faces[s.face as usize];
                assert_eq!(s.index_count as usize, 3 * (face.polygon.vertices.len() - 2));
                let normal = world_to_scene(face.polygon.plane.normal);
                for t in mesh.indices[s.first_index as usize..(s.first_index + s.index_count) as usize].chunks(3) {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                    let n = (b - a).cross(c - a);
                    assert!(n.dot(normal) > 0.0, "counter-clockwise seen from the empty side");
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
        // The cache hands out the same compiled world.
        assert!(Arc::ptr_eq(&w, &compiled(&WorldLevel::Fig8c).unwrap()));
    }
}
