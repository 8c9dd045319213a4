//! Hidden surfaces without a depth test (`hidden = "painter" | "fixed"`): the segments drawn in
//! a painter's order from the BSP the set-up built.
//!
//! The thesis draws each frame from "PolygonLists in a predetermined order" (§5.5); a painter's
//! order is only right for the eye it was taken from (digest §3.3 item 5). `painter` walks the
//! BSP back to front from the frame's eye every frame (§5.2.2), the corrected form; `fixed`
//! keeps the order from the first frame's eye, the document's, which fails once the eye crosses
//! a node's plane. The default (`depth`) uses the depth buffer.
//!
//! The tree is kept as the set-up built it (planes, children, the fragments in each node) with,
//! per fragment, its triangles in the segment index buffer, which `Segments` lays out fragment
//! by fragment. A frame's order is a list of index ranges, neighbours merged, one draw each.

use std::ops::Range;

use glam::DVec3;

use crate::world::bsp::{Child, Node, Tree};
use crate::world::Plane;

/// A child link in the encoded tree that is a leaf (the fragments live in the nodes).
const LEAF: u32 = u32::MAX;

/// The set-up's BSP as the run time walks it, and where each fragment's triangles are.
#[derive(Clone, Debug, Default)]
pub struct PainterTree {
    /// Nodes only: every child that is not a node is `Child::Leaf(0)` (leaves hold nothing
    /// here).
    tree: Tree,
    /// Per fragment (`FaceId` in the nodes): its triangles, as a range of triangle indices.
    fragment_triangles: Vec<Range<u32>>,
}

impl PartialEq for PainterTree {
    fn eq(&self, other: &Self) -> bool {
        self.encode() == other.encode()
    }
}

impl PainterTree {
    /// From the set-up's tree and, per segment triangle, the fragment it belongs to.
    pub fn new(tree: &Tree, triangle_fragment: &[u32]) -> PainterTree {
        let nodes = tree
            .nodes
            .iter()
            .map(|n| Node {
                plane: n.plane,
                front: node_or_leaf(n.front),
                back: node_or_leaf(n.back),
                faces: n.faces.clone(),
            })
            .collect();
        let stripped = Tree {
            nodes,
            leaves: Vec::new(),
            root: tree.root.map(node_or_leaf),
            fragments: Vec::new(),
            degenerate_fragments: 0,
        };
        PainterTree {
            tree: stripped,
            fragment_triangles: super::setup::owner_ranges(triangle_fragment, tree.fragments.len()),
        }
    }

    pub fn fragments(&self) -> usize {
        self.fragment_triangles.len()
    }

    /// Fragments back to front from `eye` (the BSP walk of `world::bsp`).
    pub fn back_to_front(&self, eye: DVec3) -> Vec<u32> {
        self.tree.faces_back_to_front(eye)
    }

    /// The index ranges `(first index, index count)` to draw, in order, for fragments in
    /// `order`; ranges that follow each other in the index buffer are merged into one draw.
    pub fn draws(&self, order: &[u32]) -> Vec<(u32, u32)> {
        let mut out: Vec<(u32, u32)> = Vec::new();
        for &f in order {
            let Some(t) = self.fragment_triangles.get(f as usize) else {
                continue;
            };
            if t.is_empty() {
                continue;
            }
            let (first, count) = (3 * t.start, 3 * (t.end - t.start));
            match out.last_mut() {
                Some(last) if last.0 + last.1 == first => last.1 += count,
                _ => out.push((first, count)),
            }
        }
        out
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut words: Vec<u32> = vec![
            self.tree.nodes.len() as u32,
            self.tree.root.map_or(LEAF, encode_child),
            self.fragment_triangles.len() as u32,
        ];
        for r in &self.fragment_triangles {
            words.extend([r.start, r.end]);
        }
        let mut out: Vec<u8> = bytemuck::cast_slice(&words).to_vec();
        for n in &self.tree.nodes {
            for x in [n.plane.normal.x, n.plane.normal.y, n.plane.normal.z, n.plane.dist] {
                out.extend_from_slice(&x.to_le_bytes());
            }
            for w in [encode_child(n.front), encode_child(n.back), n.faces.len() as u32]
                .into_iter()
                .chain(n.faces.iter().copied())
            {
                out.extend_from_slice(&w.to_le_bytes());
            }
        }
        out
    }

    /// The tree from `bytes` (as `encode` wrote it), and the bytes it took; `None` when they
    /// are not a well-formed tree over `triangles` triangles.
    pub fn decode(bytes: &[u8], triangles: u32) -> Option<(PainterTree, usize)> {
        let mut r = Reader { bytes, at: 0 };
        let (nodes, root, fragments) = (r.u32()?, r.u32()?, r.u32()?);
        let mut fragment_triangles = Vec::with_capacity(fragments.min(1 << 24) as usize);
        for _ in 0..fragments {
            let (start, end) = (r.u32()?, r.u32()?);
            if start > end || end > triangles {
                return None;
            }
            fragment_triangles.push(start..end);
        }
        let mut tree = Tree {
            root: Some(decode_child(root, nodes)?),
            ..Tree::default()
        };
        for _ in 0..nodes {
            let normal = DVec3::new(r.f64()?, r.f64()?, r.f64()?);
            let plane = Plane { normal, dist: r.f64()? };
            let (front, back, count) = (r.u32()?, r.u32()?, r.u32()?);
            let faces: Option<Vec<u32>> = (0..count).map(|_| r.u32().filter(|&f| f < fragments)).collect();
            tree.nodes.push(Node {
                plane,
                front: decode_child(front, nodes)?,
                back: decode_child(back, nodes)?,
                faces: faces?,
            });
        }
        // Children come after their parent (the build numbers nodes depth first): a corrupt
        // link that points back up would make the walk loop.
        for (i, n) in tree.nodes.iter().enumerate() {
            for c in [n.front, n.back] {
                if let Child::Node(c) = c {
                    if c as usize <= i {
                        return None;
                    }
                }
            }
        }
        Some((
            PainterTree {
                tree,
                fragment_triangles,
            },
            r.at,
        ))
    }
}

/// Little-endian words read from the front of a byte slice.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let b = self.bytes.get(self.at..self.at + N)?.try_into().ok()?;
        self.at += N;
        Some(b)
    }

    fn u32(&mut self) -> Option<u32> {
        self.take().map(u32::from_le_bytes)
    }

    fn f64(&mut self) -> Option<f64> {
        self.take().map(f64::from_le_bytes)
    }
}

fn node_or_leaf(c: Child) -> Child {
    match c {
        Child::Node(n) => Child::Node(n),
        Child::Leaf(_) => Child::Leaf(0),
    }
}

fn encode_child(c: Child) -> u32 {
    match c {
        Child::Node(n) => n,
        Child::Leaf(_) => LEAF,
    }
}

fn decode_child(w: u32, nodes: u32) -> Option<Child> {
    match w {
        LEAF => Some(Child::Leaf(0)),
        n if n < nodes => Some(Child::Node(n)),
        _ => None,
    }
}
