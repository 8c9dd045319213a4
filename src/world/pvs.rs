//! Leaf-to-leaf potentially visible sets from the portals (the seed's CaPVS, §6.1.1).
//!
//! Each directed portal is treated, as in the seed, as a one-way planar light source; the
//! light flows from leaf to leaf through further portals, and every portal passed narrows it.
//! The narrowing is done with *separating planes* (planes through an edge of one winding and a
//! vertex of the other that have the source wholly behind and the passed portal wholly in
//! front): every line from the source through the passed portal stays in front of such a plane
//! beyond it, so clipping the next portal to it removes only points no line can reach. That
//! keeps the result conservative: a leaf is left out only if no stabbing line exists along any
//! portal sequence (up to the slack below, which only ever keeps more).
//!
//! Two cheap bounds prune the recursion: a per-portal flood that only requires each later
//! portal to lie partly in front of the source ("might see"), and the finished result of a
//! portal whose own flow is done, since a line through it continues as a line from it. Portals
//! are processed smallest "might see" first, so most of the later work is cut by finished ones.
//! Per-leaf sets are the union over the leaf's outgoing portals, then made symmetric by union.

use glam::DVec3;

use super::bsp::{Leaf, Tree};
use super::polygon::{clip_points_front, Plane};
use super::portals::Portal;
use super::LeafId;

/// Slack with which the flow keeps points near a clipping plane: it makes every clip keep a
/// little more, never less.
const VIS_SLACK: f64 = 1e-4;
/// How far on the wrong side a vertex may be for a plane still to count as separating. Tiny, so
/// that the error it admits, which grows with distance beyond the passed portal, stays far below
/// [`VIS_SLACK`] across a level.
const SEPARATOR_EPSILON: f64 = 1e-9;

/// A bitset per leaf: `is_visible(a, b)`. Solid leaves see nothing and are seen by nothing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pvs {
    leaf_count: usize,
    words: usize,
    bits: Vec<u64>,
}

/// What the PVS computation did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PvsStats {
    pub directed_portals: usize,
    /// Portal-to-portal steps of the flow (a measure of the work).
    pub flow_steps: u64,
    /// Ordered pairs (a, b), a ≠ b, marked visible.
    pub visible_pairs: usize,
    /// Of those, pairs only the symmetric union added (the flow from b found a but not the
    /// flow from a found b).
    pub added_by_symmetry: usize,
}

impl Pvs {
    fn empty(leaf_count: usize) -> Pvs {
        let words = leaf_count.div_ceil(64);
        Pvs {
            leaf_count,
            words,
            bits: vec![0; words * leaf_count],
        }
    }

    /// Every empty leaf sees every empty leaf: the fallback without a PVS.
    pub fn all_visible(leaves: &[Leaf]) -> Pvs {
        let mut pvs = Pvs::empty(leaves.len());
        for a in (0..leaves.len()).filter(|&a| !leaves[a].solid) {
            for b in (0..leaves.len()).filter(|&b| !leaves[b].solid) {
                pvs.set(a, b);
            }
        }
        pvs
    }

    fn set(&mut self, a: usize, b: usize) {
        self.bits[a * self.words + b / 64] |= 1 << (b % 64);
    }

    pub fn is_visible(&self, a: LeafId, b: LeafId) -> bool {
        let (a, b) = (a as usize, b as usize);
        a < self.leaf_count && b < self.leaf_count && self.bits[a * self.words + b / 64] & (1 << (b % 64)) != 0
    }

    /// The leaves `leaf` can see (itself included, unless solid), ascending.
    pub fn visible_leaves(&self, leaf: LeafId) -> impl Iterator<Item = LeafId> + '_ {
        self.row(leaf).iter().enumerate().flat_map(|(w, &bits)| {
            (0..64)
                .filter(move |i| bits & (1 << i) != 0)
                .map(move |i| (w * 64 + i) as LeafId)
        })
    }

    /// The packed row of `leaf`: bit `b` of word `b / 64` is `is_visible(leaf, b)`.
    pub fn row(&self, leaf: LeafId) -> &[u64] {
        let start = leaf as usize * self.words;
        self.bits.get(start..start + self.words).unwrap_or(&[])
    }

    pub fn leaf_count(&self) -> usize {
        self.leaf_count
    }
}

