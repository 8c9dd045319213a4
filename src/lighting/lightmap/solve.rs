//! Progressive-refinement radiosity (the Ca3D-Engine thesis §3, digest §1.2 step E): Southwell shooting of
//! n×n blocks of patches, visibility by rays through a BVH of the static triangles.
//!
//! *Faithful* (CaLight): the shooter is the best of 10 random blocks per chart, a full search
//! only when that falls below the threshold; the form factor is point-sampled with the near-field
//! clamp (`form_factor::point_sampled`). *Corrected*: the largest unshot block every time and
//! the exact differential-to-polygon form factor (`form_factor::point_to_polygon`) to the
//! block's square, so that in a closed enclosure the energy closes.

use glam::{DVec3, Vec3};

use super::form_factor;
use super::patches::{Patches, Triangle};
use super::visibility::{Matrix, Vis};
use crate::raytrace::bvh::Bvh;
use crate::util::progress::Progress;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Faithful,
    Corrected,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub mode: Mode,
    /// Patches per side of a shooting block (the seed's n, default 3).
    pub block: usize,
    /// Stop when the unshot power (corrected: all of it; faithful: the best shooter's) falls
    /// below this fraction of the initial unshot power.
    pub threshold: f64,
    /// A bound on the number of shots, whatever the threshold.
    pub max_shots: usize,
    /// The seed's random block samples per chart when choosing a shooter (faithful mode).
    pub samples_per_chart: usize,
    /// Let the visibility matrix mark pairs FULL, whose rays are skipped (false: CaLight's
    /// `-NoFullVis`, every visible pair ray-tested).
    pub full_visibility: bool,
    /// One reflectivity for every surface and wavelength in the bounces, instead of each
    /// material's albedo (CaLight's `REFLECTIVITY = 0.3`); `None`: the materials'.
    pub reflectivity: Option<f64>,
    /// The most charts the visibility matrix is built for ([`super::visibility::MAX_MATRIX_CHARTS`]).
    pub matrix_charts: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            mode: Mode::Corrected,
            block: 3,
            threshold: 1e-3,
            max_shots: 100_000,
            samples_per_chart: 10,
            full_visibility: true,
            reflectivity: None,
            matrix_charts: super::visibility::MAX_MATRIX_CHARTS,
        }
    }
}

/// How a solve went.
#[derive(Clone, Debug, Default)]
pub struct Report {
    pub shots: usize,
    /// Full searches for a shooter (faithful mode: when the random samples fell below the threshold).
    pub full_searches: usize,
    /// Unshot power (Σ over channels of area × unshot radiosity) before each shot.
    pub unshot_power: Vec<f64>,
    /// Visibility rays cast, and those the visibility matrix's FULL pairs made unnecessary.
    pub rays: u64,
    pub rays_saved: u64,
    /// Chart pairs (i ≤ j) NONE, PARTIAL and FULL in the visibility matrix.
    pub visibility: (usize, usize, usize),
    /// Border pass 2's contributions refused by the anti-bleeding ray (set by the bake).
    pub border_refused: usize,
}

/// The corrected solves' default stop (radiosity's and the SH light-map's bounces): the unshot
/// light at a ten-thousandth of what was emitted. A room lit only through a door from another
/// takes its light late in the solve, from many small shots; at a thousandth, a generated room
/// seen through a sunlit one's door drew 0.90 of the path tracer's mean (128x96 supersampled
/// 4x4, lavapipe), at a ten-thousandth 0.99, for 1.3 to 2 times the bake
/// (`the_default_stop_lights_a_room_seen_through_a_door`). Faithful modes keep their own.
pub const CORRECTED_THRESHOLD: f64 = 1e-4;

/// The static triangles as occluders (sky surfaces included: they are walls to everything but
/// the sun).
pub struct Occluders {
    tris: Vec<[Vec3; 3]>,
    bvh: Bvh,
    /// The triangles as the baker sees them (the visibility matrix's hull test).
    pub triangles: Vec<Triangle>,
    /// The charts' leaf PVS in a BSP world (the visibility matrix starts from it), set by the
    /// bake once the charts exist.
    pub pvs: Option<super::visibility::ChartPvs>,
}

