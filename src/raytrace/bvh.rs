//! A bounding volume hierarchy over world-space triangles, built on the CPU with binned SAH and
//! flattened into the 32-byte nodes `glsl/reference/trace.glsl` walks.
//!
//! Layout: nodes are in depth-first order, so an interior node's first child is the next node;
//! `index` holds the second child. A leaf (`count > 0`) covers triangles
//! `index .. index + count` of the reordered triangle list ([`Bvh::order`] maps those slots back
//! to the input triangles).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::util::parallel::{cores, fold_ranges};

/// One node as the shader reads it (std430 `struct { vec3 lo; uint index; vec3 hi; uint count; }`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub lo: [f32; 3],
    /// Interior: the second child's node index (the first child is the next node). Leaf: the
    /// first triangle slot.
    pub index: u32,
    pub hi: [f32; 3],
    /// Triangles in the leaf; 0 marks an interior node.
    pub count: u32,
}

impl BvhNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// `order[slot]` is the input triangle stored at leaf slot `slot`.
    pub order: Vec<u32>,
    /// Deepest leaf (the root is depth 0); the shader's traversal stack holds [`MAX_DEPTH`].
    pub depth: u32,
}

/// Traversal stack size of the shader. The build switches to median splits, which halve the
/// triangle count, once SAH splits have gone `SAH_DEPTH` levels deep, so no leaf is deeper than
/// `SAH_DEPTH + 32`.
pub const MAX_DEPTH: u32 = 64;
const SAH_DEPTH: u32 = 24;
const BINS: usize = 16;
/// Leaves never hold more than this many triangles (unless they are all at one centroid).
const MAX_LEAF: usize = 8;
/// Cost of visiting a node relative to intersecting one triangle.
const TRAVERSAL_COST: f32 = 1.0;

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: Vec3,
    hi: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: Vec3::splat(f32::INFINITY),
        hi: Vec3::splat(f32::NEG_INFINITY),
    };
    fn grow(&mut self, p: Vec3) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }
    fn union(&mut self, o: &Aabb) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }
    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// Builds one subtree: over `order`, which holds slots `base .. base + order.len()` of the whole
/// build. Its nodes are numbered from 0; a subtree built on another thread is spliced into its
/// parent's nodes with its second-child indices shifted (leaf slots are already absolute).
struct Builder<'a> {
    bounds: &'a [Aabb],
    centroids: &'a [Vec3],
    order: &'a mut [u32],
    base: usize,
    nodes: Vec<BvhNode>,
    depth: u32,
    /// Threads this build may still start (shared by all its threads).
    spare_threads: &'a AtomicUsize,
    /// Threads a node's scans (bounds, SAH bins) may be shared among.
    scan_threads: usize,
}

/// A split's second subtree over at least this many triangles is built on a thread of its own
/// while the build has threads to spare. The tree is the same either way: each split depends
/// only on its own triangles.
const PARALLEL_MIN: usize = 8192;
/// Threads a build may run at once, per core. More than one: SAH splits are uneven, and with a
/// thread per core the largest subtree would keep one core busy while the others idle. Measured
/// on an NVIDIA H200 host's 16 cores with the top nodes' scans shared, a
/// 524k-triangle plane: 76–87 ms at 2 a core, 80–81 at 4, 83–100 at 1 (without shared scans),
/// 364–405 on one thread; four such planes, 2 M triangles: 345–364, 357–395, 427–443 and
/// 1,553–2,255 ms. On this 2-core machine one extra thread does best (87–100 ms against 108–111
/// at 2 a core), which is not worth a special case.
const THREADS_PER_CORE: usize = 2;
/// Slots one thread scans at least where a node's scans are shared (the top levels: below them
/// the subtrees themselves run on threads). On the H200 host the root's scans of 524k triangles
/// took 31 ms of a 90 ms build, all of it on one core.
const SCAN_PIECE: usize = 32_768;

impl Bvh {
    /// Builds over `tris` (world-space corners). An empty input gives an empty hierarchy.
    pub fn build(tris: &[[Vec3; 3]]) -> Bvh {
        let cores = cores();
        Bvh::build_on(tris, if cores > 1 { cores * THREADS_PER_CORE - 1 } else { 0 }, cores)
    }

