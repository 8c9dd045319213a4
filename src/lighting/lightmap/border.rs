//! Border post-processing (the Ca3D-Engine thesis §3.3.6, digest §1.2 step G). The renderer filters light-maps
//! bilinearly, so the texels around a polygon's edge are read too: those that no shot gave a
//! value must not read black (pass 1), and where two coplanar charts meet, both must hold the
//! same values near the seam or a shadow crossing it steps (pass 2). Pass 2 must not carry light
//! through a wall thinner than a patch: a neighbour's patch counts only if a ray from inside the
//! own polygon reaches it (the anti-bleeding check).

use glam::DVec3;

use super::patches::Patches;
use super::solve::Occluders;

/// Both passes over `values` (one per patch; those of patches outside their polygon are
/// ignored and replaced). Returns how many contributions the anti-bleeding check refused.
pub fn apply(p: &Patches, occluders: &Occluders, values: &mut [DVec3]) -> usize {
    let plan = Plan::new(p, occluders);
    for pass in &plan.passes {
        let source = values.to_vec();
        for (dst, sources) in pass {
            values[*dst] = sources.iter().map(|&(k, w)| source[k] * w).sum();
        }
    }
    plan.refused
}

/// Each pass as a linear map: the patches it replaces, each with its sources and weights (an
/// empty list is 0). RGB light-maps and CaSHL's coefficient vectors (the Ca3D-Engine thesis §5.4.4) go through
/// the same plan.
/// One pass: each patch it replaces, with its sources and their weights.
pub type Pass = Vec<(usize, Vec<(usize, f64)>)>;

pub struct Plan {
    pub passes: [Pass; 2],
    /// Pass 2's contributions refused by the anti-bleeding ray.
    pub refused: usize,
}

impl Plan {
    pub fn new(p: &Patches, occluders: &Occluders) -> Plan {
        let (second, refused) = pass2_plan(p, occluders);
        Plan {
            passes: [pass1_plan(p), second],
            refused,
        }
    }

    /// Applies pass 1 then pass 2 to `dim` values per patch (patch k's at `k·dim..`); each pass
    /// reads the values as they were before it.
    pub fn apply_flat(&self, values: &mut [f64], dim: usize) {
        for pass in &self.passes {
            let source = values.to_vec();
            for (dst, sources) in pass {
                for d in 0..dim {
                    values[dst * dim + d] = sources.iter().map(|&(k, w)| source[k * dim + d] * w).sum();
                }
            }
        }
    }
}

/// Pass 1: every patch outside its polygon takes the mean of its inside 8-neighbours (0 without any).
pub fn pass1(p: &Patches, values: &mut [DVec3]) {
    // Pass 1 reads inside patches only and writes outside ones: in place is exact.
    for (dst, sources) in pass1_plan(p) {
        values[dst] = sources.iter().map(|&(k, w)| values[k] * w).sum();
    }
}

fn pass1_plan(p: &Patches) -> Pass {
    let mut out = Vec::new();
    for c in &p.charts {
        let at = |i: usize, j: usize| c.first + j * c.width + i;
        for j in 0..c.height {
            for i in 0..c.width {
                let k = at(i, j);
                if p.patches[k].inside() {
                    continue;
                }
                let inside: Vec<usize> = neighbours(i, j, c.width, c.height)
                    .map(|(ni, nj)| at(ni, nj))
                    .filter(|&n| p.patches[n].inside())
                    .collect();
                let w = 1.0 / inside.len().max(1) as f64;
                out.push((k, inside.into_iter().map(|n| (n, w)).collect()));
            }
        }
    }
    out
}

fn neighbours(i: usize, j: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    (-1i64..=1)
        .flat_map(move |dj| (-1i64..=1).map(move |di| (i as i64 + di, j as i64 + dj)))
        .filter(move |&(ni, nj)| {
            (ni, nj) != (i as i64, j as i64) && ni >= 0 && nj >= 0 && (ni as usize) < w && (nj as usize) < h
        })
        .map(|(ni, nj)| (ni as usize, nj as usize))
}

/// Two charts are coplanar when they face the same way within this cosine and their planes lie
/// within this fraction of a patch: then their world-aligned grids coincide.
const COPLANAR_COS: f64 = 1.0 - 1e-4;
const COPLANAR_OFFSET: f64 = 1e-3;

/// Pass 2 (CaLight's SHL version, which the light-maps' needs match): each OUTER or PARTIAL
/// patch takes the area-weighted mean of the INNER or PARTIAL patches that cover the same world
/// cell in coplanar charts (a PARTIAL one counting its own value too), each accepted only if a
/// ray from a point of the own polygon near the patch reaches its sample point; the weights are
/// renormalised over those accepted. Returns how many were refused.
pub fn pass2(p: &Patches, occluders: &Occluders, values: &mut [DVec3]) -> usize {
    let (plan, refused) = pass2_plan(p, occluders);
    let source = values.to_vec();
    for (dst, sources) in plan {
        values[dst] = sources.iter().map(|&(k, w)| source[k] * w).sum();
    }
    refused
}