impl Occluders {
    pub fn new(triangles: &[Triangle]) -> Occluders {
        let tris: Vec<[Vec3; 3]> = triangles.iter().map(|t| t.p.map(|p| p.as_vec3())).collect();
        let bvh = Bvh::build(&tris);
        Occluders {
            tris,
            bvh,
            triangles: triangles.to_vec(),
            pvs: None,
        }
    }

    /// The first triangle a ray from `a` along the unit `dir` hits: (distance, index).
    pub fn first_hit(&self, a: DVec3, dir: DVec3) -> Option<(f64, usize)> {
        self.bvh
            .closest_hit(&self.tris, a.as_vec3(), dir.as_vec3())
            .map(|(t, i)| (t as f64, i as usize))
    }

    pub fn has_sky(&self) -> bool {
        self.triangles.iter().any(|t| t.sky)
    }

    /// Nothing between `a` and `b` (both ends excluded by a small margin).
    pub fn visible(&self, a: DVec3, b: DVec3) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 0.0 {
            return true;
        }
        let dir = (d / len).as_vec3();
        match self.bvh.closest_hit(&self.tris, a.as_vec3(), dir) {
            Some((t, _)) => t as f64 >= len * (1.0 - 1e-4) - 1e-5,
            None => true,
        }
    }
}

/// One shooting block: patches of one chart, its square, and the normal it shoots along (the
/// chart's, or with normal-mapped patches their renormalised mean: the Ca3D-Engine thesis §5.7).
pub(crate) struct Block {
    pub chart: usize,
    pub members: Vec<usize>,
    pub corners: [DVec3; 4],
    pub normal: DVec3,
}

/// The n×n shooting blocks of every chart. With `walls` (the corrected mode), a block's patches
/// that a wall standing on the chart parts are shot as separate blocks ([`parted_by_walls`]).
pub(crate) fn blocks(p: &Patches, n: usize, walls: Option<&Occluders>) -> Vec<Block> {
    blocks_of(&Geometry::from(p), n, walls)
}

fn blocks_of(p: &Geometry<'_>, n: usize, walls: Option<&Occluders>) -> Vec<Block> {
    let mut out = Vec::new();
    for (ci, c) in p.charts.iter().enumerate() {
        for j0 in (0..c.height).step_by(n) {
            for i0 in (0..c.width).step_by(n) {
                let (i1, j1) = ((i0 + n).min(c.width), (j0 + n).min(c.height));
                let members: Vec<usize> = (j0..j1)
                    .flat_map(|j| (i0..i1).map(move |i| c.first + j * c.width + i))
                    .filter(|&k| p.patches[k].inside())
                    .collect();
                if members.is_empty() {
                    continue;
                }
                match walls {
                    Some(occluders) => {
                        for group in parted_by_walls(p, c.normal, members, occluders) {
                            out.push(block_of(p, ci, group));
                        }
                    }
                    None => out.push(block_of(p, ci, members)),
                }
            }
        }
    }
    out
}

/// `members` (patches of one block) in groups whose centres are joined by clear segments,
/// directly or through other members. A block shoots its summed power from its centre: a 3×3
/// block of 0.36 m floor patches that a 3.4 cm wall crosses shot the light of the lit room from
/// a centre in the dark one (a generated room showed 2.13 of the path tracer's mean).
fn parted_by_walls(p: &Geometry<'_>, normal: DVec3, members: Vec<usize>, occluders: &Occluders) -> Vec<Vec<usize>> {
    let eps = 1e-4 * p.size;
    let at = |k: usize| p.patches[k].centre + normal * eps;
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut left = members;
    while !left.is_empty() {
        let mut group = vec![left.remove(0)];
        let mut next = 0;
        while next < group.len() {
            let a = at(group[next]);
            next += 1;
            let (joined, apart): (Vec<usize>, Vec<usize>) =
                left.into_iter().partition(|&b| occluders.visible(a, at(b)));
            group.extend(joined);
            left = apart;
        }
        group.sort_unstable();
        groups.push(group);
    }
    groups
}