    /// The build, with up to `threads` subtrees on threads of their own and a node's scans
    /// shared among up to `scan_threads` (the same tree: bins and bounds are unions and counts,
    /// whatever the order they are gathered in).
    fn build_on(tris: &[[Vec3; 3]], threads: usize, scan_threads: usize) -> Bvh {
        if tris.is_empty() {
            return Bvh::default();
        }
        let (bounds, centroids) = fold_ranges(
            tris.len(),
            scan_threads,
            SCAN_PIECE,
            |range| {
                let bounds: Vec<Aabb> = tris[range]
                    .iter()
                    .map(|t| {
                        let mut b = Aabb::EMPTY;
                        t.iter().for_each(|&p| b.grow(p));
                        b
                    })
                    .collect();
                let centroids: Vec<Vec3> = bounds.iter().map(|b| 0.5 * (b.lo + b.hi)).collect();
                (bounds, centroids)
            },
            |(mut bounds, mut centroids), (b, c)| {
                bounds.extend(b);
                centroids.extend(c);
                (bounds, centroids)
            },
        );
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let spare_threads = AtomicUsize::new(threads);
        let mut b = Builder {
            bounds: &bounds,
            centroids: &centroids,
            order: &mut order,
            base: 0,
            nodes: Vec::new(),
            depth: 0,
            spare_threads: &spare_threads,
            scan_threads,
        };
        b.node(0, tris.len(), 0);
        let (nodes, depth) = (b.nodes, b.depth);
        Bvh { nodes, order, depth }
    }
}

impl Bvh {
    /// Per node, the index of the node that follows its subtree in storage order (preorder: an
    /// interior node's first child is the next node), `nodes.len()` past the last one. With them a
    /// shadow ray walks the tree without a stack: into a node whose box it enters, past its
    /// subtree (to its skip link) when it misses (glsl/common/bvh.glsl's `occluded`).
    pub fn skip_links(&self) -> Vec<u32> {
        let mut skip = vec![0u32; self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let n = &self.nodes[i];
            // The second child comes after the first child's subtree, so its link is known.
            skip[i] = if n.is_leaf() {
                i as u32 + 1
            } else {
                skip[n.index as usize]
            };
        }
        skip
    }

    /// Per node and ray octant (bit k set where the direction's component k is negative), the
    /// node that follows its subtree when every interior node's children are taken in the order
    /// that octant gives them, `nodes.len()` past the last; bit 31 of an interior node's word
    /// says that octant takes its second child first. A child goes first where the ray runs
    /// from its centre toward the other's along the axis that separates their centres most,
    /// so a closest-hit walk without a stack meets nearer boxes first, as a stack walk taking
    /// the nearer child first would (glsl/common/bvh.glsl's `trace_triangles_ordered`). Eight
    /// words a node, octant-major within the node.
    pub fn octant_skip_links(&self) -> Vec<u32> {
        const SECOND_FIRST: u32 = 1 << 31;
        let count = self.nodes.len();
        let mut words = vec![0u32; 8 * count];
        if count == 0 {
            return words;
        }
        let centre = |n: &BvhNode| (Vec3::from(n.lo) + Vec3::from(n.hi)) * 0.5;
        // The root's link is the end. In preorder a node's link is set (by its parent) before
        // the node is reached, and its flag only when it is.
        words[..8].fill(count as u32);
        for i in 0..count {
            let n = self.nodes[i];
            if n.is_leaf() {
                continue;
            }
            let (first, second) = (i + 1, n.index as usize);
            let gap = centre(&self.nodes[second]) - centre(&self.nodes[first]);
            let spread = gap.abs();
            let axis = if spread.x >= spread.y && spread.x >= spread.z {
                0
            } else if spread.y >= spread.z {
                1
            } else {
                2
            };
            for oct in 0..8 {
                let negative = oct & (1 << axis) != 0;
                // The second child goes first where it lies behind the first along the ray.
                let second_first = if negative { gap[axis] > 0.0 } else { gap[axis] < 0.0 };
                let (a, b) = if second_first { (second, first) } else { (first, second) };
                words[8 * a + oct] = b as u32;
                words[8 * b + oct] = words[8 * i + oct];
                if second_first {
                    words[8 * i + oct] |= SECOND_FIRST;
                }
            }
        }
        words
    }
}

