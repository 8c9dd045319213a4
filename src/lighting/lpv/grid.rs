//! The CPU reference of a light propagation volume: one colour channel of 2-band SH per cell
//! (intensity, W/sr, in units where a cell is 1 wide), zero outside the grid. The GPU passes
//! are tested against it, and it reproduces the digest's tables (§7 T4–T7, T9).

use glam::{DVec3, IVec3};

use super::sh;

/// Ω of a destination cell's face opposite the source, seen from the source cell's centre:
/// 4·asin(0.1) (digest §2.7, T3).
pub fn omega_front() -> f64 {
    4.0 * 0.1f64.asin()
}

/// Ω of one of the four side faces: the rest of the destination's 2π/3, shared equally.
pub fn omega_side() -> f64 {
    (2.0 * std::f64::consts::PI / 3.0 - omega_front()) / 4.0
}

/// The side face's solid angle as widely published, 1e-5 off (digest §2.7): kept to show what
/// it costs (T4: +1.9e-5 of the flux per step).
pub const OMEGA_SIDE_PUBLISHED: f64 = 0.423_441_354_4;

/// The document's propagation weights (digest §2.7): face neighbours 0.65, edge neighbours half
/// that, the sum over 18 neighbours divided by 18 and added to the cell's previous value.
pub const FAITHFUL_FALLOFF: f64 = 0.65;

/// One channel of a volume.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub size: [usize; 3],
    pub cells: Vec<[f64; 4]>,
}

impl Grid {
    pub fn new(size: [usize; 3]) -> Grid {
        Grid {
            size,
            cells: vec![[0.0; 4]; size[0] * size[1] * size[2]],
        }
    }

    pub fn cube(n: usize) -> Grid {
        Grid::new([n, n, n])
    }

    /// The index of cell `c`, `None` outside.
    pub fn index(&self, c: IVec3) -> Option<usize> {
        let s = self.size.map(|s| s as i32);
        ((0..3).all(|a| c[a] >= 0 && c[a] < s[a])).then(|| (c.x + s[0] * (c.y + s[1] * c.z)) as usize)
    }

    pub fn cell(&self, i: usize) -> IVec3 {
        let [x, y, _] = self.size;
        IVec3::new((i % x) as i32, ((i / x) % y) as i32, (i / (x * y)) as i32)
    }

    /// Cell `c`'s coefficients (zero outside).
    pub fn at(&self, c: IVec3) -> [f64; 4] {
        self.index(c).map_or([0.0; 4], |i| self.cells[i])
    }

    pub fn add(&mut self, c: IVec3, v: &[f64; 4]) {
        if let Some(i) = self.index(c) {
            for (a, b) in self.cells[i].iter_mut().zip(v) {
                *a += b;
            }
        }
    }

    pub fn centre(&self) -> IVec3 {
        IVec3::new(
            self.size[0] as i32 / 2,
            self.size[1] as i32 / 2,
            self.size[2] as i32 / 2,
        )
    }

    /// Total flux, Σ 2√π c₀.
    pub fn flux(&self) -> f64 {
        self.cells.iter().map(sh::flux).sum()
    }

    /// Trilinear interpolation with the lattice points at integer `p` (cell centres for a
    /// volume, corners for a geometry volume), zero beyond the border.
    pub fn trilinear(&self, p: DVec3) -> [f64; 4] {
        let base = p.floor();
        let f = p - base;
        let b = base.as_ivec3();
        let mut out = [0.0; 4];
        for corner in 0..8 {
            let o = IVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if o.x == 1 { f.x } else { 1.0 - f.x })
                * (if o.y == 1 { f.y } else { 1.0 - f.y })
                * (if o.z == 1 { f.z } else { 1.0 - f.z });
            if w == 0.0 {
                continue;
            }
            let c = self.at(b + o);
            for k in 0..4 {
                out[k] += w * c[k];
            }
        }
        out
    }

    /// The sum of two grids of one size.
    pub fn plus(&self, other: &Grid) -> Grid {
        let mut out = self.clone();
        for (a, b) in out.cells.iter_mut().zip(&other.cells) {
            for k in 0..4 {
                a[k] += b[k];
            }
        }
        out
    }
}

/// How light crosses from a cell into its neighbours.
#[derive(Clone, Copy, Debug)]
pub struct Corrected<'a> {
    /// Clamp the source's intensity toward a face at 0 (its negative lobe sends no light).
    pub clamp: bool,
    pub omega_front: f64,
    pub omega_side: f64,
    /// The geometry volume: blocking potential at cell corners (lattice at integer corner
    /// coordinates), sampled at the face between source and destination.
    pub occlusion: Option<&'a Grid>,
}

impl Default for Corrected<'_> {
    fn default() -> Self {
        Corrected {
            clamp: true,
            omega_front: omega_front(),
            omega_side: omega_side(),
            occlusion: None,
        }
    }
}

const AXES: [IVec3; 6] = [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z];

/// One face of a destination cell: the direction the light crosses it along (from the source
/// cell's centre), the face's outward normal and its solid angle.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    pub direction: DVec3,
    pub normal: DVec3,
    pub omega: f64,
}