/// A block of `members` of chart `ci`: its rectangle is that of its patches inside the polygon
/// (the border frame lies outside the surface and must not shoot).
fn block_of(p: &Geometry<'_>, ci: usize, members: Vec<usize>) -> Block {
    let (c, s) = (&p.charts[ci], p.size);
    let ij = |k: usize| c.cell_of(k);
    let (lo_i, hi_i) = members
        .iter()
        .map(|&k| ij(k).0)
        .fold((usize::MAX, 0), |(a, b), i| (a.min(i), b.max(i + 1)));
    let (lo_j, hi_j) = members
        .iter()
        .map(|&k| ij(k).1)
        .fold((usize::MAX, 0), |(a, b), j| (a.min(j), b.max(j + 1)));
    // The cells' rectangle clipped to the polygon's bounds, but never narrower than a patch
    // (centred on the polygon where that is thinner): an edge block's cells overhang its
    // polygon, and shot from there its light would leave from beyond the surface (behind a wall
    // the chart meets, whose patches then miss it). A square smaller than a patch, nearer its
    // receivers than their size, would let their point-sampled form factors give away more than
    // its power: clipped to a 2.7 cm wall's side, a bake of a generated room never converged.
    let (lo, hi) = c.extent;
    let span = |a: usize, b: usize, min: f64, max: f64| {
        let (x0, x1) = (a as f64 * s, b as f64 * s);
        let (y0, y1) = (x0.max(min), x1.min(max));
        let least = s.min(x1 - x0);
        if y1 - y0 >= least {
            (y0, y1)
        } else {
            let m = (0.5 * (min + max)).clamp(x0 + 0.5 * least, x1 - 0.5 * least);
            (m - 0.5 * least, m + 0.5 * least)
        }
    };
    let (x0, x1) = span(lo_i, hi_i, lo.x, hi.x);
    let (y0, y1) = span(lo_j, hi_j, lo.y, hi.y);
    let at = |x: f64, y: f64| c.origin + c.u * x + c.v * y;
    let normal = members
        .iter()
        .map(|&k| p.patches[k].normal)
        .sum::<DVec3>()
        .try_normalize()
        .unwrap_or(c.normal);
    Block {
        chart: ci,
        members,
        corners: [at(x0, y0), at(x1, y0), at(x1, y1), at(x0, y1)],
        normal,
    }
}

fn magnitude(v: DVec3) -> f64 {
    v.x.abs() + v.y.abs() + v.z.abs()
}

/// Receivers closer to a shooting square than this many times the square's and the patch's
/// radii gather over their sub-samples. Farther, the centre's form factor is the patch's mean
/// to within its curvature, which falls as the fourth power of the distance. The two rules
/// mixed in one receiver's gather leave a closed box's light slightly unbalanced: 4.4e-4 of it
/// in a 2 m furnace box of 0.25 m patches (`the_gpu_shooter_closes_the_furnace`).
pub(crate) const NEAR_FIELD: f64 = 3.0;

/// Whether a receiver at `x` is near enough to the shooting square `corners` that its form
/// factor, sampled at its centre, misjudges the patch ([`NEAR_FIELD`]). The form factor to a
/// near square falls off faster than linearly across the receiver, so its centre's value is
/// not the patch's mean: a wall beside a ceiling panel took 0.86 of its exact share
/// (`a_panel_whose_cells_overhang_a_wall_lights_it_by_its_own_extent`).
pub(crate) fn near_field(size: f64, x: DVec3, corners: &[DVec3; 4]) -> bool {
    let centre = corners.iter().sum::<DVec3>() / 4.0;
    let radius = 0.5
        * (corners[2] - corners[0])
            .length()
            .max((corners[3] - corners[1]).length());
    (x - centre).length() < NEAR_FIELD * (radius + size * std::f64::consts::FRAC_1_SQRT_2)
}