impl Builder<'_> {
    /// The triangles at slots `start..end` (slots count from the whole build's first).
    fn slots(&self, start: usize, end: usize) -> &[u32] {
        &self.order[start - self.base..end - self.base]
    }

    fn slots_mut(&mut self, start: usize, end: usize) -> &mut [u32] {
        &mut self.order[start - self.base..end - self.base]
    }

    fn range_bounds(&self, start: usize, end: usize) -> (Aabb, Aabb) {
        let (slots, bounds, centroids) = (self.slots(start, end), self.bounds, self.centroids);
        fold_ranges(
            slots.len(),
            self.scan_threads,
            SCAN_PIECE,
            |range| {
                let (mut all, mut cent) = (Aabb::EMPTY, Aabb::EMPTY);
                for &t in &slots[range] {
                    all.union(&bounds[t as usize]);
                    cent.grow(centroids[t as usize]);
                }
                (all, cent)
            },
            |(mut all, mut cent), (a, c)| {
                all.union(&a);
                cent.union(&c);
                (all, cent)
            },
        )
    }

    /// Appends the subtree over slots `start..end` and returns its root's index.
    fn node(&mut self, start: usize, end: usize, depth: u32) -> u32 {
        let (bounds, cent) = self.range_bounds(start, end);
        let id = self.nodes.len() as u32;
        self.nodes.push(BvhNode {
            lo: bounds.lo.into(),
            index: start as u32,
            hi: bounds.hi.into(),
            count: (end - start) as u32,
        });
        self.depth = self.depth.max(depth);
        let n = end - start;
        let extent = cent.hi - cent.lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if n == 1 || extent[axis] <= 0.0 {
            // One triangle, or all centroids coincide: no split can separate them.
            return id;
        }
        let mid = if depth < SAH_DEPTH {
            match self.sah_split(start, end, &bounds, &cent) {
                Some(mid) => mid,
                None if n <= MAX_LEAF => return id,
                None => self.median_split(start, end, axis),
            }
        } else {
            self.median_split(start, end, axis)
        };
        self.nodes[id as usize].count = 0;
        if end - mid >= PARALLEL_MIN && take_thread(self.spare_threads) {
            let second = self.split_in_parallel(start, mid, end, depth + 1);
            self.nodes[id as usize].index = second;
            return id;
        }
        self.node(start, mid, depth + 1);
        let second = self.node(mid, end, depth + 1);
        self.nodes[id as usize].index = second;
        id
    }

    /// Builds the two children of a split at `mid`, the second on another thread (whose share
    /// of the budget the caller took, and which gives it back when done), and appends both
    /// (first child first, as the serial build does); returns the second child's index. Where
    /// the system gives no thread, the second is built after the first on this one, and the
    /// build starts no more.
    fn split_in_parallel(&mut self, start: usize, mid: usize, end: usize, depth: u32) -> u32 {
        let (bounds, centroids, spare_threads, scan_threads) =
            (self.bounds, self.centroids, self.spare_threads, self.scan_threads);
        // The first subtree is built straight into this builder's nodes (its indices are then
        // already where they stay); only the second, built on the other thread, is copied in.
        // Copying both cost the top levels of a 2 M-triangle build a copy of every node below
        // them per level.
        let own = std::mem::take(&mut self.nodes);
        let (first, second) = self.slots_mut(start, end).split_at_mut(mid - start);
        let subtree = move |order: &mut [u32], base: usize, end: usize, nodes: Vec<BvhNode>| {
            let mut b = Builder {
                bounds,
                centroids,
                order,
                base,
                nodes,
                depth: 0,
                spare_threads,
                scan_threads,
            };
            b.node(base, end, depth);
            (b.nodes, b.depth)
        };
        let (own, built) = std::thread::scope(|scope| {
            let Ok(right) = std::thread::Builder::new().spawn_scoped(scope, move || {
                let built = subtree(second, mid, end, Vec::new());
                spare_threads.fetch_add(1, Ordering::Relaxed);
                built
            }) else {
                return (own, None);
            };
            let (own, first_depth) = subtree(first, start, mid, own);
            // A panic in the thread is a bug in this builder; carry it to the caller.
            (
                own,
                Some((
                    first_depth,
                    right.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
                )),
            )
        });
        self.nodes = own;
        let Some((first_depth, (second_nodes, second_depth))) = built else {
            // No thread to be had: both children here, one after the other (the same tree).
            self.spare_threads.store(0, Ordering::Relaxed);
            self.node(start, mid, depth);
            return self.node(mid, end, depth);
        };
        let offset = self.nodes.len() as u32;
        self.nodes.extend(second_nodes.into_iter().map(|n| {
            if n.is_leaf() {
                n
            } else {
                BvhNode {
                    index: n.index + offset,
                    ..n
                }
            }
        }));
        self.depth = self.depth.max(first_depth).max(second_depth);
        offset
    }

    /// The best binned-SAH partition over all three axes, or `None` when a leaf is cheaper.
    fn sah_split(&mut self, start: usize, end: usize, bounds: &Aabb, cent: &Aabb) -> Option<usize> {
        let n = end - start;
        // Per axis the centroids' range as (lo, bins per unit), or none where they coincide.
        let axes: [Option<(f32, f32)>; 3] = std::array::from_fn(|axis| {
            let (lo, hi) = (cent.lo[axis], cent.hi[axis]);
            (hi > lo).then(|| (lo, BINS as f32 / (hi - lo)))
        });
        let bin_of = |c: f32, (lo, scale): (f32, f32)| (((c - lo) * scale) as usize).min(BINS - 1);
        // Every axis's bins in one pass over the slots, in pieces on threads at the top levels.
        let (slots, bounds_of, centroids) = (self.slots(start, end), self.bounds, self.centroids);
        let all_bins = fold_ranges(
            n,
            self.scan_threads,
            SCAN_PIECE,
            |range| {
                let mut bins = [[(Aabb::EMPTY, 0usize); BINS]; 3];
                for &t in &slots[range] {
                    let (c, b) = (centroids[t as usize], &bounds_of[t as usize]);
                    for (axis, range) in axes.iter().enumerate() {
                        if let Some(range) = *range {
                            let bin = &mut bins[axis][bin_of(c[axis], range)];
                            bin.0.union(b);
                            bin.1 += 1;
                        }
                    }
                }
                bins
            },
            |mut all, piece| {
                for (into, from) in all.iter_mut().flatten().zip(piece.iter().flatten()) {
                    into.0.union(&from.0);
                    into.1 += from.1;
                }
                all
            },
        );
        let mut best: Option<(f32, usize, usize)> = None; // cost, axis, bins left of the split
        for (axis, bins) in all_bins.iter().enumerate() {
            if axes[axis].is_none() {
                continue;
            }
            // Sweep from the right to get each suffix's area × count, then from the left.
            let mut right_cost = [0.0f32; BINS];
            let (mut acc, mut count) = (Aabb::EMPTY, 0);
            for i in (1..BINS).rev() {
                acc.union(&bins[i].0);
                count += bins[i].1;
                right_cost[i] = acc.half_area() * count as f32;
            }
            let (mut acc, mut count) = (Aabb::EMPTY, 0);
            for i in 0..BINS - 1 {
                acc.union(&bins[i].0);
                count += bins[i].1;
                if count == 0 || count == n {
                    continue;
                }
                let cost = acc.half_area() * count as f32 + right_cost[i + 1];
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, axis, i + 1));
                }
            }
        }
        let (cost, axis, left_bins) = best?;
        let area = bounds.half_area().max(f32::MIN_POSITIVE);
        let split_cost = TRAVERSAL_COST + cost / area;
        if n <= MAX_LEAF && split_cost >= n as f32 {
            return None;
        }
        let (lo, hi) = (cent.lo[axis], cent.hi[axis]);
        let scale = BINS as f32 / (hi - lo);
        let centroids = self.centroids;
        let slice = self.slots_mut(start, end);
        let left = partition(slice, |&t| {
            (((centroids[t as usize][axis] - lo) * scale) as usize).min(BINS - 1) < left_bins
        });
        Some(start + left)
    }

    /// Splits at the median centroid along `axis` (halves the count: bounds the depth).
    fn median_split(&mut self, start: usize, end: usize, axis: usize) -> usize {
        let mid = start + (end - start) / 2;
        let centroids = self.centroids;
        self.slots_mut(start, end).select_nth_unstable_by(mid - start, |a, b| {
            centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
        });
        mid
    }
}