/// How far above the surface, in patches, pass 2's anti-bleeding ray runs. A hair above it, the
/// ray passed under a wall modelled a few tenths of a millimetre above the floor (as generated
/// and real scenes have them), and the dark room's texels along the wall took the lit room's
/// light. Anything standing on the surface between two seam patches taller than this refuses the
/// blend, which is what a seam crossed by a wall or a box should do.
const SEAM_RAY_HEIGHT: f64 = 0.25;

fn pass2_plan(p: &Patches, occluders: &Occluders) -> (Pass, usize) {
    let size = p.size;
    let lift = SEAM_RAY_HEIGHT * size;
    let mut out = Vec::new();
    let mut refused = 0;
    let charts = &p.charts;
    // Coplanar candidates through a hash of the charts' planes: a scan of every chart for each
    // is quadratic in the chart count, tens of thousands on a curved mesh.
    let radius = charts.iter().map(|c| c.origin.length()).fold(0.0, f64::max);
    let grid = super::patches::PlaneGrid::new(radius, COPLANAR_OFFSET * size);
    let mut planes: std::collections::HashMap<[i64; 4], Vec<usize>> = std::collections::HashMap::new();
    for (b, cb) in charts.iter().enumerate().filter(|(_, c)| !c.sky) {
        planes.entry(grid.cell(cb.normal, cb.origin)).or_default().push(b);
    }
    for (a, ca) in charts.iter().enumerate() {
        if ca.sky {
            continue;
        }
        let mut partners: Vec<usize> = grid
            .around(ca.normal, ca.origin)
            .filter_map(|cell| planes.get(&cell))
            .flatten()
            .copied()
            .filter(|&b| {
                let cb = &charts[b];
                b != a
                    && !cb.sky
                    && ca.normal.dot(cb.normal) > COPLANAR_COS
                    && (ca.normal.dot(ca.origin) - ca.normal.dot(cb.origin)).abs() < COPLANAR_OFFSET * size
                    && ca.cell.0 < cb.cell.0 + cb.width as i64
                    && cb.cell.0 < ca.cell.0 + ca.width as i64
                    && ca.cell.1 < cb.cell.1 + cb.height as i64
                    && cb.cell.1 < ca.cell.1 + ca.height as i64
            })
            .collect();
        // In chart order, as a scan finds them: the sources' sum keeps its order.
        partners.sort_unstable();
        if partners.is_empty() {
            continue;
        }
        for j in 0..ca.height {
            for i in 0..ca.width {
                let k = ca.first + j * ca.width + i;
                let own = &p.patches[k];
                if own.coverage >= 1.0 {
                    continue;
                }
                let (cx, cy) = (ca.cell.0 + i as i64, ca.cell.1 + j as i64);
                let mut from: Option<DVec3> = None;
                let mut sources: Vec<(usize, f64)> = if own.inside() { vec![(k, own.area)] } else { Vec::new() };
                let mut any = false;
                for &b in &partners {
                    let cb = &charts[b];
                    let (bi, bj) = (cx - cb.cell.0, cy - cb.cell.1);
                    if bi < 0 || bj < 0 || bi >= cb.width as i64 || bj >= cb.height as i64 {
                        continue;
                    }
                    let kb = cb.first + bj as usize * cb.width + bi as usize;
                    let other = &p.patches[kb];
                    if !other.inside() {
                        continue;
                    }
                    let start = *from.get_or_insert_with(|| near_inside(p, a, i, j));
                    if occluders.visible(start + ca.normal * lift, other.centre + cb.normal * lift) {
                        sources.push((kb, other.area));
                        any = true;
                    } else {
                        refused += 1;
                    }
                }
                let weight: f64 = sources.iter().map(|s| s.1).sum();
                if any && weight > 0.0 {
                    out.push((k, sources.into_iter().map(|(s, w)| (s, w / weight)).collect()));
                }
            }
        }
    }
    (out, refused)
}

/// A point of chart `c`'s polygon close to its patch (i, j): the patch's own sample point if
/// it is inside, else the nearest inside patch's.
fn near_inside(p: &Patches, c: usize, i: usize, j: usize) -> DVec3 {
    let ch = &p.charts[c];
    let k = ch.first + j * ch.width + i;
    let q = &p.patches[k];
    if q.inside() {
        return q.centre;
    }
    let cell_centre = q.centre;
    p.patches[ch.first..ch.first + ch.width * ch.height]
        .iter()
        .filter(|o| o.inside())
        .map(|o| o.centre)
        .min_by(|x, y| {
            (*x - cell_centre)
                .length_squared()
                .total_cmp(&(*y - cell_centre).length_squared())
        })
        .unwrap_or(cell_centre)
}