/// Receiver `r`'s form factor to the square `corners` (shooting along `normal`), averaged over
/// the sub-samples the patch keeps ([`super::patches::Patch::samples`]), and the centroid of
/// those in front of the shooter's plane (behind it they get nothing); `None` when none is. The
/// form factor is taken once per quarter of the patch, at the centroid of its kept sub-samples
/// and weighted by their count: a quarter of the work of every sub-sample, for nearly its value.
fn near_form_factor(g: Geometry<'_>, r: usize, normal: DVec3, corners: &[DVec3; 4]) -> Option<(f64, DVec3)> {
    let rp = &g.patches[r];
    let c = &g.charts[rp.chart];
    let n = super::patches::COVERAGE_SAMPLES;
    let cell = c.cell_of(r);
    // Per quarter: the sum and count of its kept sub-samples in front of the shooter's plane.
    let mut quarters = [(DVec3::ZERO, 0u32); 4];
    let mut count = 0u32;
    for bit in (0..n * n).filter(|b| rp.samples & (1 << b) != 0) {
        let (si, sj) = (bit % n, bit / n);
        let x = c.sub_sample(g.size, cell, (si, sj));
        count += 1;
        if normal.dot(x - corners[0]) > 0.0 {
            let q = &mut quarters[2 * (sj * 2 / n) + si * 2 / n];
            q.0 += x;
            q.1 += 1;
        }
    }
    if count == 0 {
        // No sub-sample recorded: the centre alone.
        let x = rp.centre;
        return (normal.dot(x - corners[0]) > 0.0).then(|| (form_factor::point_to_polygon(x, rp.normal, corners), x));
    }
    let (mut sum, mut front, mut centroid) = (0.0, 0, DVec3::ZERO);
    for &(total, k) in quarters.iter().filter(|q| q.1 > 0) {
        sum += k as f64 * form_factor::point_to_polygon(total / k as f64, rp.normal, corners);
        front += k;
        centroid += total;
    }
    (front > 0).then(|| (sum / count as f64, centroid / front as f64))
}

/// Shows a solve's progress: the unshot energy falls about geometrically, so the fraction done is
/// taken on a log scale from the initial energy down to the stop, which keeps the time left honest.
pub(crate) fn show_progress(progress: &mut Progress, shots: usize, left: f64, initial: f64, threshold: f64) {
    let fraction = if initial > 0.0 && left > 0.0 {
        ((initial / left).ln() / (1.0 / threshold).ln()).clamp(0.0, 1.0)
    } else {
        1.0
    };
    progress.set_detail(format!(
        "{shots} shots, unshot {:.2e} of the initial energy",
        if initial > 0.0 { left / initial } else { 0.0 }
    ));
    progress.update((fraction * 1000.0) as u64, 1000);
}

/// xorshift64*: the faithful mode's random block samples, reproducible.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) % n.max(1) as u64) as usize
    }
}

/// What the shooting loop shoots: radiosity (RGB, [`solve`]) or SH transfer vectors (the Ca3D-Engine thesis
/// §5.4.3, `sh_lightmap`), kept outside [`Patches`] so that one loop serves both.
pub trait Unshot {
    /// The magnitude the seed selects shooters by (the L1 norm of patch `k`'s unshot value).
    fn magnitude(&self, k: usize) -> f64;
    /// Patch `k` reflects anything (receivers that cannot are skipped, and cast no ray).
    fn reflects(&self, k: usize) -> bool;
    /// The block `members` shoots: each receiver `r` of `shares` gains its reflectance × Σ
    /// (unshot · area) of the members × `f`, and the members' unshot values are cleared.
    fn shoot(&mut self, members: &[usize], area: &[f64], shares: &[(usize, f64)]);
}

/// Radiosity as the loop's payload: the patches' own total and unshot RGB radiosity.
struct Radiosity<'a>(&'a mut [super::patches::Patch]);

impl Unshot for Radiosity<'_> {
    fn magnitude(&self, k: usize) -> f64 {
        magnitude(self.0[k].unshot)
    }
    fn reflects(&self, k: usize) -> bool {
        self.0[k].albedo != DVec3::ZERO
    }
    fn shoot(&mut self, members: &[usize], area: &[f64], shares: &[(usize, f64)]) {
        let flux: DVec3 = members.iter().map(|&k| self.0[k].unshot * area[k]).sum();
        for &k in members {
            self.0[k].unshot = DVec3::ZERO;
        }
        for &(r, f) in shares {
            let q = &mut self.0[r];
            let delta = q.albedo * flux * f;
            q.total += delta;
            q.unshot += delta;
        }
    }
}

/// Shoots until no block's unshot power exceeds `threshold` × the initial unshot power.
pub fn solve(p: &mut Patches, occluders: &Occluders, settings: &Settings, progress: &mut Progress) -> Report {
    // The loop reads the geometry while the payload (the same patches' radiosity) changes.
    let geometry = p.patches.clone();
    let g = Geometry {
        size: p.size,
        charts: &p.charts,
        patches: &geometry,
    };
    shoot(g, occluders, settings, progress, &mut Radiosity(&mut p.patches))
}