/// Takes one thread from the build's budget, if it has one left.
fn take_thread(spare: &AtomicUsize) -> bool {
    spare
        .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1))
        .is_ok()
}

/// Moves the elements satisfying `pred` to the front; returns how many there are.
fn partition<T>(s: &mut [T], pred: impl Fn(&T) -> bool) -> usize {
    let mut left = 0;
    for i in 0..s.len() {
        if pred(&s[i]) {
            s.swap(i, left);
            left += 1;
        }
    }
    left
}

/// Möller–Trumbore; the same arithmetic as `intersect_triangle` in the shader. Returns the
/// distance and barycentrics (u, v) of a hit with `0 < t < t_max`.
pub fn intersect_triangle(o: Vec3, d: Vec3, p0: Vec3, e1: Vec3, e2: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (t > 0.0 && t < t_max).then_some((t, u, v))
}

/// Entry distance of the ray into the box, or `None` when it misses within `[0, t_max]`.
pub fn box_entry(lo: Vec3, hi: Vec3, o: Vec3, inv_d: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let enter = t0.min(t1).max_element().max(0.0);
    let exit = t0.max(t1).min_element().min(t_max);
    (enter <= exit).then_some(enter)
}

/// `1 / d` with zero components replaced by a tiny value, so slab tests never compute 0 × ∞.
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let f = |x: f32| 1.0 / if x == 0.0 { 1e-30 } else { x };
    Vec3::new(f(d.x), f(d.y), f(d.z))
}

