//! Visibility wedges (the height-field thesis §4.2.1 Eq. 4.17–4.19, §4.3.1 Eq. 4.26; digest §1.6): the SH
//! projection of the visibility of one azimuthal wedge [0, Δφ] above a horizon that runs
//! linearly from ω_l (at φ = 0) to ω_r (at φ = Δφ), tabulated for node pairs, and the total
//! visibility V = Σ_j R_{φ_j} v(ω_j, ω_{j+1}).
//!
//! Directions are in the SH frame (z up; φ from +x toward +y; elevation θ from the equator,
//! u = cos(polar) = sin θ, dω = cos θ dθ dφ), so
//! `v_k(ω_l, ω_r) = ∫_0^{Δφ} ∫_{ω(φ)}^{π/2} y_k(θ, φ) cos θ dθ dφ`, evaluated by Gauss–Legendre
//! quadrature in both variables (the integrand is a trigonometric polynomial in θ and smooth in
//! φ, so 16×16 nodes converge to rounding). The table depends on Δφ = 2π/nφ and is rebuilt for
//! every nφ (digest §1.6: the thesis varies nφ without saying so).

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::{Arc, Mutex, OnceLock};

use glam::DVec3;

use crate::sh::{self, ShResult};

/// Which table: the environment's hemisphere (horizons in [0, π/2]) or the local lights' full
/// sphere (horizons in [−π/2, π/2]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TableKind {
    Environment,
    Local,
}

impl TableKind {
    /// The horizon-angle range of the table's nodes (both ends are nodes).
    pub fn range(self) -> (f64, f64) {
        match self {
            TableKind::Environment => (0.0, FRAC_PI_2),
            TableKind::Local => (-FRAC_PI_2, FRAC_PI_2),
        }
    }
}

/// Gauss–Legendre nodes per variable of the wedge quadrature.
const QUAD_NODES: usize = 16;

fn gl_nodes() -> &'static (Vec<f64>, Vec<f64>) {
    static NODES: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    NODES.get_or_init(|| sh::gauss_legendre(QUAD_NODES).expect("16 Gauss–Legendre nodes"))
}

/// The SH projection (`bands²` coefficients) of the wedge [0, dphi] above the horizon running
/// linearly from `wl` to `wr` (radians of elevation).
pub fn exact_wedge(wl: f64, wr: f64, dphi: f64, bands: usize) -> ShResult<Vec<f64>> {
    sh::check_bands(bands)?;
    let n = bands * bands;
    let (x, w) = gl_nodes();
    let mut out = vec![0.0; n];
    let mut y = vec![0.0; n];
    for (xp, wp) in x.iter().zip(w) {
        let phi = 0.5 * dphi * (xp + 1.0);
        let wphi = 0.5 * dphi * wp;
        let omega = wl + (phi / dphi) * (wr - wl);
        let (lo, hi) = (omega, FRAC_PI_2);
        if hi <= lo {
            continue;
        }
        let (sp, cp) = phi.sin_cos();
        for (xt, wt) in x.iter().zip(w) {
            let theta = lo + 0.5 * (hi - lo) * (xt + 1.0);
            let wtheta = 0.5 * (hi - lo) * wt;
            let (st, ct) = theta.sin_cos();
            sh::eval_basis_f64(DVec3::new(ct * cp, ct * sp, st), bands, &mut y)?;
            let weight = wphi * wtheta * ct;
            for (o, yk) in out.iter_mut().zip(&y) {
                *o += weight * yk;
            }
        }
    }
    Ok(out)
}

/// A wedge table: `nodes × nodes` entries of `bands²` coefficients; entry (a, b) is the wedge
/// with ω_l = node a and ω_r = node b, node a at `lo + a·(hi − lo)/(nodes − 1)`.
#[derive(Clone, Debug, PartialEq)]
pub struct WedgeTable {
    pub kind: TableKind,
    pub nphi: usize,
    pub nodes: usize,
    pub bands: usize,
    /// Row-major by (a, b), then coefficient.
    pub data: Vec<f64>,
}

type TableKey = (TableKind, usize, usize, usize);