/// What each patch reflects of the emitters' first shot (quad lights and emissive surfaces): their
/// emitted radiosity shot once through the same form factors and visibility as [`solve`], the
/// reflected light received never shot on. This is the direct light of area emitters, which a
/// light-map of bounced light only must leave out (point, spot and sun light never enters the
/// solve as emission: a bake subtracts it as it adds it).
pub fn emitters_first_shot(p: &Patches, occluders: &Occluders, settings: &Settings) -> Vec<DVec3> {
    let mut first = FirstShot {
        unshot: p.patches.iter().map(|q| q.emission).collect(),
        albedo: p.patches.iter().map(|q| q.albedo).collect(),
        received: vec![DVec3::ZERO; p.patches.len()],
    };
    if first.unshot.iter().all(|e| *e == DVec3::ZERO) {
        return first.received;
    }
    // Every block with emission shoots once: nothing else ever holds unshot energy, so the loop
    // ends when the last emitting block has shot (the stop at zero left).
    let once = Settings {
        threshold: 0.0,
        max_shots: usize::MAX,
        ..*settings
    };
    shoot(
        Geometry::from(p),
        occluders,
        &once,
        &mut Progress::new("emitters' direct light"),
        &mut first,
    );
    first.received
}

/// [`emitters_first_shot`]'s payload: the emission shot, what it lands as kept apart.
struct FirstShot {
    unshot: Vec<DVec3>,
    albedo: Vec<DVec3>,
    received: Vec<DVec3>,
}

impl Unshot for FirstShot {
    fn magnitude(&self, k: usize) -> f64 {
        magnitude(self.unshot[k])
    }
    fn reflects(&self, k: usize) -> bool {
        self.albedo[k] != DVec3::ZERO
    }
    fn shoot(&mut self, members: &[usize], area: &[f64], shares: &[(usize, f64)]) {
        let flux: DVec3 = members.iter().map(|&k| self.unshot[k] * area[k]).sum();
        for &k in members {
            self.unshot[k] = DVec3::ZERO;
        }
        for &(r, f) in shares {
            self.received[r] += self.albedo[r] * flux * f;
        }
    }
}

/// The patch geometry the loop reads.
#[derive(Clone, Copy)]
pub struct Geometry<'a> {
    pub size: f64,
    pub charts: &'a [super::patches::Chart],
    pub patches: &'a [super::patches::Patch],
}

impl<'a> From<&'a Patches> for Geometry<'a> {
    fn from(p: &'a Patches) -> Geometry<'a> {
        Geometry {
            size: p.size,
            charts: &p.charts,
            patches: &p.patches,
        }
    }
}

/// The progressive-refinement loop over any [`Unshot`] payload: shooter selection (the seed's
/// random block samples, or the largest), the stop, form factors and visibility.
pub fn shoot(
    g: Geometry<'_>,
    occluders: &Occluders,
    settings: &Settings,
    progress: &mut Progress,
    energy: &mut dyn Unshot,
) -> Report {
    // Chart pairs grow as the square of the charts (a triangle soup is one chart a triangle):
    // seconds to minutes that must not pass in silence.
    let solve = progress.stage("chart visibility", || Solve::new(g, occluders, settings));
    let initial: f64 = solve.blocks.iter().map(|b| solve.power(energy, b)).sum();
    let stop = settings.threshold * initial;
    let mut report = Report {
        visibility: solve.matrix.counts(),
        ..Report::default()
    };
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    // The shooting's rate is timed from here, not from the set-up's start.
    show_progress(progress, 0, initial, initial, settings.threshold);
    // A cancelled solve stops between shots; the bake it is part of then caches nothing.
    while report.shots < settings.max_shots && !progress.cancelled() {
        let (best, best_power) = solve.pick_shooter(energy, stop, &mut rng, &mut report);
        let unshot: f64 = solve.blocks.iter().map(|b| solve.power(energy, b)).sum();
        report.unshot_power.push(unshot);
        // CaLight stops when no shooter is above its threshold, which leaves up to (blocks ×
        // threshold) of the light unshot; the corrected solve stops on the total instead.
        let done = match settings.mode {
            Mode::Faithful => best_power <= stop,
            Mode::Corrected => unshot <= stop,
        };
        if done || best_power <= 0.0 {
            break;
        }
        let b = &solve.blocks[best];
        let found = solve.receivers_of(&Shot::new(g, b, &solve.area), &*energy);
        let mut shares = Vec::with_capacity(found.len());
        for (r, f, seen, full) in found {
            if full {
                report.rays_saved += 1;
            } else {
                report.rays += 1;
            }
            if seen {
                shares.push((r, f));
            }
        }
        energy.shoot(&b.members, &solve.area, &shares);
        report.shots += 1;
        let left = report.unshot_power.last().copied().unwrap_or(0.0);
        show_progress(progress, report.shots, left, initial, settings.threshold);
    }
    progress.finish();
    report
}

