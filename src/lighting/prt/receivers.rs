//! What the transfer bakers see: every vertex of the scene's objects as a receiver (world
//! position and normal, the occluder set it is shadowed by), and each occluder set's triangles in
//! world space (Staniszewski 2005 §3.1, the occluded/occluding object system).

use glam::{DVec3, Mat4, Vec3};

use crate::error::{Error, Result};
use crate::scene::{Mesh, Scene};

/// Near and far of the visibility test: a hit counts only at a distance in (near, far) along
/// the ray (radial), or at a depth in (near, far) along the normal (planar, the document's
/// raster projection). `far = ∞` means unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    pub near: f64,
    pub far: f64,
}

impl Default for Clip {
    fn default() -> Clip {
        Clip {
            near: 1e-3,
            far: f64::INFINITY,
        }
    }
}

/// One occluder set: the objects that shadow its receivers, as world-space triangles. An empty
/// set means unshadowed (not even by the receiver itself).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccluderSet {
    /// Scene object indices.
    pub objects: Vec<usize>,
    pub triangles: Vec<[Vec3; 3]>,
}

/// Every receiver vertex, in the order of the scene's vertex buffer for the draws that are
/// objects (so a receiver's index plus its draw's offset is `gl_VertexIndex`).
#[derive(Clone, Debug, Default)]
pub struct Receivers {
    pub positions: Vec<DVec3>,
    /// Unit world-space normals.
    pub normals: Vec<DVec3>,
    /// Per receiver: its occluder set (index into `sets`).
    pub set: Vec<u32>,
    pub sets: Vec<OccluderSet>,
}

impl Receivers {
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Receivers at explicit points and normals, all in one occluder set made of `occluders`
    /// (tests and tools).
    pub fn explicit(points: &[(DVec3, DVec3)], occluders: Vec<[Vec3; 3]>) -> Receivers {
        Receivers {
            positions: points.iter().map(|p| p.0).collect(),
            normals: points.iter().map(|p| p.1.normalize()).collect(),
            set: vec![0; points.len()],
            sets: vec![OccluderSet {
                objects: Vec::new(),
                triangles: occluders,
            }],
        }
    }

    /// The receivers of the given set, as indices.
    pub fn of_set(&self, set: usize) -> Vec<usize> {
        (0..self.len()).filter(|&i| self.set[i] as usize == set).collect()
    }
}

/// Who shadows whom: per receiver object, `None` for every object (the default, the receiver
/// included), or the listed objects.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OccluderRules {
    /// (receiver object, its occluders).
    pub rules: Vec<(usize, Vec<usize>)>,
}

impl OccluderRules {
    /// Parses `receiver: occluder occluder …; receiver: …` with object names, `self` for the
    /// receiver itself and nothing after the colon for an unshadowed receiver; receivers not
    /// listed are shadowed by every object. An error is the message alone: the caller names the
    /// file, line and parameter.
    pub fn parse(text: &str, scene: &Scene) -> std::result::Result<OccluderRules, String> {
        let find = |name: &str| -> std::result::Result<usize, String> {
            scene.objects.iter().position(|o| o.name == name).ok_or_else(|| {
                let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
                format!("no object is called {name:?} (objects: {})", names.join(", "))
            })
        };
        let mut rules = Vec::new();
        for entry in text.split(';').map(str::trim).filter(|e| !e.is_empty()) {
            let (receiver, list) = entry
                .split_once(':')
                .ok_or_else(|| format!("{entry:?} is not `receiver: occluders…`"))?;
            let r = find(receiver.trim())?;
            if rules.iter().any(|(x, _): &(usize, Vec<usize>)| *x == r) {
                return Err(format!("{:?} is listed twice", receiver.trim()));
            }
            let mut occ = Vec::new();
            for name in list.split([',', ' ']).map(str::trim).filter(|n| !n.is_empty()) {
                let o = if name == "self" { r } else { find(name)? };
                if !occ.contains(&o) {
                    occ.push(o);
                }
            }
            occ.sort_unstable();
            rules.push((r, occ));
        }
        Ok(OccluderRules { rules })
    }

    /// The occluders of receiver object `o` among `all` objects.
    pub fn occluders_of(&self, o: usize, all: &[usize]) -> Vec<usize> {
        self.rules
            .iter()
            .find(|(r, _)| *r == o)
            .map_or_else(|| all.to_vec(), |(_, occ)| occ.clone())
    }
}

/// One object's mesh where it stands: the scene object, its placement and its mesh.
pub struct Placed<'a> {
    pub object: usize,
    pub model: Mat4,
    pub mesh: &'a Mesh,
}

/// The receivers and occluder sets of `objects` (in vertex-buffer order).
pub fn gather(objects: &[Placed<'_>], rules: &OccluderRules) -> Result<Receivers> {
    let all: Vec<usize> = objects.iter().map(|p| p.object).collect();
    let mut out = Receivers::default();
    for p in objects {
        let occ = rules.occluders_of(p.object, &all);
        let set = match out.sets.iter().position(|s| s.objects == occ) {
            Some(s) => s,
            None => {
                let triangles = objects
                    .iter()
                    .filter(|q| occ.contains(&q.object))
                    .flat_map(|q| world_triangles(q))
                    .collect();
                out.sets.push(OccluderSet {
                    objects: occ,
                    triangles,
                });
                out.sets.len() - 1
            }
        };
        let normal_matrix = p.model.inverse().transpose();
        for (i, &pos) in p.mesh.positions.iter().enumerate() {
            let n = p.mesh.normals.get(i).copied().unwrap_or(Vec3::Y);
            let n = normal_matrix.transform_vector3(n).as_dvec3();
            let pos = p.model.transform_point3(pos).as_dvec3();
            if !pos.is_finite() || !n.is_finite() || n.length_squared() == 0.0 {
                return Err(Error::Usage(format!(
                    "objects[{}]: vertex {i} has a non-finite position or a zero normal",
                    p.object
                )));
            }
            out.positions.push(pos);
            out.normals.push(n.normalize());
            out.set.push(set as u32);
        }
    }
    Ok(out)
}

fn world_triangles<'a>(p: &'a Placed<'_>) -> impl Iterator<Item = [Vec3; 3]> + 'a {
    p.mesh
        .indices
        .chunks_exact(3)
        .map(move |t| [0, 1, 2].map(|k| p.model.transform_point3(p.mesh.positions[t[k] as usize])))
}

/// An orthonormal tangent frame (t, b) around the unit normal `n`, rotated by `twist` radians
/// about it: the per-vertex camera's orientation, which must not change the transfer.
pub fn tangent_frame(n: DVec3, twist: f64) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t0 = helper.cross(n).normalize();
    let b0 = n.cross(t0);
    let (s, c) = twist.sin_cos();
    let t = t0 * c + b0 * s;
    (t, n.cross(t))
}

/// The vertex camera's frame (tangent, bitangent, normal) for the unit normal `n`.
pub fn frame(n: DVec3, twist: f64) -> (DVec3, DVec3, DVec3) {
    let (t, b) = tangent_frame(n, twist);
    (t, b, n)
}
