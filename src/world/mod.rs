//! The static world: convex brushes compiled into a BSP tree with leaves, portals, a leaf-to-leaf
//! PVS, ray casting, and the shadow-caster sets of the stencil-volume path (the Ca3D-Engine thesis §6.1.1 and
//! §4.3.1). Pure CPU, no GPU types: the radiosity and SH bakers and the BSP shadow system reuse
//! it as it is.
//!
//! Pipeline ([`World::compile`]): brush planes → boundary polygons → CSG (drop the parts buried
//! in other brushes) → BSP over the face polygons, every face in a node plane → convex cells →
//! portals → flood fill inside-out from the start point, dropping every face it does not reach
//! → the same again over the surviving faces → PVS by portal flow.
//!
//! Conventions: `f64` world units (metres in the generated levels), z up. Face polygons run
//! counter-clockwise seen from the empty side, their normals point into it.
//!
//! Epsilons: [`PLANE_EPSILON`] is the thickness of a plane for every side test (1e-5: far above
//! the ~1e-12 rounding of f64 coordinates of ~100 after dozens of splits, far below any modelled
//! detail). Polygons under [`MIN_POLYGON_AREA`] (1 mm²) are dropped as degenerate and counted.

pub(crate) mod brush;
pub(crate) mod bsp;
pub(crate) mod casters;
pub(crate) mod compile;
pub mod level_gen;
pub mod polygon;
pub(crate) mod portals;
pub(crate) mod pvs;
pub(crate) mod raycast;

#[cfg(test)]
mod tests;

use std::time::Duration;

use glam::DVec3;

pub use brush::{Brush, BrushSide, CsgStats};
pub use bsp::{Child, Leaf, Node, SplitHeuristic};
pub use compile::CompileOptions;
pub use polygon::{Aabb, Plane, Polygon, Side, Split, Tolerance};
pub use portals::Portal;
pub use pvs::{Pvs, PvsStats};
pub use raycast::RayHit;

/// Index into [`CompiledWorld::faces`].
pub type FaceId = u32;
/// Index into the tree's leaves ([`CompiledWorld::leaves`]).
pub type LeafId = u32;
/// Index into the tree's nodes.
pub type NodeId = u32;
/// Index into [`CompiledWorld::portals`].
pub type PortalId = u32;
/// Opaque material index carried from brush sides to faces.
pub type MaterialId = u32;

/// Half-thickness of a plane for side classification, in world units.
pub const PLANE_EPSILON: f64 = 1e-5;
/// Polygons smaller than this (world units², 1 mm² at metre scale) are dropped as degenerate.
pub const MIN_POLYGON_AREA: f64 = 1e-6;

/// The source description: solid brushes and a point in the playable space from which the
/// flood fill starts.
#[derive(Clone, Debug, PartialEq)]
pub struct World {
    pub brushes: Vec<Brush>,
    pub start: DVec3,
}

/// A face of the compiled world: a convex polygon of the solid's boundary, seen from the empty
/// side.
#[derive(Clone, Debug)]
pub struct Face {
    pub polygon: Polygon,
    pub material: MaterialId,
    /// The brush it is a side of.
    pub brush: u32,
    /// The node whose plane it lies in.
    pub node: NodeId,
    /// The (empty) leaves it bounds, i.e. touches with non-zero area; ascending.
    pub leaves: Vec<LeafId>,
    pub bounds: Aabb,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CompileError {
    #[error("the start point {start} is inside brush {brush}")]
    StartInSolid { start: DVec3, brush: usize },
    #[error("the flood fill from {start} leaks to the outside near {leaf_center}: the level is not sealed")]
    Leak { start: DVec3, leaf_center: DVec3 },
    #[error("the world has no faces left")]
    NoFaces,
}

/// What the compiler did, for reports and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompileStats {
    pub brushes: usize,
    pub csg: CsgStats,
    /// CSG faces the inside-out flood fill did not reach (the seed's step 4).
    pub unreachable_faces_dropped: usize,
    /// Faces not reached in the rebuilt tree (informational; zero on sound input).
    pub second_pass_faces_dropped: usize,
    /// Pieces that came out thinner than the epsilon when the BSP split a face.
    pub degenerate_fragments: usize,
    pub faces: usize,
    pub nodes: usize,
    pub leaves: usize,
    pub empty_leaves: usize,
    pub portals: usize,
    pub pvs: PvsStats,
    pub compile_time: Duration,
    pub pvs_time: Duration,
}

/// The compiled world: faces, BSP tree, portals between empty leaves, PVS.
#[derive(Clone, Debug)]
pub struct CompiledWorld {
    pub faces: Vec<Face>,
    pub tree: bsp::Tree,
    pub portals: Vec<Portal>,
    pub pvs: Pvs,
    /// The world-bounds box the outermost cells were closed with.
    pub bounds: Aabb,
    pub stats: CompileStats,
}

impl CompiledWorld {
    pub fn leaves(&self) -> &[Leaf] {
        &self.tree.leaves
    }

    pub fn nodes(&self) -> &[Node] {
        &self.tree.nodes
    }

    /// The leaf containing `p` (points on a node plane count as in front of it).
    pub fn leaf_of(&self, p: DVec3) -> LeafId {
        self.tree.leaf_of(p)
    }

    /// The empty leaves a box reaches, ascending: a conservative descent of the tree (see
    /// `bsp::Tree::box_leaves`).
    pub fn box_leaves(&self, b: &Aabb) -> Vec<LeafId> {
        let mut out = self.tree.box_leaves(b);
        out.retain(|&l| !self.is_solid(l));
        out
    }

    pub fn is_solid(&self, leaf: LeafId) -> bool {
        self.tree.leaves.get(leaf as usize).is_none_or(|l| l.solid)
    }

    /// Whether leaf `b` is potentially visible from leaf `a` (symmetric, conservative).
    pub fn is_visible(&self, a: LeafId, b: LeafId) -> bool {
        self.pvs.is_visible(a, b)
    }

    /// The leaves potentially visible from `leaf`, itself included; none for a solid leaf.
    pub fn visible_leaves(&self, leaf: LeafId) -> impl Iterator<Item = LeafId> + '_ {
        self.pvs.visible_leaves(leaf)
    }

    /// Faces in back-to-front order from `eye` (painter's order over the node lists).
    pub fn faces_back_to_front(&self, eye: DVec3) -> Vec<FaceId> {
        self.tree.faces_back_to_front(eye)
    }

    /// Empty leaf ids.
    pub fn empty_leaves(&self) -> impl Iterator<Item = LeafId> + '_ {
        self.tree
            .leaves
            .iter()
            .enumerate()
            .filter(|(_, l)| !l.solid)
            .map(|(i, _)| i as LeafId)
    }
}
