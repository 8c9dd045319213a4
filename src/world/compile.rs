//! The compiler driver: brushes → CSG faces → BSP → portals → flood fill → (drop unreachable
//! faces, rebuild) → PVS. The seed's CaBSP steps 1–4, then repeated once on the surviving faces
//! as its step 5 prescribes ("removing surfaces essentially invalidates the previously created
//! BSP tree"), then CaPVS.

use std::time::Instant;

use glam::DVec3;

use super::brush::{csg_faces, BrushFace};
use super::bsp::{Fragment, SplitHeuristic, Tree};
use super::polygon::{Aabb, Polygon};
use super::portals::{flood_fill, make_portals, Portal};
use super::pvs::{compute_pvs, Pvs};
use super::{CompileError, CompileStats, CompiledWorld, Face, FaceId, LeafId, World};

/// Options for [`World::compile_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompileOptions {
    pub heuristic: SplitHeuristic,
    /// Without a PVS every leaf sees every leaf (the seed's "fully visible" fallback).
    pub compute_pvs: bool,
}

impl Default for CompileOptions {
    fn default() -> Self {
        CompileOptions {
            heuristic: SplitHeuristic::default(),
            compute_pvs: true,
        }
    }
}

/// Margin between the faces and the world-bounds box that closes off the outermost cells.
const BOUNDS_MARGIN: f64 = 1.0;

/// One run of BSP + portals + flood fill over a face set.
struct Pass {
    tree: Tree,
    portals: Vec<Portal>,
    reached: Vec<bool>,
    /// Per tree fragment: the reached leaves it bounds (empty: unreachable).
    fragment_leaves: Vec<Vec<LeafId>>,
    bounds: Aabb,
}

fn run_pass(faces: &[BrushFace], start: DVec3, heuristic: SplitHeuristic) -> Result<Pass, CompileError> {
    let fragments = faces
        .iter()
        .enumerate()
        .map(|(i, f)| Fragment {
            polygon: f.polygon.clone(),
            source: i,
        })
        .collect();
    let mut tree = Tree::build(fragments, heuristic);
    let bounds = faces
        .iter()
        .fold(Aabb::EMPTY, |b, f| b.union(&f.polygon.bounds()))
        .expanded(BOUNDS_MARGIN);

    let windings = tree.compute_cells(&bounds);

    let polygons: Vec<&Polygon> = tree.fragments.iter().map(|(f, _)| &f.polygon).collect();
    let portals = make_portals(&tree, &windings, &polygons);
    let start_leaf = tree.leaf_of(start);
    let reached = flood_fill(tree.leaves.len(), &portals, start_leaf);
    if let Some(leaf) = (0..tree.leaves.len()).find(|&l| reached[l] && tree.leaves[l].touches_world_bounds) {
        return Err(CompileError::Leak {
            start,
            leaf_center: tree.leaves[leaf].bounds.center(),
        });
    }

    // A fragment bounds the leaves its front side touches: push it down the side it faces.
    let fragment_leaves = tree
        .fragments
        .iter()
        .map(|(frag, node)| {
            let node = &tree.nodes[*node as usize];
            let side = if frag.polygon.plane.normal.dot(node.plane.normal) > 0.0 {
                node.front
            } else {
                node.back
            };
            let mut leaves: Vec<LeafId> = tree
                .push_down(frag.polygon.clone(), side)
                .into_iter()
                .map(|(l, _)| l)
                .filter(|&l| reached[l as usize])
                .collect();
            leaves.sort_unstable();
            leaves.dedup();
            leaves
        })
        .collect();
    Ok(Pass {
        tree,
        portals,
        reached,
        fragment_leaves,
        bounds,
    })
}

/// The CSG faces the first pass's flood fill touches (it bounds some reached leaf).
fn reached_faces(csg: &[BrushFace], first: &Pass) -> Vec<BrushFace> {
    let mut keep = vec![false; csg.len()];
    for (i, (frag, _)) in first.tree.fragments.iter().enumerate() {
        keep[frag.source] |= !first.fragment_leaves[i].is_empty();
    }
    csg.iter()
        .zip(&keep)
        .filter(|(_, &k)| k)
        .map(|(f, _)| f.clone())
        .collect()
}

