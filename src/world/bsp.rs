//! The BSP tree: building it over face polygons (the seed's CaBSP step 2), the convex cells of
//! its nodes and leaves, pushing polygons down to the leaves they touch, point location and
//! painter's-order traversal.
//!
//! Every face fragment ends up stored in the node whose plane it lies in (a "coincident list",
//! as Ridderhof 2002's BSP shadow system also wants); leaves appear where no fragments remain.

use glam::DVec3;

use super::brush::{convex_faces, BASE_WINDING_SIZE};
use super::polygon::{Aabb, Plane, Polygon, Side, Split, Tolerance};
use super::{FaceId, LeafId, NodeId};

/// How the splitting plane of a node is chosen among the planes of its remaining faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplitHeuristic {
    /// Minimise `split_weight · splits + |front − back|` (faces cut, and imbalance of the
    /// faces on either side), over all distinct face planes; O(faces²) per node, as the seed's
    /// CaBSP. Ties go to axis-aligned planes, then to the plane holding more faces. A split
    /// costs more than imbalance because every split adds a face, a polygon to draw and light
    /// forever, while imbalance only adds depth to point and ray queries.
    Balanced { split_weight: u32 },
    /// The first remaining face's plane, as Ridderhof 2002's BSP system (no heuristic).
    FirstFace,
}

impl Default for SplitHeuristic {
    fn default() -> Self {
        SplitHeuristic::Balanced { split_weight: 5 }
    }
}

/// A child link: another node or a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Child {
    Node(NodeId),
    Leaf(LeafId),
}

#[derive(Clone, Debug)]
pub struct Node {
    pub plane: Plane,
    pub front: Child,
    pub back: Child,
    /// Faces lying in this node's plane (either facing).
    pub faces: Vec<FaceId>,
}

#[derive(Clone, Debug)]
pub struct Leaf {
    /// Solid leaves are everything the inside-out flood fill did not reach.
    pub solid: bool,
    /// Faces that bound this leaf: they lie in one of its node planes, face into it, and
    /// touch it with non-zero area.
    pub faces: Vec<FaceId>,
    pub portals: Vec<super::PortalId>,
    /// Bounds of the leaf's convex cell (clipped to the world bounds).
    pub bounds: Aabb,
    /// Whether the cell reaches the world bounds: an empty leaf that does is a leak.
    pub touches_world_bounds: bool,
}

/// A polygon being filtered into the tree, with the index of the face it came from.
#[derive(Clone, Debug)]
pub struct Fragment {
    pub polygon: Polygon,
    pub source: usize,
}

/// The tree. `root` is `None` only before [`Tree::build`]; node and leaf ids index `nodes`
/// and `leaves`.
#[derive(Clone, Debug, Default)]
pub struct Tree {
    pub nodes: Vec<Node>,
    pub leaves: Vec<Leaf>,
    pub root: Option<Child>,
    /// During compilation: the fragments that ended up in nodes, indexed by the ids stored in
    /// `nodes`. Empty in a [`CompiledWorld`](super::CompiledWorld), whose node lists hold
    /// `FaceId`s into its `faces` instead.
    pub fragments: Vec<(Fragment, NodeId)>,
    /// Fragments that came out degenerate when split.
    pub degenerate_fragments: usize,
}

impl Tree {
    /// Builds the tree over `fragments`; every fragment lands in exactly one node.
    pub fn build(fragments: Vec<Fragment>, heuristic: SplitHeuristic) -> Tree {
        Tree::build_in(fragments, heuristic, &Tolerance::EXACT)
    }

    /// [`Tree::build`] with `tolerance`'s side tests and rounding of the cuts.
    pub fn build_in(fragments: Vec<Fragment>, heuristic: SplitHeuristic, tolerance: &Tolerance) -> Tree {
        let mut tree = Tree::default();
        let root = tree.build_rec(fragments, heuristic, tolerance);
        tree.root = Some(root);
        tree
    }

    fn new_leaf(&mut self) -> Child {
        self.leaves.push(Leaf {
            solid: false,
            faces: Vec::new(),
            portals: Vec::new(),
            bounds: Aabb::EMPTY,
            touches_world_bounds: false,
        });
        Child::Leaf((self.leaves.len() - 1) as LeafId)
    }