impl Bvh {
    /// Whether `hit` holds for some input triangle in a leaf whose box overlaps [`lo`, `hi`]
    /// (a superset of the triangles whose boxes overlap it); stops at the first that does.
    pub fn any_in_box(&self, lo: Vec3, hi: Vec3, mut hit: impl FnMut(u32) -> bool) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let overlaps = |n: &BvhNode| !(Vec3::from(n.hi).cmplt(lo).any() || Vec3::from(n.lo).cmpgt(hi).any());
        let mut stack = vec![0u32];
        while let Some(node) = stack.pop() {
            let n = &self.nodes[node as usize];
            if !overlaps(n) {
                continue;
            }
            if n.is_leaf() {
                if (n.index..n.index + n.count).any(|slot| hit(self.order[slot as usize])) {
                    return true;
                }
            } else {
                stack.push(n.index);
                stack.push(node + 1);
            }
        }
        false
    }

    /// Closest hit of the ray among `tris` (indexed like the input of [`Bvh::build`]): the
    /// distance and the input triangle. The CPU twin of `trace_closest` in the shader.
    pub fn closest_hit(&self, tris: &[[Vec3; 3]], o: Vec3, d: Vec3) -> Option<(f32, u32)> {
        let inv_d = safe_inverse(d);
        let mut best: Option<(f32, u32)> = None;
        let mut t_max = f32::INFINITY;
        let root = self.nodes.first()?;
        box_entry(root.lo.into(), root.hi.into(), o, inv_d, t_max)?;
        let mut stack: Vec<(u32, f32)> = Vec::new();
        let mut node = 0u32;
        loop {
            let n = &self.nodes[node as usize];
            if n.is_leaf() {
                for slot in n.index..n.index + n.count {
                    let tri = self.order[slot as usize];
                    let [p0, p1, p2] = tris[tri as usize];
                    if let Some((t, _, _)) = intersect_triangle(o, d, p0, p1 - p0, p2 - p0, t_max) {
                        t_max = t;
                        best = Some((t, tri));
                    }
                }
            } else {
                let (mut a, mut b) = (node + 1, n.index);
                let entry = |i: u32| {
                    let c = &self.nodes[i as usize];
                    box_entry(c.lo.into(), c.hi.into(), o, inv_d, t_max)
                };
                let (mut ta, mut tb) = (entry(a), entry(b));
                if tb.unwrap_or(f32::INFINITY) < ta.unwrap_or(f32::INFINITY) {
                    std::mem::swap(&mut a, &mut b);
                    std::mem::swap(&mut ta, &mut tb);
                }
                if ta.is_some() {
                    if let Some(tb) = tb {
                        stack.push((b, tb));
                    }
                    node = a;
                    continue;
                }
            }
            // Continue with the most recently deferred subtree that can still hold a closer hit.
            loop {
                match stack.pop() {
                    None => return best,
                    Some((next, t)) if t < t_max => {
                        node = next;
                        break;
                    }
                    Some(_) => {}
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (the tests must not depend on a crate's RNG).
    struct Lcg(u64);
    impl Lcg {
        fn f(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn v(&mut self, scale: f32) -> Vec3 {
            Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5) * scale
        }
    }

    fn soup(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut r = Lcg(seed);
        (0..n)
            .map(|_| {
                let c = r.v(10.0);
                [c + r.v(1.0), c + r.v(1.0), c + r.v(1.0)]
            })
            .collect()
    }

    /// A tessellated sphere and an axis-aligned floor: shared edges, thin boxes, coplanar faces.
    fn structured() -> Vec<[Vec3; 3]> {
        let s = crate::scene::generators::sphere(1.0, 24, 12);
        let p = crate::scene::generators::plane(glam::Vec2::splat(6.0), 8);
        let mut out = Vec::new();
        for (m, off) in [(&s, Vec3::new(0.0, 1.0, 0.0)), (&p, Vec3::ZERO)] {
            for t in m.triangles() {
                out.push(t.map(|i| m.positions[i] + off));
            }
        }
        out
    }

    /// Ray `k` of a test: from anywhere around the soups, some aimed at the geometry, some
    /// axis-aligned (zero direction components); none where the direction is zero.
    fn test_ray(r: &mut Lcg, k: usize) -> Option<(Vec3, Vec3)> {
        let o = r.v(14.0);
        let d = match k % 3 {
            0 => r.v(1.0),
            1 => r.v(4.0) - o,
            _ => [Vec3::X, Vec3::NEG_Y, Vec3::Z][k % 9 / 3],
        };
        Some((o, d.try_normalize()?))
    }

    fn brute_force(tris: &[[Vec3; 3]], o: Vec3, d: Vec3) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        for (i, [p0, p1, p2]) in tris.iter().enumerate() {
            let t_max = best.map_or(f32::INFINITY, |b| b.0);
            if let Some((t, _, _)) = intersect_triangle(o, d, *p0, *p1 - *p0, *p2 - *p0, t_max) {
                best = Some((t, i as u32));
            }
        }
        best
    }

    /// Walks the tree: leaves partition the slots, every triangle lies in every ancestor's box.
    fn check_structure(bvh: &Bvh, tris: &[[Vec3; 3]]) {
        let mut seen = vec![0u32; tris.len()];
        let mut slots = vec![0u32; tris.len()];
        let mut stack = vec![(0u32, 0u32, Vec::<u32>::new())];
        let mut max_depth = 0;
        while let Some((i, depth, ancestors)) = stack.pop() {
            let n = bvh.nodes[i as usize];
            max_depth = max_depth.max(depth);
            let mut path = ancestors.clone();
            path.push(i);
            if n.is_leaf() {
                for slot in n.index..n.index + n.count {
                    slots[slot as usize] += 1;
                    let t = bvh.order[slot as usize];
                    seen[t as usize] += 1;
                    for &a in &path {
                        let b = bvh.nodes[a as usize];
                        for p in tris[t as usize] {
                            assert!(
                                p.cmpge(b.lo.into()).all() && p.cmple(b.hi.into()).all(),
                                "triangle {t} outside node {a}"
                            );
                        }
                    }
                }
            } else {
                assert!(
                    n.index > i + 1 && (n.index as usize) < bvh.nodes.len(),
                    "node {i}: second child {}",
                    n.index
                );
                stack.push((i + 1, depth + 1, path.clone()));
                stack.push((n.index, depth + 1, path));
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "every triangle reachable exactly once");
        assert!(slots.iter().all(|&c| c == 1), "leaves partition the slots");
        assert_eq!(max_depth, bvh.depth);
        assert!(bvh.depth < MAX_DEPTH);
    }

    #[test]
    fn every_triangle_is_reachable_exactly_once() {
        for tris in [soup(1, 1), soup(2, 2), soup(7, 3), soup(1000, 4), structured()] {
            let bvh = Bvh::build(&tris);
            check_structure(&bvh, &tris);
        }
        // Degenerate inputs: all triangles at one spot, and a long line of them.
        let same = vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 100];
        check_structure(&Bvh::build(&same), &same);
        let line: Vec<_> = (0..5000)
            .map(|i| {
                [
                    Vec3::X * i as f32,
                    Vec3::X * i as f32 + Vec3::Y,
                    Vec3::X * i as f32 + Vec3::Z,
                ]
            })
            .collect();
        check_structure(&Bvh::build(&line), &line);
        assert!(Bvh::build(&[]).nodes.is_empty());
    }

    /// The threaded build gives the serial build's tree, node for node and slot for slot, on
    /// inputs large enough to be split across threads (and one that is not), and with the top
    /// nodes' scans in pieces.
    #[test]
    fn the_parallel_build_equals_the_serial_one() {
        let grid: Vec<_> = (0..40_000)
            .map(|i| {
                let c = Vec3::new((i % 200) as f32, ((i / 200) % 200) as f32 * 0.5, (i % 7) as f32);
                [c, c + Vec3::X, c + Vec3::Y]
            })
            .collect();
        // A large cluster and a small one far away: the root's second child is too small for a
        // thread, so it is built here after the first child's threaded subtrees.
        let lopsided: Vec<_> = soup(40_000, 14)
            .into_iter()
            .chain(soup(5_000, 15).into_iter().map(|t| t.map(|p| p + Vec3::X * 1000.0)))
            .collect();
        for tris in [soup(60_000, 8), grid, soup(3_000, 9), lopsided] {
            let b = Bvh::build_on(&tris, 0, 1);
            // A budget that runs out leaves nodes built here after subtrees built on threads
            // (grafted before them when the tree is flattened); a large one threads every split
            // it can.
            for threads in [1, 2, 3, 63] {
                let a = Bvh::build_on(&tris, threads, 5);
                assert_eq!(a.order, b.order);
                assert_eq!(a.nodes, b.nodes, "{threads} threads");
                assert_eq!(a.depth, b.depth);
                check_structure(&a, &tris);
            }
        }
        // Large enough that the top nodes' scans are split among threads (5 pieces at the root).
        let big = soup(5 * SCAN_PIECE + 1000, 10);
        let (a, b) = (Bvh::build_on(&big, 63, 5), Bvh::build_on(&big, 0, 1));
        assert_eq!(a.order, b.order);
        assert_eq!(a.nodes, b.nodes);
    }

    #[test]
    fn traversal_equals_brute_force() {
        let mut r = Lcg(99);
        for tris in [soup(500, 5), structured()] {
            let bvh = Bvh::build(&tris);
            let mut hits = 0;
            for k in 0..3000 {
                let Some((o, d)) = test_ray(&mut r, k) else { continue };
                let (a, b) = (bvh.closest_hit(&tris, o, d), brute_force(&tris, o, d));
                match (a, b) {
                    (None, None) => {}
                    (Some(a), Some(b)) => {
                        hits += 1;
                        // The triangles may differ only where two share an edge, at equal distance.
                        assert_eq!(a.0, b.0, "ray {k}: bvh {a:?} vs brute force {b:?}");
                    }
                    _ => panic!("ray {k} from {o} along {d}: bvh {a:?} vs brute force {b:?}"),
                }
            }
            assert!(hits > 500, "enough rays hit something ({hits})");
        }
    }

    /// The stackless walk of glsl/common/bvh.glsl's `occluded`, by the skip links.
    fn occluded_by_skip_links(
        bvh: &Bvh,
        skip: &[u32],
        tris: &[[Vec3; 3]],
        o: Vec3,
        d: Vec3,
        t_max: f32,
    ) -> (bool, usize) {
        let inv_d = safe_inverse(d);
        let (mut node, mut visited) = (0usize, 0usize);
        while node < bvh.nodes.len() {
            visited += 1;
            let n = &bvh.nodes[node];
            if box_entry(n.lo.into(), n.hi.into(), o, inv_d, t_max).is_none() {
                node = skip[node] as usize;
                continue;
            }
            if n.is_leaf() {
                for slot in n.index..n.index + n.count {
                    let [a, b, c] = tris[bvh.order[slot as usize] as usize];
                    if intersect_triangle(o, d, a, b - a, c - a, t_max).is_some() {
                        return (true, visited);
                    }
                }
                node = skip[node] as usize;
            } else {
                node += 1;
            }
        }
        (false, visited)
    }

    #[test]
    fn skip_links_walk_the_tree_once_and_find_what_brute_force_finds() {
        let mut r = Lcg(7);
        for tris in [soup(500, 11), structured()] {
            let bvh = Bvh::build(&tris);
            let skip = bvh.skip_links();
            for (i, &s) in skip.iter().enumerate() {
                assert!(s as usize > i && s as usize <= bvh.nodes.len(), "node {i}: skip {s}");
            }
            let mut blocked = 0;
            for k in 0..3000 {
                let (o, to) = (r.v(14.0), r.v(6.0));
                let Some(d) = (to - o).try_normalize() else { continue };
                let t_max = (to - o).length();
                let truth = brute_force(&tris, o, d).is_some_and(|(t, _)| t < t_max);
                let (hit, visited) = occluded_by_skip_links(&bvh, &skip, &tris, o, d, t_max);
                assert_eq!(hit, truth, "ray {k} from {o} to {to}");
                assert!(visited <= bvh.nodes.len());
                blocked += usize::from(hit);
            }
            assert!(
                blocked > 300 && blocked < 2700,
                "a mix of blocked and free segments ({blocked})"
            );
        }
    }

    /// The stackless walk of glsl/common/bvh.glsl's `trace_triangles_ordered`: the closest hit
    /// and the nodes visited, in order.
    fn closest_by_octant_links(
        bvh: &Bvh,
        words: &[u32],
        tris: &[[Vec3; 3]],
        o: Vec3,
        d: Vec3,
        mut t_max: f32,
    ) -> (Option<(f32, u32)>, Vec<usize>) {
        let inv_d = safe_inverse(d);
        let octant = usize::from(d.x < 0.0) | usize::from(d.y < 0.0) << 1 | usize::from(d.z < 0.0) << 2;
        let (mut node, mut visited, mut hit) = (0usize, Vec::new(), None);
        let end = bvh.nodes.len();
        while node < end {
            visited.push(node);
            assert!(visited.len() <= end, "the walk visits a node twice");
            let n = &bvh.nodes[node];
            let word = words[8 * node + octant];
            let skip = (word & 0x7fff_ffff) as usize;
            if box_entry(n.lo.into(), n.hi.into(), o, inv_d, t_max).is_none() {
                node = skip;
            } else if n.is_leaf() {
                for slot in n.index..n.index + n.count {
                    let [a, b, c] = tris[bvh.order[slot as usize] as usize];
                    if let Some((t, _, _)) = intersect_triangle(o, d, a, b - a, c - a, t_max) {
                        t_max = t;
                        hit = Some((t, bvh.order[slot as usize]));
                    }
                }
                node = skip;
            } else {
                node = if word >> 31 != 0 { n.index as usize } else { node + 1 };
            }
        }
        (hit, visited)
    }

    #[test]
    fn octant_links_walk_every_node_once_nearer_child_first_and_find_the_closest_hit() {
        let mut r = Lcg(21);
        for tris in [soup(500, 12), structured(), soup(1, 13)] {
            let bvh = Bvh::build(&tris);
            let words = bvh.octant_skip_links();
            assert_eq!(words.len(), 8 * bvh.nodes.len());
            // Every box entered: each octant's order visits every node exactly once, a parent
            // before its children (a preorder of the tree).
            let big = Bvh {
                nodes: bvh
                    .nodes
                    .iter()
                    .map(|n| BvhNode {
                        lo: [-1e9; 3],
                        hi: [1e9; 3],
                        ..*n
                    })
                    .collect(),
                ..bvh.clone()
            };
            for octant in 0..8 {
                let d = Vec3::new(
                    if octant & 1 != 0 { -1.0 } else { 1.0 },
                    if octant & 2 != 0 { -1.0 } else { 1.0 },
                    if octant & 4 != 0 { -1.0 } else { 1.0 },
                )
                .normalize();
                let (_, visited) = closest_by_octant_links(&big, &words, &tris, Vec3::ZERO, d, f32::MAX);
                let mut seen = vec![0; bvh.nodes.len()];
                let mut position = vec![0; bvh.nodes.len()];
                for (k, &n) in visited.iter().enumerate() {
                    seen[n] += 1;
                    position[n] = k;
                }
                assert!(seen.iter().all(|&c| c == 1), "octant {octant}: every node once");
                for (i, n) in bvh.nodes.iter().enumerate().filter(|(_, n)| !n.is_leaf()) {
                    let (a, b) = (i + 1, n.index as usize);
                    assert!(
                        position[a] > position[i] && position[b] > position[i],
                        "octant {octant}: node {i} before its children"
                    );
                    // The child taken first is the one the direction leaves behind.
                    let centre = |k: usize| (Vec3::from(bvh.nodes[k].lo) + Vec3::from(bvh.nodes[k].hi)) * 0.5;
                    let gap = centre(b) - centre(a);
                    let g = gap.abs();
                    let axis = if g.x >= g.y && g.x >= g.z {
                        0
                    } else if g.y >= g.z {
                        1
                    } else {
                        2
                    };
                    let first = if gap[axis] * d[axis] >= 0.0 { a } else { b };
                    assert!(
                        position[first] < position[a + b - first],
                        "octant {octant}: node {i} takes {first} first"
                    );
                }
            }
            for k in 0..3000 {
                let Some((o, d)) = test_ray(&mut r, k) else { continue };
                let (hit, _) = closest_by_octant_links(&bvh, &words, &tris, o, d, f32::MAX);
                assert_eq!(
                    hit.map(|h| h.0),
                    brute_force(&tris, o, d).map(|h| h.0),
                    "ray {k} from {o} along {d}"
                );
            }
        }
    }

    #[test]
    fn node_layout_is_32_bytes() {
        assert_eq!(std::mem::size_of::<BvhNode>(), 32);
    }

    /// Build time against the thread budget and shared scans, on a 524k-triangle plane and four
    /// of them: `cargo test --release --lib measure_build_time -- --ignored --nocapture` (the
    /// H200 host's numbers in THREADS_PER_CORE's comment came from it).
    #[test]
    #[ignore]
    fn measure_build_time_against_threads() {
        let plane = crate::scene::generators::plane(glam::Vec2::splat(3.0), 1000);
        let one: Vec<[Vec3; 3]> = plane.triangles().map(|t| t.map(|i| plane.positions[i])).collect();
        let four: Vec<[Vec3; 3]> = (0..4)
            .flat_map(|k| one.iter().map(move |t| t.map(|p| p + Vec3::X * (3.0 * k as f32))))
            .collect();
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        for tris in [&one, &four] {
            eprintln!("{} triangles, {cores} cores", tris.len());
            for (threads, scans) in [
                (0, 1),
                (cores - 1, 1),
                (cores * 2 - 1, 1),
                (cores * 2 - 1, cores),
                (cores * 4 - 1, 1),
                (cores * 4 - 1, cores),
            ] {
                let times: Vec<f64> = (0..3)
                    .map(|_| {
                        let t = std::time::Instant::now();
                        std::hint::black_box(Bvh::build_on(tris, threads, scans));
                        t.elapsed().as_secs_f64() * 1e3
                    })
                    .collect();
                eprintln!(
                    "threads {threads:2} scans {scans:2}: {:.0} {:.0} {:.0} ms",
                    times[0], times[1], times[2]
                );
            }
        }
    }
}