/// The world's faces: the tree fragments that bound a reached leaf, with their source face's
/// material and brush; and per fragment its face id (`None`: dropped).
fn faces_of_fragments(
    tree: &Tree,
    fragment_leaves: Vec<Vec<LeafId>>,
    sources: &[BrushFace],
) -> (Vec<Face>, Vec<Option<FaceId>>) {
    let mut faces = Vec::new();
    let mut face_id_of_fragment: Vec<Option<FaceId>> = vec![None; tree.fragments.len()];
    for (i, ((frag, node), leaves)) in tree.fragments.iter().zip(fragment_leaves).enumerate() {
        if leaves.is_empty() {
            continue;
        }
        let source = &sources[frag.source];
        face_id_of_fragment[i] = Some(faces.len() as FaceId);
        faces.push(Face {
            bounds: frag.polygon.bounds(),
            polygon: frag.polygon.clone(),
            material: source.material,
            brush: source.brush,
            node: *node,
            leaves,
        });
    }
    (faces, face_id_of_fragment)
}

/// Rewrites the tree to refer to `faces` instead of its fragments (which it drops), marks the
/// leaves the flood fill did not reach solid, and links the leaves to their faces and to the
/// portals between reached leaves, which it returns.
fn link_tree(
    tree: &mut Tree,
    faces: &[Face],
    face_id_of_fragment: &[Option<FaceId>],
    reached: &[bool],
    portals: Vec<Portal>,
) -> Vec<Portal> {
    tree.fragments.clear();
    for node in &mut tree.nodes {
        node.faces = node
            .faces
            .iter()
            .filter_map(|&f| face_id_of_fragment[f as usize])
            .collect();
    }
    for (leaf, &r) in tree.leaves.iter_mut().zip(reached) {
        leaf.solid = !r;
    }
    for (id, face) in faces.iter().enumerate() {
        for &l in &face.leaves {
            tree.leaves[l as usize].faces.push(id as FaceId);
        }
    }
    let portals: Vec<Portal> = portals
        .into_iter()
        .filter(|p| reached[p.front as usize] && reached[p.back as usize])
        .collect();
    for (id, p) in portals.iter().enumerate() {
        tree.leaves[p.front as usize].portals.push(id as u32);
        tree.leaves[p.back as usize].portals.push(id as u32);
    }
    portals
}

impl World {
    /// Compiles with the default options (balanced BSP, PVS).
    pub fn compile(&self) -> Result<CompiledWorld, CompileError> {
        self.compile_with(CompileOptions::default())
    }

    pub fn compile_with(&self, options: CompileOptions) -> Result<CompiledWorld, CompileError> {
        let t0 = Instant::now();
        if let Some(b) = self.brushes.iter().position(|b| b.contains_point(self.start)) {
            return Err(CompileError::StartInSolid {
                start: self.start,
                brush: b,
            });
        }
        let (csg, csg_stats) = csg_faces(&self.brushes);
        if csg.is_empty() {
            return Err(CompileError::NoFaces);
        }

        // Pass 1: find what the flood fill reaches, and keep the CSG faces it touches.
        let first = run_pass(&csg, self.start, options.heuristic)?;
        let kept = reached_faces(&csg, &first);
        let unreachable_faces_dropped = csg.len() - kept.len();
        if kept.is_empty() {
            return Err(CompileError::NoFaces);
        }

        // Pass 2: the tree over the surviving faces only; the flood fill now defines solidity.
        let second = run_pass(&kept, self.start, options.heuristic)?;
        let Pass {
            mut tree,
            portals,
            reached,
            fragment_leaves,
            bounds,
        } = second;
        let (faces, face_id_of_fragment) = faces_of_fragments(&tree, fragment_leaves, &kept);
        let second_pass_faces_dropped = tree.fragments.len() - faces.len();
        let portals = link_tree(&mut tree, &faces, &face_id_of_fragment, &reached, portals);
        let compile_time = t0.elapsed();

        let t1 = Instant::now();
        let (pvs, pvs_stats) = if options.compute_pvs {
            compute_pvs(&tree, &portals)
        } else {
            (Pvs::all_visible(&tree.leaves), Default::default())
        };
        let stats = CompileStats {
            brushes: self.brushes.len(),
            csg: csg_stats,
            unreachable_faces_dropped,
            second_pass_faces_dropped,
            degenerate_fragments: first.tree.degenerate_fragments + tree.degenerate_fragments,
            faces: faces.len(),
            nodes: tree.nodes.len(),
            leaves: tree.leaves.len(),
            empty_leaves: reached.iter().filter(|&&r| r).count(),
            portals: portals.len(),
            pvs: pvs_stats,
            compile_time,
            pvs_time: t1.elapsed(),
        };
        Ok(CompiledWorld {
            faces,
            tree,
            portals,
            pvs,
            bounds,
            stats,
        })
    }
}