    fn build_rec(&mut self, fragments: Vec<Fragment>, heuristic: SplitHeuristic, tolerance: &Tolerance) -> Child {
        if fragments.is_empty() {
            return self.new_leaf();
        }
        let plane = choose_plane(&fragments, heuristic, tolerance);
        let (mut front, mut back) = (Vec::new(), Vec::new());
        let node_id = self.nodes.len() as NodeId;
        self.nodes.push(Node {
            plane,
            front: Child::Leaf(0),
            back: Child::Leaf(0),
            faces: Vec::new(),
        });
        for frag in fragments {
            match frag.polygon.split_in(&plane, tolerance) {
                Split::Front(polygon) => front.push(Fragment { polygon, ..frag }),
                Split::Back(polygon) => back.push(Fragment { polygon, ..frag }),
                Split::On(polygon, _) => {
                    self.nodes[node_id as usize].faces.push(self.fragments.len() as FaceId);
                    self.fragments.push((Fragment { polygon, ..frag }, node_id));
                }
                Split::Spanning { front: f, back: b } => {
                    self.degenerate_fragments += usize::from(f.is_none()) + usize::from(b.is_none());
                    front.extend(f.map(|polygon| Fragment {
                        polygon,
                        source: frag.source,
                    }));
                    back.extend(b.map(|polygon| Fragment {
                        polygon,
                        source: frag.source,
                    }));
                }
            }
        }
        let front = self.build_rec(front, heuristic, tolerance);
        let back = self.build_rec(back, heuristic, tolerance);
        let node = &mut self.nodes[node_id as usize];
        node.front = front;
        node.back = back;
        Child::Node(node_id)
    }

    /// The leaf containing `p`; points on a plane count as in front of it.
    pub fn leaf_of(&self, p: DVec3) -> LeafId {
        let mut child = self.root.unwrap_or(Child::Leaf(0));
        loop {
            match child {
                Child::Leaf(l) => return l,
                Child::Node(n) => {
                    let node = &self.nodes[n as usize];
                    child = if node.plane.distance(p) >= 0.0 {
                        node.front
                    } else {
                        node.back
                    };
                }
            }
        }
    }