impl WedgeTable {
    /// Builds the table for `nphi` directions (Δφ = 2π/nφ).
    pub fn build(kind: TableKind, nphi: usize, nodes: usize, bands: usize) -> ShResult<WedgeTable> {
        let nodes = nodes.max(2);
        let nc = bands * bands;
        let dphi = TAU / nphi.max(1) as f64;
        let mut data = Vec::with_capacity(nodes * nodes * nc);
        let t = WedgeTable {
            kind,
            nphi,
            nodes,
            bands,
            data: Vec::new(),
        };
        for a in 0..nodes {
            for b in 0..nodes {
                data.extend(exact_wedge(t.node(a), t.node(b), dphi, bands)?);
            }
        }
        Ok(WedgeTable { data, ..t })
    }

    /// The table for these settings, built once per process and shared.
    pub fn shared(kind: TableKind, nphi: usize, nodes: usize, bands: usize) -> ShResult<Arc<WedgeTable>> {
        static CACHE: OnceLock<Mutex<HashMap<TableKey, Arc<WedgeTable>>>> = OnceLock::new();
        let key = (kind, nphi, nodes, bands);
        let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(t) = cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return Ok(t);
        }
        let t = Arc::new(WedgeTable::build(kind, nphi, nodes, bands)?);
        if let Ok(mut c) = cache.lock() {
            c.insert(key, t.clone());
        }
        Ok(t)
    }

    /// Horizon angle of node `a`.
    pub fn node(&self, a: usize) -> f64 {
        let (lo, hi) = self.kind.range();
        lo + (hi - lo) * a as f64 / (self.nodes - 1) as f64
    }

    pub fn entry(&self, a: usize, b: usize) -> &[f64] {
        let nc = self.bands * self.bands;
        let at = (a * self.nodes + b) * nc;
        &self.data[at..at + nc]
    }

    /// The wedge for horizons (wl, wr): the nearest node pair, or bilinear between the four
    /// around it. Mirrors `hf_wedge` in `glsl/heightfield/common.glsl`.
    pub fn lookup(&self, wl: f64, wr: f64, bilinear: bool) -> Vec<f64> {
        let (lo, hi) = self.kind.range();
        let last = (self.nodes - 1) as f64;
        let x = |w: f64| ((w - lo) / (hi - lo) * last).clamp(0.0, last);
        let (xl, xr) = (x(wl), x(wr));
        if !bilinear {
            return self
                .entry((xl + 0.5).floor() as usize, (xr + 0.5).floor() as usize)
                .to_vec();
        }
        let a0 = (xl.floor() as usize).min(self.nodes - 2);
        let b0 = (xr.floor() as usize).min(self.nodes - 2);
        let (ta, tb) = (xl - a0 as f64, xr - b0 as f64);
        let mut out = vec![0.0; self.bands * self.bands];
        for (a, b, w) in [
            (a0, b0, (1.0 - ta) * (1.0 - tb)),
            (a0, b0 + 1, (1.0 - ta) * tb),
            (a0 + 1, b0, ta * (1.0 - tb)),
            (a0 + 1, b0 + 1, ta * tb),
        ] {
            for (o, v) in out.iter_mut().zip(self.entry(a, b)) {
                *o += w * v;
            }
        }
        out
    }

    /// The coefficients as f32, for the GPU.
    pub fn to_f32(&self) -> Vec<f32> {
        self.data.iter().map(|&v| v as f32).collect()
    }
}

/// How each wedge is evaluated when horizons become visibility.
#[derive(Clone, Copy, Debug)]
pub enum WedgeSource<'a> {
    /// Exact quadrature (no table).
    Exact,
    /// Table lookup, bilinear or nearest.
    Table(&'a WedgeTable, bool),
}

