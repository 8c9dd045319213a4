//! Portalization (the seed's CaBSP step 3) and the inside-out flood fill (step 4).
//!
//! A portal is a convex piece of a node plane where two leaves touch and no face separates
//! them. Portals are made for every pair of touching leaves before anything is known about which
//! leaves are solid; the flood fill from the start point then decides that: what it reaches
//! through portals is empty space, everything else is solid.

use std::collections::VecDeque;

use super::bsp::Tree;
use super::polygon::Polygon;
use super::{LeafId, NodeId};

#[derive(Clone, Debug)]
pub struct Portal {
    /// The opening; its plane's normal points into `front`.
    pub polygon: Polygon,
    pub front: LeafId,
    pub back: LeafId,
    /// The node whose plane the portal lies in.
    pub node: NodeId,
}

impl Portal {
    /// The leaf on the other side from `leaf`.
    pub fn other(&self, leaf: LeafId) -> LeafId {
        if self.front == leaf {
            self.back
        } else {
            self.front
        }
    }
}

/// Tolerance for "this point of a portal lies inside a face": generous, because by
/// construction a portal piece is either wholly covered by faces or not at all (see
/// [`make_portals`]), so the test only has to be right away from face edges.
const COVER_TOLERANCE: f64 = 1e-6;

/// Cuts every node's plane winding (clipped to the node's cell) into the pieces where a front
/// leaf touches a back leaf, and keeps those not covered by a face lying in that plane.
///
/// Why a single point decides coverage: leaf cells never contain a face in their interior (all
/// faces lie in node planes), so each cell is wholly inside or wholly outside the closed surface
/// the faces form. A piece between two cells is therefore covered by faces entirely (one cell
/// inside, one outside) or nowhere (both on the same side), and its centre point tells which.
/// Portals are kept between solid cells too; only the flood fill knows which cells are solid.
pub fn make_portals(tree: &Tree, node_windings: &[Option<Polygon>], face_polygons: &[&Polygon]) -> Vec<Portal> {
    let mut portals = Vec::new();
    for (n, winding) in node_windings.iter().enumerate() {
        let Some(winding) = winding else { continue };
        let node = &tree.nodes[n];
        for (front, piece) in tree.push_down(winding.clone(), node.front) {
            for (back, piece) in tree.push_down(piece, node.back) {
                let center = piece.center();
                let covered = node.faces.iter().any(|&f| {
                    let face = face_polygons[f as usize];
                    face.bounds().expanded(COVER_TOLERANCE).contains(center)
                        && face.contains_point(center, COVER_TOLERANCE)
                });
                if !covered {
                    portals.push(Portal {
                        polygon: piece,
                        front,
                        back,
                        node: n as NodeId,
                    });
                }
            }
        }
    }
    portals
}

/// Breadth-first flood from `start` through `portals`; `reached[leaf]`.
pub fn flood_fill(leaf_count: usize, portals: &[Portal], start: LeafId) -> Vec<bool> {
    let mut adjacency: Vec<Vec<LeafId>> = vec![Vec::new(); leaf_count];
    for p in portals {
        adjacency[p.front as usize].push(p.back);
        adjacency[p.back as usize].push(p.front);
    }
    let mut reached = vec![false; leaf_count];
    let mut queue = VecDeque::from([start]);
    reached[start as usize] = true;
    while let Some(leaf) = queue.pop_front() {
        for &next in &adjacency[leaf as usize] {
            if !reached[next as usize] {
                reached[next as usize] = true;
                queue.push_back(next);
            }
        }
    }
    reached
}