/// What every shot of one solve reads: the blocks, the patches' areas, the chart-to-chart
/// visibility and the receiving patches.
struct Solve<'a> {
    g: Geometry<'a>,
    occluders: &'a Occluders,
    settings: &'a Settings,
    blocks: Vec<Block>,
    area: Vec<f64>,
    matrix: Matrix,
    /// Per chart: its blocks.
    by_chart: Vec<Vec<usize>>,
    receivers: Vec<usize>,
    threads: usize,
    /// Receivers start a hair in front of their surface, so that their own plane never occludes.
    eps: f64,
}

/// One shooting block seen as a patch: its unshot power spread over its square, or (faithful)
/// concentrated at its centre.
struct Shot<'b> {
    block: &'b Block,
    area: f64,
    square: f64,
    centre: DVec3,
}

impl<'b> Shot<'b> {
    fn new(g: Geometry<'_>, block: &'b Block, area: &[f64]) -> Shot<'b> {
        let b = block;
        let block_area: f64 = b.members.iter().map(|&k| area[k]).sum();
        let square = (b.corners[1] - b.corners[0]).length() * (b.corners[3] - b.corners[0]).length();
        let centre = b.members.iter().map(|&k| g.patches[k].centre * area[k]).sum::<DVec3>() / block_area;
        Shot {
            block,
            area: block_area,
            square,
            centre,
        }
    }
}