    /// Every leaf a box reaches, solid ones included: the box goes down each side of every
    /// plane it reaches (points on a plane count as in front, as in [`Tree::leaf_of`]), so a
    /// leaf the box passes through is found even when no corner lies in it.
    pub fn box_leaves(&self, b: &Aabb) -> Vec<LeafId> {
        let (center, half) = (b.center(), 0.5 * (b.max - b.min));
        let mut out = Vec::new();
        let mut stack = vec![self.root.unwrap_or(Child::Leaf(0))];
        while let Some(child) = stack.pop() {
            match child {
                Child::Leaf(l) => out.push(l),
                Child::Node(n) => {
                    let node = &self.nodes[n as usize];
                    // The box's extent along the normal about its centre's distance.
                    let (d, r) = (node.plane.distance(center), half.dot(node.plane.normal.abs()));
                    if d + r >= 0.0 {
                        stack.push(node.front);
                    }
                    if d - r < 0.0 {
                        stack.push(node.back);
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Filters a polygon down from `start`, splitting it at every plane it crosses: the pieces
    /// and the leaves they end in. A piece lying in a plane below `start` (only possible
    /// through rounding, since coplanar faces are gathered in one node) goes both ways.
    pub fn push_down(&self, polygon: Polygon, start: Child) -> Vec<(LeafId, Polygon)> {
        let mut out = Vec::new();
        let mut stack = vec![(start, polygon)];
        while let Some((child, poly)) = stack.pop() {
            let n = match child {
                Child::Leaf(l) => {
                    out.push((l, poly));
                    continue;
                }
                Child::Node(n) => &self.nodes[n as usize],
            };
            match poly.split(&n.plane) {
                Split::Front(p) => stack.push((n.front, p)),
                Split::Back(p) => stack.push((n.back, p)),
                Split::On(p, _) => {
                    stack.push((n.front, p.clone()));
                    stack.push((n.back, p));
                }
                Split::Spanning { front, back } => {
                    stack.extend(front.map(|p| (n.front, p)));
                    stack.extend(back.map(|p| (n.back, p)));
                }
            }
        }
        out
    }

    /// Walks the convex cells, starting from the world-bounds box: sets every leaf's bounds and
    /// whether it reaches the world bounds, and returns every node's plane winding clipped to
    /// the node's cell (what portals are cut from), by node id.
    pub fn compute_cells(&mut self, world_bounds: &Aabb) -> Vec<Option<Polygon>> {
        let mut windings = vec![None; self.nodes.len()];
        let mut cells = vec![(Aabb::EMPTY, false); self.leaves.len()];
        if let Some(root) = self.root {
            let mut planes: Vec<Plane> = world_bounds.planes().to_vec();
            self.cells_rec(root, &mut planes, &mut windings, &mut cells);
        }
        for (leaf, (bounds, touches)) in self.leaves.iter_mut().zip(cells) {
            leaf.bounds = bounds;
            leaf.touches_world_bounds = touches;
        }
        windings
    }

    /// `planes`: the cell of `child`, normals outward; the first six are the world bounds.
    fn cells_rec(
        &self,
        child: Child,
        planes: &mut Vec<Plane>,
        windings: &mut [Option<Polygon>],
        cells: &mut [(Aabb, bool)],
    ) {
        match child {
            Child::Leaf(l) => {
                let faces = convex_faces(planes.iter().copied());
                let bounds = faces.iter().flatten().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
                cells[l as usize] = (bounds, faces.iter().take(6).any(Option::is_some));
            }
            Child::Node(n) => {
                let node = &self.nodes[n as usize];
                let mut winding = Some(Polygon::base_winding(&node.plane, BASE_WINDING_SIZE));
                for p in planes.iter() {
                    winding = winding.and_then(|w| w.clip_back(p));
                }
                windings[n as usize] = winding;
                planes.push(node.plane.flipped());
                self.cells_rec(node.front, planes, windings, cells);
                planes.pop();
                planes.push(node.plane);
                self.cells_rec(node.back, planes, windings, cells);
                planes.pop();
            }
        }
    }

    /// Faces in back-to-front order as seen from `eye` (painter's order, Ridderhof 2002 §5.2.2): at
    /// each node, the far side, then the node's faces, then the near side.
    pub fn faces_back_to_front(&self, eye: DVec3) -> Vec<FaceId> {
        let mut out = Vec::new();
        let Some(root) = self.root else { return out };
        let mut stack = vec![(root, false)];
        // Explicit stack: (child, node faces already due). A node pushes near, itself, far.
        while let Some((child, emit)) = stack.pop() {
            let Child::Node(n) = child else { continue };
            let node = &self.nodes[n as usize];
            if emit {
                out.extend_from_slice(&node.faces);
                continue;
            }
            let (near, far) = if node.plane.distance(eye) >= 0.0 {
                (node.front, node.back)
            } else {
                (node.back, node.front)
            };
            stack.push((near, false));
            stack.push((child, true));
            stack.push((far, false));
        }
        out
    }
}

/// Picks the split plane for a set of fragments (see [`SplitHeuristic`]).
fn choose_plane(fragments: &[Fragment], heuristic: SplitHeuristic, tolerance: &Tolerance) -> Plane {
    let split_weight = match heuristic {
        SplitHeuristic::FirstFace => return fragments[0].polygon.plane,
        SplitHeuristic::Balanced { split_weight } => split_weight as i64,
    };
    let mut candidates: Vec<Plane> = Vec::new();
    for f in fragments {
        let p = f.polygon.plane;
        if !candidates.iter().any(|c| c.coplanar_facing(&p).is_some()) {
            candidates.push(p);
        }
    }
    let mut best: Option<((i64, u8, i64), Plane)> = None;
    for plane in candidates {
        let (mut front, mut back, mut splits, mut on) = (0i64, 0i64, 0i64, 0i64);
        for f in fragments {
            match f.polygon.classify_in(&plane, tolerance) {
                Side::Front => front += 1,
                Side::Back => back += 1,
                Side::On => on += 1,
                Side::Spanning => splits += 1,
            }
        }
        let score = (
            split_weight * splits + (front - back).abs(),
            u8::from(plane.axis().is_none()),
            -on,
        );
        if best.as_ref().is_none_or(|(s, _)| score < *s) {
            best = Some((score, plane));
        }
    }
    best.map(|(_, p)| p).unwrap_or(fragments[0].polygon.plane)
}