/// V = Σ_j R_{φ_j} v(ω_j, ω_{j+1 mod nφ}) with φ_j = 2πj/nφ (Eq. 4.19).
pub fn visibility(horizons: &[f64], source: WedgeSource, bands: usize) -> ShResult<Vec<f64>> {
    let nphi = horizons.len();
    let dphi = TAU / nphi.max(1) as f64;
    let mut total = vec![0.0; bands * bands];
    for j in 0..nphi {
        let (wl, wr) = (horizons[j], horizons[(j + 1) % nphi]);
        let mut v = match source {
            WedgeSource::Exact => exact_wedge(wl, wr, dphi, bands)?,
            WedgeSource::Table(t, bilinear) => t.lookup(wl, wr, bilinear),
        };
        sh::rotate_z(&mut v, j as f64 * dphi)?;
        for (t, x) in total.iter_mut().zip(&v) {
            *t += x;
        }
    }
    Ok(total)
}

/// The exact visible fraction of the cosine-weighted hemisphere above a horizon ω(φ) sampled in
/// `nphi` directions and interpolated linearly: `(1/π) ∫∫_{θ>ω(φ)} sin θ cos θ dθ dφ`, the
/// shading of a unit sky (normal +z, ρ = 1) with these horizons. Closed form per wedge
/// direction, integrated over φ numerically.
pub fn exact_sky_fraction(horizons: &[f64], samples_per_wedge: usize) -> f64 {
    let nphi = horizons.len();
    let dphi = TAU / nphi as f64;
    let mut sum = 0.0;
    for j in 0..nphi {
        let (wl, wr) = (horizons[j], horizons[(j + 1) % nphi]);
        for s in 0..samples_per_wedge {
            let t = (s as f64 + 0.5) / samples_per_wedge as f64;
            let w = (wl + t * (wr - wl)).max(0.0);
            // ∫_w^{π/2} sin θ cos θ dθ = cos² w / 2
            sum += 0.5 * w.cos().powi(2) * dphi / samples_per_wedge as f64;
        }
    }
    sum / PI
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cap(half_angle: f64, bands: usize) -> Vec<f64> {
        sh::cap_zh(half_angle, bands).unwrap()
    }

    /// The horizon angle of node `a` of a 64-node table of `kind`, written out from the digest's
    /// ranges (environment [0, π/2], local [−π/2, π/2]) rather than read from the table, so a
    /// table built over the wrong range is not judged by its own nodes.
    fn node_angle(kind: TableKind, a: usize) -> f64 {
        match kind {
            TableKind::Environment => FRAC_PI_2 * a as f64 / 63.0,
            TableKind::Local => -FRAC_PI_2 + PI * a as f64 / 63.0,
        }
    }

    /// Nodes checked: both ends, the two around 0° (the local table has no node there) and a
    /// few between; for the local table half of them are negative horizons.
    const NODES: [usize; 7] = [0, 7, 20, 31, 32, 50, 63];

    /// B1: a constant horizon ω summed over every wedge is the cap of half-angle π/2 − ω about
    /// +z (all m ≠ 0 cancel), for nφ ∈ {8, 16, 32}: with exact wedges at arbitrary ω, and through
    /// both tables the methods use (environment and local, 64 nodes, built by `shared` for each
    /// nφ), looked up nearest and bilinear at their nodes, negative horizons included. Measured
    /// 3e-15 at worst (1e-6 allowed); a table built over the environment's range for the local
    /// kind, or for nφ + 1 directions, is off by 0.2 in c_00 (mutations tried).
    #[test]
    fn swath_closure() {
        for nphi in [8usize, 16, 32] {
            for (kind, omegas) in [
                (TableKind::Environment, vec![0.0, 0.3, 1.2]),
                (TableKind::Local, vec![-0.4, 0.0, 0.3, -1.5]),
            ] {
                for w in omegas {
                    let v = visibility(&vec![w; nphi], WedgeSource::Exact, 4).unwrap();
                    let zh = cap(FRAC_PI_2 - w, 4);
                    let want = sh::zh_rotate(&zh, glam::Vec3::Z).unwrap();
                    for k in 0..16 {
                        assert!(
                            (v[k] - want[k]).abs() < 1e-6,
                            "{kind:?} nphi {nphi} ω {w} coefficient {k}: {} vs {}",
                            v[k],
                            want[k]
                        );
                    }
                }
                let t = WedgeTable::shared(kind, nphi, 64, 4).unwrap();
                assert_eq!((t.kind, t.nphi, t.nodes), (kind, nphi, 64));
                for a in NODES {
                    let w = node_angle(kind, a);
                    let want = sh::zh_rotate(&cap(FRAC_PI_2 - w, 4), glam::Vec3::Z).unwrap();
                    for bilinear in [false, true] {
                        let v = visibility(&vec![w; nphi], WedgeSource::Table(&t, bilinear), 4).unwrap();
                        for k in 0..16 {
                            assert!((v[k] - want[k]).abs() < 1e-6, "{kind:?} table, nphi {nphi}, node {a} (ω {w:.4}), bilinear {bilinear}, coefficient {k}: {} vs {}", v[k], want[k]);
                        }
                    }
                }
            }
        }
    }

    /// B2: every horizon at −π/2 sees the whole sphere: V = [2√π, 0, …].
    #[test]
    fn full_sphere_limit() {
        let t = WedgeTable::build(TableKind::Local, 16, 5, 4).unwrap();
        let v = visibility(&[-FRAC_PI_2; 16], WedgeSource::Table(&t, true), 4).unwrap();
        assert!((v[0] - sh::CONSTANT_ONE_C00).abs() < 1e-6, "{}", v[0]);
        for x in &v[1..] {
            assert!(x.abs() < 1e-6);
        }
    }

    /// R_{Δφ/2} F R_{−Δφ/2} v: the wedge reflected about its bisector (F negates every m < 0
    /// coefficient, the reflection φ → −φ).
    fn mirrored(v: &[f64], dphi: f64) -> Vec<f64> {
        let mut m = v.to_vec();
        sh::rotate_z(&mut m, -0.5 * dphi).unwrap();
        for (i, x) in m.iter_mut().enumerate() {
            if sh::band_of(i).1 < 0 {
                *x = -*x;
            }
        }
        sh::rotate_z(&mut m, 0.5 * dphi).unwrap();
        m
    }

    /// B3: v(ω_r, ω_l) = R_{Δφ/2} F R_{−Δφ/2} v(ω_l, ω_r), for the exact wedges and for the
    /// entries of both tables (environment and local, nφ = 12, 64 nodes) at node pairs, through
    /// `lookup` nearest and bilinear. Catches z-rotation sign errors and wedges integrated over
    /// the wrong interval. A reflection is its own inverse, so a transposed table would still
    /// pass; each entry is therefore also checked to be the exact wedge (ω_l = its row's node,
    /// ω_r = its column's), which a left/right mix-up fails (by 0.014 in c_1,−1, tried). Measured
    /// 3e-16 at worst; a sign-flipped z-rotation is off by 0.09.
    #[test]
    fn mirror_symmetry() {
        let nphi = 12;
        let dphi = TAU / nphi as f64;
        for (kind, pairs) in [
            (TableKind::Environment, [(0.1, 0.9), (0.0, 1.3)]),
            (TableKind::Local, [(-0.7, 0.4), (0.2, -1.1)]),
        ] {
            for (wl, wr) in pairs {
                let a = exact_wedge(wl, wr, dphi, 4).unwrap();
                let b = exact_wedge(wr, wl, dphi, 4).unwrap();
                let m = mirrored(&a, dphi);
                for k in 0..16 {
                    assert!(
                        (m[k] - b[k]).abs() < 1e-12,
                        "exact ({wl}, {wr}) coefficient {k}: {} vs {}",
                        m[k],
                        b[k]
                    );
                }
            }
            let t = WedgeTable::shared(kind, nphi, 64, 4).unwrap();
            assert_eq!((t.kind, t.nphi), (kind, nphi));
            for (na, nb) in [(3usize, 41usize), (0, 63), (20, 31), (32, 55), (62, 9)] {
                let (wl, wr) = (node_angle(kind, na), node_angle(kind, nb));
                for bilinear in [false, true] {
                    let a = t.lookup(wl, wr, bilinear);
                    let b = t.lookup(wr, wl, bilinear);
                    let m = mirrored(&a, dphi);
                    let exact = exact_wedge(wl, wr, dphi, 4).unwrap();
                    for k in 0..16 {
                        assert!(
                            (m[k] - b[k]).abs() < 1e-10,
                            "{kind:?} table, nodes ({na}, {nb}), bilinear {bilinear}, coefficient {k}: {} vs {}",
                            m[k],
                            b[k]
                        );
                        assert!((a[k] - exact[k]).abs() < 1e-10, "{kind:?} table entry ({na}, {nb}), bilinear {bilinear}, coefficient {k}: {} vs the exact wedge {}", a[k], exact[k]);
                    }
                }
            }
        }
    }

    /// A4: shifting the horizons by nφ/4 directions is a z-rotation of V by +90°.
    #[test]
    fn quarter_shift_is_a_quarter_rotation() {
        let h: Vec<f64> = (0..16).map(|j| 0.1 + 0.5 * ((j * 7 % 16) as f64 / 16.0)).collect();
        let mut shifted = h.clone();
        shifted.rotate_right(4);
        let mut v = visibility(&h, WedgeSource::Exact, 4).unwrap();
        sh::rotate_z(&mut v, FRAC_PI_2).unwrap();
        let w = visibility(&shifted, WedgeSource::Exact, 4).unwrap();
        for k in 0..16 {
            assert!((v[k] - w[k]).abs() < 1e-12);
        }
    }

    /// B4: table interpolation error for random horizons, relative to the exact wedges:
    /// nearest ≤ 0.7%, bilinear ≤ 0.05% of |V| (digest: 0.3–0.6% and 0.01%).
    #[test]
    fn interpolation_error() {
        let t = WedgeTable::build(TableKind::Environment, 32, 64, 4).unwrap();
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut worst_nearest, mut worst_bilinear) = (0.0f64, 0.0f64);
        for _ in 0..20 {
            let h: Vec<f64> = (0..32).map(|_| rnd() * 1.2).collect();
            let exact = visibility(&h, WedgeSource::Exact, 4).unwrap();
            let norm = exact.iter().map(|x| x * x).sum::<f64>().sqrt();
            for (bilinear, worst) in [(false, &mut worst_nearest), (true, &mut worst_bilinear)] {
                let v = visibility(&h, WedgeSource::Table(&t, bilinear), 4).unwrap();
                let err = v.iter().zip(&exact).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt() / norm;
                *worst = worst.max(err);
            }
        }
        assert!(worst_nearest < 7e-3, "nearest {worst_nearest}");
        assert!(worst_bilinear < 5e-4, "bilinear {worst_bilinear}");
    }

    /// §4.1 of the digest: a wall of elevation β (horizon atan(tan β cos φ) toward it, 0 away)
    /// shaded by the SH pipeline with exact wedges at nφ = 32 against the exact (1 + cos β)/2.
    #[test]
    fn wall_table_matches_the_digest() {
        let cc = sh::clamped_cosine_zh(4)
            .unwrap()
            .iter()
            .map(|z| z / PI)
            .collect::<Vec<_>>();
        let c = sh::zh_rotate(&cc, glam::Vec3::Z).unwrap();
        let l = {
            let mut l = vec![0.0; 16];
            l[0] = sh::CONSTANT_ONE_C00;
            l
        };
        let gamma = sh::TripleProductTensor::shared(4).unwrap();
        for (beta_deg, want_sh) in [(15.0f64, 0.9748), (30.0, 0.9266), (45.0, 0.8523), (60.0, 0.7529)] {
            let tb = beta_deg.to_radians().tan();
            let h: Vec<f64> = (0..32)
                .map(|j| (tb * (TAU * j as f64 / 32.0).cos()).atan().max(0.0))
                .collect();
            let v = visibility(&h, WedgeSource::Exact, 4).unwrap();
            let tr = gamma.product(&v, &c, 4).unwrap();
            let got: f64 = tr.iter().zip(&l).map(|(a, b)| a * b).sum();
            assert!((got - want_sh).abs() < 2e-4, "β {beta_deg}: {got} vs {want_sh}");
            let exact = 0.5 * (1.0 + beta_deg.to_radians().cos());
            assert!(
                (got - exact).abs() / exact < 0.01,
                "β {beta_deg}: {got} vs exact {exact}"
            );
        }
    }
}
