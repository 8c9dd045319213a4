//! Vertices where the transfer needs them. Per-vertex transfer samples visibility at the mesh's
//! vertices only, so a wall or floor modelled as two triangles carries four samples, and a corner
//! that sees past the room (the far side of a wall, under its foot) lights the whole face when
//! interpolated. The corrected bake splits long edges first: longest-edge bisection over all the
//! receivers at once, an edge at a time in every triangle that holds it (by position, so the
//! faces of a box meeting at a crease stay joined), until no edge is longer than its object's
//! limit or the vertex budget is spent.

use std::collections::{BinaryHeap, HashMap};

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::scene::Mesh;

/// A mesh to refine: its vertices, its placement (lengths are measured in the world) and the
/// longest edge it may keep.
pub struct Target<'a> {
    pub mesh: &'a Mesh,
    pub model: Mat4,
    pub max_edge: f32,
}

/// The meshes after refinement, in the order given, and whether the budget stopped it first.
pub struct Refined {
    pub meshes: Vec<Mesh>,
    pub added: usize,
    pub budget_spent: bool,
}

/// An edge by its endpoints' positions (bit patterns, lower first): the faces of a box share
/// positions but not vertices.
type EdgeKey = ([u32; 3], [u32; 3]);

fn edge_key(a: Vec3, b: Vec3) -> EdgeKey {
    let (a, b) = (a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits));
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

/// One mesh being split, with the triangles holding each edge.
struct Work {
    mesh: Mesh,
    model: Mat4,
    max_edge: f32,
    triangles: Vec<[u32; 3]>,
    by_edge: HashMap<EdgeKey, Vec<usize>>,
    /// Midpoints already made, by their endpoints' indices (lower first).
    midpoints: HashMap<(u32, u32), u32>,
}

/// A queued edge: its length over its mesh's limit, the mesh and the edge.
#[derive(PartialEq)]
struct Queued(f32, usize, EdgeKey);

impl Eq for Queued {}

impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Queued {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0
            .total_cmp(&other.0)
            .then(self.1.cmp(&other.1))
            .then(self.2.cmp(&other.2))
    }
}

impl Work {
    fn new(t: &Target<'_>) -> Work {
        let triangles: Vec<[u32; 3]> = t.mesh.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let mut w = Work {
            mesh: t.mesh.clone(),
            model: t.model,
            max_edge: t.max_edge,
            triangles,
            by_edge: HashMap::new(),
            midpoints: HashMap::new(),
        };
        for i in 0..w.triangles.len() {
            w.link(i);
        }
        w
    }

    fn position(&self, v: u32) -> Vec3 {
        self.mesh.positions[v as usize]
    }

    /// The edge's length in the world over the mesh's limit.
    fn ratio(&self, key: &EdgeKey) -> f32 {
        let p = |bits: [u32; 3]| self.model.transform_point3(Vec3::from_array(bits.map(f32::from_bits)));
        p(key.0).distance(p(key.1)) / self.max_edge
    }

    fn edges(&self, t: usize) -> [EdgeKey; 3] {
        let [a, b, c] = self.triangles[t].map(|v| self.position(v));
        [edge_key(a, b), edge_key(b, c), edge_key(c, a)]
    }

    fn link(&mut self, t: usize) {
        for e in self.edges(t) {
            self.by_edge.entry(e).or_default().push(t);
        }
    }

    fn unlink(&mut self, t: usize) {
        for e in self.edges(t) {
            if let Some(list) = self.by_edge.get_mut(&e) {
                list.retain(|&x| x != t);
            }
        }
    }