impl<'a> Solve<'a> {
    fn new(g: Geometry<'a>, occluders: &'a Occluders, settings: &'a Settings) -> Solve<'a> {
        // Corrected: a block a wall parts shoots each side from its own centre. Faithful:
        // CaLight's blocks.
        let walls = (settings.mode == Mode::Corrected).then_some(occluders);
        let blocks = blocks_of(&g, settings.block.max(1), walls);
        // NONE pairs exchange nothing (skipped: the form factor would be 0 in faithful mode, and
        // in corrected mode only a block square's overhang beyond its polygon could reach them);
        // FULL pairs need no rays. The same matrix in both modes.
        let matrix = Matrix::build_up_to(
            &occluders.triangles,
            g.charts,
            settings.full_visibility,
            occluders.pvs.as_ref(),
            settings.matrix_charts,
        );
        let mut by_chart: Vec<Vec<usize>> = vec![Vec::new(); g.charts.len()];
        for (b, block) in blocks.iter().enumerate() {
            by_chart[block.chart].push(b);
        }
        Solve {
            g,
            occluders,
            settings,
            area: g.patches.iter().map(|q| q.area).collect(),
            matrix,
            by_chart,
            receivers: (0..g.patches.len()).filter(|&k| g.patches[k].inside()).collect(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            eps: 1e-4 * g.size,
            blocks,
        }
    }

    /// The unshot power of block `b`.
    fn power(&self, e: &dyn Unshot, b: &Block) -> f64 {
        b.members.iter().map(|&k| e.magnitude(k) * self.area[k]).sum::<f64>()
    }

    /// The block with the most unshot power (the first of equals) and that power.
    fn strongest(&self, e: &dyn Unshot) -> (usize, f64) {
        (0..self.blocks.len())
            .map(|b| (b, self.power(e, &self.blocks[b])))
            .fold((0, -1.0), |a, x| if x.1 > a.1 { x } else { a })
    }

    /// The next shooter and its power: the strongest block (corrected), or the best of the
    /// seed's random samples per chart, searching every block only when that best is below
    /// `stop` (faithful).
    fn pick_shooter(&self, e: &dyn Unshot, stop: f64, rng: &mut Rng, report: &mut Report) -> (usize, f64) {
        match self.settings.mode {
            Mode::Corrected => self.strongest(e),
            Mode::Faithful => {
                let mut cand = (0, -1.0);
                for list in self.by_chart.iter().filter(|l| !l.is_empty()) {
                    for _ in 0..self.settings.samples_per_chart {
                        let b = list[rng.below(list.len())];
                        let w = self.power(e, &self.blocks[b]);
                        if w > cand.1 {
                            cand = (b, w);
                        }
                    }
                }
                if cand.1 > stop {
                    cand
                } else {
                    report.full_searches += 1;
                    self.strongest(e)
                }
            }
        }
    }

    /// Every receiver the shot reaches: (patch, form factor, seen, FULL pair). Each receiver's
    /// share is independent of the others': the receivers are split over the machine's cores
    /// (each thread casts its receivers' rays) and the results kept in receiver order, so the
    /// result does not depend on the thread count.
    fn receivers_of(&self, shot: &Shot<'_>, e: &dyn Unshot) -> Vec<(usize, f64, bool, bool)> {
        let reflects: Vec<bool> = self.receivers.iter().map(|&r| e.reflects(r)).collect();
        let chunk = self.receivers.len().div_ceil(self.threads).max(1);
        let indexed: Vec<(usize, &usize)> = self.receivers.iter().enumerate().collect();
        let reflects = &reflects;
        std::thread::scope(|scope| {
            let handles: Vec<_> = indexed
                .chunks(chunk)
                .map(|part| {
                    scope.spawn(move || {
                        part.iter()
                            .filter_map(|&(i, &r)| self.receiver_share(shot, reflects[i], r))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect::<Vec<_>>()
        })
    }

    /// Receiver `r`'s form factor to the shot, whether it sees the shooter and whether the pair
    /// is FULL (no ray cast); `None` when it gets nothing.
    fn receiver_share(&self, shot: &Shot<'_>, reflects: bool, r: usize) -> Option<(usize, f64, bool, bool)> {
        let (g, b, centre) = (self.g, shot.block, shot.centre);
        let normal = b.normal;
        let rp = g.patches[r];
        let plane = g.charts[rp.chart].normal;
        let vis = self.matrix.get(b.chart, rp.chart);
        if vis == Vis::None {
            return None;
        }
        // Shooters emit toward their normal only: a receiver behind the shooter's plane gets
        // nothing (the exact form factor looks from the receiver and cannot see it). A receiver
        // near the shooter is judged by its sub-samples, which may straddle that plane, from
        // the centroid of those in front.
        let near = self.settings.mode == Mode::Corrected && near_field(g.size, rp.centre, &b.corners);
        if rp.chart == b.chart || (!near && normal.dot(rp.centre - b.corners[0]) <= 0.0) {
            return None;
        }
        let (f, at) = match self.settings.mode {
            // F from the receiver to the square times the square's mean unshot radiosity.
            Mode::Corrected if near => {
                let (f, at) = near_form_factor(g, r, normal, &b.corners)?;
                (f / shot.square, at)
            }
            Mode::Corrected => (
                form_factor::point_to_polygon(rp.centre, rp.normal, &b.corners) / shot.square,
                rp.centre,
            ),
            // CaLight: the block as one patch of its area at its centre.
            Mode::Faithful => (
                form_factor::point_sampled(rp.centre, rp.normal, centre, normal, shot.area, g.size) / shot.area,
                rp.centre,
            ),
        };
        // With normal-mapped patches, both ends must also face each other's planes (the seed's
        // four cosines); for plain patches these equal the tests above.
        if f <= 0.0 || !reflects || plane.dot(centre - at) <= 0.0 || g.charts[b.chart].normal.dot(at - centre) <= 0.0 {
            return None;
        }
        let full = vis == Vis::Full;
        let eps = self.eps;
        let seen = full
            || self
                .occluders
                .visible(at + plane * eps, centre + g.charts[b.chart].normal * eps);
        Some((r, f, seen, full))
    }
}