/// A portal taken in one direction: the light enters `to` through `winding`, whose plane's
/// normal points into `to`.
struct Directed {
    winding: Vec<DVec3>,
    plane: Plane,
    from: LeafId,
    to: LeafId,
}

struct Flow<'a> {
    directed: &'a [Directed],
    leaving: &'a [Vec<usize>],
    might: &'a [Vec<u64>],
    done: &'a [Option<Vec<u64>>],
    steps: u64,
}

/// Computes the PVS of every leaf of `tree` from `portals` (between empty leaves only).
pub fn compute_pvs(tree: &Tree, portals: &[Portal]) -> (Pvs, PvsStats) {
    let leaf_count = tree.leaves.len();
    let words = leaf_count.div_ceil(64);
    let mut directed = Vec::with_capacity(portals.len() * 2);
    for p in portals {
        directed.push(Directed {
            winding: p.polygon.vertices.clone(),
            plane: p.polygon.plane,
            from: p.back,
            to: p.front,
        });
        let flipped = p.polygon.flipped();
        directed.push(Directed {
            winding: flipped.vertices,
            plane: flipped.plane,
            from: p.front,
            to: p.back,
        });
    }
    let mut leaving: Vec<Vec<usize>> = vec![Vec::new(); leaf_count];
    for (i, d) in directed.iter().enumerate() {
        leaving[d.from as usize].push(i);
    }
    let might: Vec<Vec<u64>> = (0..directed.len())
        .map(|s| might_see(s, &directed, &leaving, words))
        .collect();
    let mut order: Vec<usize> = (0..directed.len()).collect();
    order.sort_by_key(|&s| might[s].iter().map(|w| w.count_ones()).sum::<u32>());

    let mut done: Vec<Option<Vec<u64>>> = vec![None; directed.len()];
    let mut steps = 0;
    for &s in &order {
        let mut flow = Flow {
            directed: &directed,
            leaving: &leaving,
            might: &might,
            done: &done,
            steps: 0,
        };
        let mut vis = vec![0u64; words];
        let mut path = vec![0u64; words];
        set_bit(&mut path, directed[s].from as usize);
        let d = &directed[s];
        flow.recurse(d.to, &d.winding, &d.plane, None, &might[s], &mut vis, &mut path);
        steps += flow.steps;
        done[s] = Some(vis);
    }

    let mut pvs = Pvs::empty(leaf_count);
    for (l, leaf) in tree.leaves.iter().enumerate() {
        if !leaf.solid {
            pvs.set(l, l);
        }
    }
    for (s, d) in directed.iter().enumerate() {
        let row = d.from as usize * words;
        for (w, bits) in done[s].iter().flatten().enumerate() {
            pvs.bits[row + w] |= bits;
        }
    }
    let mut stats = PvsStats {
        directed_portals: directed.len(),
        flow_steps: steps,
        ..Default::default()
    };
    for a in 0..leaf_count {
        for b in 0..leaf_count {
            if pvs.is_visible(a as LeafId, b as LeafId) && !pvs.is_visible(b as LeafId, a as LeafId) {
                pvs.set(b, a);
                stats.added_by_symmetry += 1;
            }
        }
    }
    stats.visible_pairs = (0..leaf_count)
        .map(|a| pvs.visible_leaves(a as LeafId).filter(|&b| b as usize != a).count())
        .sum();
    (pvs, stats)
}

fn set_bit(bits: &mut [u64], i: usize) {
    bits[i / 64] |= 1 << (i % 64);
}

fn get_bit(bits: &[u64], i: usize) -> bool {
    bits[i / 64] & (1 << (i % 64)) != 0
}

/// The leaves a flood from directed portal `s` reaches when every portal passed only has to lie
/// partly in front of `s`, with `s` partly behind it: a cheap superset of the real answer.
fn might_see(s: usize, directed: &[Directed], leaving: &[Vec<usize>], words: usize) -> Vec<u64> {
    let src = &directed[s];
    let mut seen = vec![0u64; words];
    let mut stack = vec![src.to];
    set_bit(&mut seen, src.to as usize);
    while let Some(leaf) = stack.pop() {
        for &p in &leaving[leaf as usize] {
            let d = &directed[p];
            let in_front = d.winding.iter().any(|&v| src.plane.distance(v) > VIS_SLACK);
            let source_behind = src.winding.iter().any(|&v| d.plane.distance(v) < -VIS_SLACK);
            if in_front && source_behind && !get_bit(&seen, d.to as usize) {
                set_bit(&mut seen, d.to as usize);
                stack.push(d.to);
            }
        }
    }
    seen
}