    /// The vertex halfway between `a` and `b`, every attribute interpolated.
    fn midpoint(&mut self, a: u32, b: u32) -> u32 {
        let pair = (a.min(b), a.max(b));
        if let Some(&m) = self.midpoints.get(&pair) {
            return m;
        }
        let m = self.mesh.positions.len() as u32;
        let (i, j) = (pair.0 as usize, pair.1 as usize);
        let mesh = &mut self.mesh;
        // The sum in a fixed order: two vertices at the same positions give the same midpoint.
        let (pa, pb) = (mesh.positions[i], mesh.positions[j]);
        let (lo, hi) = if edge_key(pa, pa) <= edge_key(pb, pb) {
            (pa, pb)
        } else {
            (pb, pa)
        };
        mesh.positions.push((lo + hi) * 0.5);
        if mesh.normals.len() > j {
            let n = (mesh.normals[i] + mesh.normals[j]).normalize_or(mesh.normals[i]);
            mesh.normals.push(n);
        }
        if mesh.uvs.len() > j {
            mesh.uvs.push(Vec2::lerp(mesh.uvs[i], mesh.uvs[j], 0.5));
        }
        if mesh.tangents.len() > j {
            let (ta, tb) = (mesh.tangents[i], mesh.tangents[j]);
            let t = (ta.truncate() + tb.truncate()).normalize_or(ta.truncate());
            mesh.tangents.push(Vec4::from((t, ta.w)));
        }
        self.midpoints.insert(pair, m);
        m
    }

    /// Bisects every triangle holding `key`; the new edges it makes.
    fn split(&mut self, key: &EdgeKey) -> Vec<EdgeKey> {
        let holders = self.by_edge.remove(key).unwrap_or_default();
        let mut made = Vec::new();
        for t in holders {
            let tri = self.triangles[t];
            let Some(k) = (0..3).find(|&k| edge_key(self.position(tri[k]), self.position(tri[(k + 1) % 3])) == *key)
            else {
                continue;
            };
            let (i, j, r) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            self.unlink(t);
            let m = self.midpoint(i, j);
            self.triangles[t] = [i, m, r];
            self.triangles.push([m, j, r]);
            let u = self.triangles.len() - 1;
            self.link(t);
            self.link(u);
            let (pi, pj, pm, pr) = (self.position(i), self.position(j), self.position(m), self.position(r));
            made.extend([edge_key(pi, pm), edge_key(pm, pj), edge_key(pm, pr)]);
        }
        made
    }

    fn finish(mut self) -> Mesh {
        self.mesh.indices = self.triangles.into_iter().flatten().collect();
        self.mesh
    }
}

/// Splits the targets' edges, longest over its limit first, until every edge is within its
/// mesh's limit or `budget` vertices have been added.
pub fn refine(targets: &[Target<'_>], budget: usize) -> Refined {
    // Meshes with no edge over their limit (most of a dense scene) skip the edge tables.
    let splits = |t: &Target<'_>| {
        t.mesh.indices.chunks_exact(3).any(|c| {
            let p = [c[0], c[1], c[2]].map(|i| t.model.transform_point3(t.mesh.positions[i as usize]));
            (0..3).any(|k| p[k].distance(p[(k + 1) % 3]) > t.max_edge)
        })
    };
    let mut work: Vec<Option<Work>> = targets.iter().map(|t| splits(t).then(|| Work::new(t))).collect();
    let mut queue = BinaryHeap::new();
    for (w, mesh) in work.iter().enumerate() {
        for (key, mesh) in mesh.iter().flat_map(|m| m.by_edge.keys().map(move |k| (k, m))) {
            let r = mesh.ratio(key);
            if r > 1.0 {
                queue.push(Queued(r, w, *key));
            }
        }
    }
    let mut added = 0;
    let mut budget_spent = false;
    while let Some(Queued(_, w, key)) = queue.pop() {
        let Some(mesh) = work[w].as_mut() else { continue };
        if mesh.by_edge.get(&key).is_none_or(|l| l.is_empty()) {
            continue;
        }
        if added >= budget {
            budget_spent = true;
            break;
        }
        let before = mesh.mesh.positions.len();
        for e in mesh.split(&key) {
            let r = mesh.ratio(&e);
            if r > 1.0 {
                queue.push(Queued(r, w, e));
            }
        }
        added += mesh.mesh.positions.len() - before;
    }
    Refined {
        meshes: (work.into_iter().zip(targets))
            .map(|(w, t)| w.map_or_else(|| t.mesh.clone(), Work::finish))
            .collect(),
        added,
        budget_spent,
    }
}