/// The five faces of the destination cell at `d` from the source that do not touch it.
pub fn faces(d: IVec3, omega_front: f64, omega_side: f64) -> [Face; 5] {
    let dd = d.as_dvec3();
    let mut out = [Face {
        direction: dd,
        normal: dd,
        omega: omega_front,
    }; 5];
    let mut k = 1;
    for a in AXES {
        if a.dot(d) == 0 {
            let ad = a.as_dvec3();
            out[k] = Face {
                direction: (dd + 0.5 * ad).normalize(),
                normal: ad,
                omega: omega_side,
            };
            k += 1;
        }
    }
    out
}

/// One step of the standard scheme (Kaplanyan & Dachsbacher 2010): every cell receives from its
/// 6 neighbours the flux Ω_f·I_src(ω_f) through the 5 faces each sees, reprojected as a cosine
/// lobe toward the face, times the transmission 1 − B(−ω) of the geometry volume between them.
pub fn step_corrected(src: &Grid, c: &Corrected<'_>) -> Grid {
    let mut out = Grid::new(src.size);
    // Per direction: the faces, the basis toward each, and each face's reprojected lobe.
    type Transfer = (IVec3, [Face; 5], [[f64; 4]; 5], [[f64; 4]; 5]);
    let all: Vec<Transfer> = AXES
        .iter()
        .map(|&d| {
            let f = faces(d, c.omega_front, c.omega_side);
            (
                d,
                f,
                f.map(|f| sh::basis(f.direction)),
                f.map(|f| sh::cosine_lobe(f.normal).map(|x| x * f.omega / std::f64::consts::PI)),
            )
        })
        .collect();
    for i in 0..out.cells.len() {
        let x = out.cell(i);
        let mut acc = [0.0; 4];
        for (d, faces, basis, lobes) in &all {
            let s = src.at(x - *d);
            if s == [0.0; 4] {
                continue;
            }
            let transmit = match c.occlusion {
                Some(gv) => {
                    // The face between the two cells, in corner coordinates.
                    let face = x.as_dvec3() + DVec3::splat(0.5) - 0.5 * d.as_dvec3();
                    Some(gv.trilinear(face))
                }
                None => None,
            };
            for k in 0..5 {
                let mut intensity = sh::dot(&s, &basis[k]);
                if c.clamp {
                    intensity = intensity.max(0.0);
                }
                if let Some(b) = &transmit {
                    intensity *= 1.0 - sh::eval(b, -faces[k].direction).clamp(0.0, 1.0);
                }
                for j in 0..4 {
                    acc[j] += intensity * lobes[k][j];
                }
            }
        }
        out.cells[i] = acc;
    }
    out
}

/// The 18 neighbour offsets of the document's propagation and their weights (faces 1, edges ½).
pub fn faithful_neighbours() -> Vec<(IVec3, f64)> {
    let mut out: Vec<(IVec3, f64)> = AXES.iter().map(|&a| (a, 1.0)).collect();
    for a in 0..3 {
        for b in a + 1..3 {
            for (sa, sb) in [(1, 1), (1, -1), (-1, 1), (-1, -1)] {
                let mut o = IVec3::ZERO;
                o[a] = sa;
                o[b] = sb;
                out.push((o, 0.5));
            }
        }
    }
    out
}

/// One step of the document's propagation (digest §2.7, Appendix 1): each neighbour's value
/// toward the cell, clamped, as a delta lobe, times 0.65·w, summed, ÷18, plus the cell's own
/// previous value. It accumulates in place and gains energy (T9).
pub fn step_faithful(src: &Grid) -> Grid {
    let neighbours: Vec<(IVec3, [f64; 4], f64)> = faithful_neighbours()
        .into_iter()
        .map(|(o, w)| {
            let dir = -o.as_dvec3().normalize();
            (o, sh::basis(dir), w)
        })
        .collect();
    let mut out = src.clone();
    for i in 0..out.cells.len() {
        let x = out.cell(i);
        let mut acc = [0.0; 4];
        for (o, y, w) in &neighbours {
            let nb = src.at(x + *o);
            let l = sh::dot(&nb, y).max(0.0);
            for k in 0..4 {
                acc[k] += y[k] * FAITHFUL_FALLOFF * w * l;
            }
        }
        for (o, a) in out.cells[i].iter_mut().zip(acc) {
            *o += a / 18.0;
        }
    }
    out
}

/// The standard scheme's `steps` iterations from `injected`: the accumulated volume (the
/// injection plus every wavefront) and the last wavefront.
pub fn propagate_corrected(injected: &Grid, steps: usize, c: &Corrected<'_>) -> (Grid, Grid) {
    let mut acc = injected.clone();
    let mut front = injected.clone();
    for _ in 0..steps {
        front = step_corrected(&front, c);
        acc = acc.plus(&front);
    }
    (acc, front)
}

/// The document's `steps` iterations: the volume after the last (it accumulates in place).
pub fn propagate_faithful(injected: &Grid, steps: usize) -> Grid {
    (0..steps).fold(injected.clone(), |g, _| step_faithful(&g))
}