impl Flow<'_> {
    /// Light from `source` (in plane `source_plane`) has reached `leaf`, last through `pass`.
    #[allow(clippy::too_many_arguments)]
    fn recurse(
        &mut self,
        leaf: LeafId,
        source: &[DVec3],
        source_plane: &Plane,
        pass: Option<(&[DVec3], &Plane)>,
        might: &[u64],
        vis: &mut Vec<u64>,
        path: &mut Vec<u64>,
    ) {
        set_bit(vis, leaf as usize);
        set_bit(path, leaf as usize);
        for &p in &self.leaving[leaf as usize] {
            let d = &self.directed[p];
            let to = d.to as usize;
            // A straight line crosses a convex leaf once, and two portals of one plane only at
            // a graze.
            if !get_bit(might, to) || get_bit(path, to) || d.plane.coplanar_facing(source_plane).is_some() {
                continue;
            }
            if pass.is_some_and(|(_, pp)| d.plane.coplanar_facing(pp).is_some()) {
                continue;
            }
            let bound = self.done[p].as_ref().unwrap_or(&self.might[p]);
            let next_might: Vec<u64> = might.iter().zip(bound).map(|(a, b)| a & b).collect();
            let more = next_might.iter().zip(vis.iter()).any(|(m, v)| m & !v != 0);
            if !more && get_bit(vis, to) {
                continue; // nothing new can be found beyond
            }
            self.steps += 1;
            // The target must be beyond the source and the passed portal; the source must be
            // behind the target.
            let mut target = clip_points_front(&d.winding, source_plane, VIS_SLACK);
            if let Some((_, pass_plane)) = pass {
                target = clip_points_front(&target, pass_plane, VIS_SLACK);
            }
            if target.len() < 3 {
                continue;
            }
            let mut src = clip_points_front(source, &d.plane.flipped(), VIS_SLACK);
            if src.len() < 3 {
                continue;
            }
            if let Some((pass_winding, _)) = pass {
                target = clip_to_separators(&src, pass_winding, target);
                if target.len() < 3 {
                    continue;
                }
                // And backwards: only the part of the source that sees the target through the
                // passed portal matters further on.
                src = clip_to_separators(&target, pass_winding, src);
                if src.len() < 3 {
                    continue;
                }
            }
            self.recurse(
                d.to,
                &src,
                source_plane,
                Some((&target, &d.plane)),
                &next_might,
                vis,
                path,
            );
        }
        path[leaf as usize / 64] &= !(1 << (leaf as usize % 64));
    }
}

/// Clips `target` to the separating planes of `from` and `through`: planes through an edge of
/// one and a vertex of the other with `from` wholly behind and `through` wholly in front.
/// Every line from `from` through `through` stays in front of each such plane beyond `through`.
fn clip_to_separators(from: &[DVec3], through: &[DVec3], mut target: Vec<DVec3>) -> Vec<DVec3> {
    for (edges, vertices) in [(from, through), (through, from)] {
        for i in 0..edges.len() {
            let (e0, e1) = (edges[i], edges[(i + 1) % edges.len()]);
            for &v in vertices {
                let Some(mut plane) = Plane::from_points(e0, e1, v) else {
                    continue;
                };
                let range = |w: &[DVec3]| {
                    w.iter()
                        .map(|&p| plane.distance(p))
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)))
                };
                let ((from_lo, from_hi), (through_lo, through_hi)) = (range(from), range(through));
                let flat = |lo: f64, hi: f64| lo > -SEPARATOR_EPSILON && hi < SEPARATOR_EPSILON;
                if flat(from_lo, from_hi) && flat(through_lo, through_hi) {
                    continue; // both windings in the plane: it separates nothing
                }
                if from_hi <= SEPARATOR_EPSILON && through_lo >= -SEPARATOR_EPSILON {
                    // already oriented
                } else if from_lo >= -SEPARATOR_EPSILON && through_hi <= SEPARATOR_EPSILON {
                    plane = plane.flipped();
                } else {
                    continue;
                }
                target = clip_points_front(&target, &plane, VIS_SLACK);
                if target.len() < 3 {
                    return target;
                }
            }
        }
    }
    target
}
