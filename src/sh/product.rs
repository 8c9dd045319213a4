//! The SH triple product: the product of two SH functions projected back onto n bands,
//! `(a • b)_k = Σ_ij a_i b_j Γ_ijk` with `Γ_ijk = ∫ y_i y_j y_k dω` (the height-field thesis Eq. 3.25–3.30).
//!
//! Γ is computed numerically but exactly (to rounding): every y_lm separates into
//! `P̄_l^|m|(z)·Φ_m(φ)`, so `Γ = ∫ P̄P̄P̄ dz · ∫ ΦΦΦ dφ`. The φ factor is a trigonometric
//! polynomial of degree ≤ 3(B−1), integrated exactly by 3B uniform samples; the z factor is a
//! polynomial of degree ≤ 3(B−1) whenever the φ factor is non-zero (the |m| then sum to an even
//! number, so the sin^m θ factors combine to powers of 1 − z²), integrated exactly by
//! ⌊3B/2⌋ + 1 Gauss–Legendre nodes. Entries with |Γ| ≤ 1e−7 (structural zeros, ~1e−17) are
//! dropped. The selection rules (l parity, triangle inequality, |m_k| = ||m_i| ± |m_j||) are
//! used only to skip work; the numbers decide what is kept.

use super::basis::legendre_normalized;
use super::projection::gauss_legendre;
use super::{band_of, bands_of, check_bands, Coeff, ShError, ShResult, MAX_BANDS};
use std::f64::consts::TAU;
use std::sync::OnceLock;

/// Entries with a magnitude at or below this are dropped.
const KEEP_ABOVE: f64 = 1e-7;

/// The sparse tensor Γ_ijk for all i, j, k < bands².
#[derive(Debug, Clone)]
pub struct TripleProductTensor {
    bands: usize,
    /// Distinct entries with i ≤ j ≤ k, sorted.
    unique: Vec<([u16; 3], f64)>,
    /// For output k: `row_start[k]..row_start[k+1]` indexes `pairs`/`values` with every ordered
    /// (i, j) such that Γ_ijk is kept.
    row_start: Vec<usize>,
    pairs: Vec<(u16, u16)>,
    values: Vec<f64>,
}

static SHARED: [OnceLock<TripleProductTensor>; MAX_BANDS + 1] = [const { OnceLock::new() }; MAX_BANDS + 1];

/// The z factor: P̄_l^|m|(z_q) (with sin^|m| θ) at the Gauss–Legendre nodes, and the weights.
struct ThetaFactors {
    weights: Vec<f64>,
    /// Per node q and (l, |m|) in triangular order t: `values[q · per_node + t]`.
    values: Vec<f64>,
    per_node: usize,
}

impl ThetaFactors {
    fn new(bands: usize) -> ShResult<Self> {
        let nz = 3 * bands / 2 + 1;
        let (zs, weights) = gauss_legendre(nz)?;
        let per_node = bands * (bands + 1) / 2;
        let mut values = vec![0.0; nz * per_node];
        for (q, z) in zs.iter().enumerate() {
            let s = (1.0 - z * z).max(0.0).sqrt();
            legendre_normalized(*z, bands, |l, m, p| {
                values[q * per_node + l * (l + 1) / 2 + m] = p * s.powi(m as i32)
            });
        }
        Ok(ThetaFactors {
            weights,
            values,
            per_node,
        })
    }

    /// ∫ P̄ P̄ P̄ dz of the three triangular indices.
    fn integral(&self, ti: usize, tj: usize, tk: usize) -> f64 {
        let (w, v, n) = (&self.weights, &self.values, self.per_node);
        (0..w.len())
            .map(|q| w[q] * v[q * n + ti] * v[q * n + tj] * v[q * n + tk])
            .sum()
    }
}

/// The φ factor: ∫ Φ_a Φ_b Φ_c dφ for a, b, c in −(B−1)..=B−1.
struct PhiIntegrals {
    /// Orders per axis, 2B − 1.
    orders: usize,
    /// B − 1: the index of order m is m + offset.
    offset: i32,
    values: Vec<f64>,
}

impl PhiIntegrals {
    fn new(bands: usize) -> Self {
        let mr = 2 * bands - 1;
        let off = bands as i32 - 1;
        let nphi = 3 * bands;
        let phi_val = |m: i32, phi: f64| match m {
            0 => 1.0,
            m if m > 0 => std::f64::consts::SQRT_2 * (m as f64 * phi).cos(),
            m => std::f64::consts::SQRT_2 * (-m as f64 * phi).sin(),
        };
        let samples: Vec<Vec<f64>> = (0..mr)
            .map(|a| {
                (0..nphi)
                    .map(|t| phi_val(a as i32 - off, (t as f64 + 0.5) * TAU / nphi as f64))
                    .collect()
            })
            .collect();
        let mut values = vec![0.0; mr * mr * mr];
        for a in 0..mr {
            for b in a..mr {
                for c in b..mr {
                    let s: f64 = (0..nphi)
                        .map(|t| samples[a][t] * samples[b][t] * samples[c][t])
                        .sum::<f64>()
                        * TAU
                        / nphi as f64;
                    let s = if s.abs() < 1e-12 { 0.0 } else { s };
                    for (x, y, z) in [(a, b, c), (a, c, b), (b, a, c), (b, c, a), (c, a, b), (c, b, a)] {
                        values[(x * mr + y) * mr + z] = s;
                    }
                }
            }
        }
        PhiIntegrals {
            orders: mr,
            offset: off,
            values,
        }
    }

    fn get(&self, mi: i32, mj: i32, mk: i32) -> f64 {
        let (mr, off) = (self.orders, self.offset);
        self.values[(((mi + off) as usize) * mr + (mj + off) as usize) * mr + (mk + off) as usize]
    }
}

/// The kept entries Γ_ijk with i ≤ j ≤ k, sorted.
fn unique_entries(bands: usize, theta: &ThetaFactors, phi: &PhiIntegrals) -> Vec<([u16; 3], f64)> {
    let n = bands * bands;
    let lm: Vec<(usize, i32)> = (0..n).map(band_of).collect();
    let tri = |l: usize, m: i32| l * (l + 1) / 2 + m.unsigned_abs() as usize;
    let mut unique = Vec::new();
    for i in 0..n {
        let (li, mi) = lm[i];
        for j in i..n {
            let (lj, mj) = lm[j];
            // l_k ≥ l_j ≥ l_i, so only l_k ≤ l_i + l_j constrains k.
            let k_end = ((li + lj + 1) * (li + lj + 1)).min(n);
            for (k, &(lk, mk)) in lm.iter().enumerate().take(k_end).skip(j) {
                if (li + lj + lk) % 2 == 1 {
                    continue;
                }
                let f = phi.get(mi, mj, mk);
                if f == 0.0 {
                    continue;
                }
                let v = f * theta.integral(tri(li, mi), tri(lj, mj), tri(lk, mk));
                if v.abs() > KEEP_ABOVE {
                    unique.push(([i as u16, j as u16, k as u16], v));
                }
            }
        }
    }
    unique
}

/// Every distinct permutation of the unique entries expanded into per-output rows of `n`
/// outputs: (row starts, (i, j) pairs, values).
fn output_rows(n: usize, unique: &[([u16; 3], f64)]) -> (Vec<usize>, Vec<(u16, u16)>, Vec<f64>) {
    let mut rows: Vec<Vec<(u16, u16, f64)>> = vec![Vec::new(); n];
    for &([i, j, k], v) in unique {
        let mut perms = [[i, j, k], [i, k, j], [j, i, k], [j, k, i], [k, i, j], [k, j, i]];
        perms.sort_unstable();
        let mut last = None;
        for p in perms {
            if last != Some(p) {
                rows[p[2] as usize].push((p[0], p[1], v));
                last = Some(p);
            }
        }
    }
    let mut row_start = Vec::with_capacity(n + 1);
    let mut pairs = Vec::new();
    let mut values = Vec::new();
    for row in rows {
        row_start.push(pairs.len());
        for (i, j, v) in row {
            pairs.push((i, j));
            values.push(v);
        }
    }
    row_start.push(pairs.len());
    (row_start, pairs, values)
}

impl TripleProductTensor {
    /// Computes Γ for `bands` bands (1..=16). 4 bands: ~1 ms; 16 bands: well under a second.
    pub fn new(bands: usize) -> ShResult<Self> {
        check_bands(bands)?;
        let theta = ThetaFactors::new(bands)?;
        let phi = PhiIntegrals::new(bands);
        let unique = unique_entries(bands, &theta, &phi);
        let (row_start, pairs, values) = output_rows(bands * bands, &unique);
        Ok(Self {
            bands,
            unique,
            row_start,
            pairs,
            values,
        })
    }

    /// A process-wide tensor for `bands`, computed on first use.
    pub fn shared(bands: usize) -> ShResult<&'static Self> {
        check_bands(bands)?;
        if let Some(t) = SHARED[bands].get() {
            return Ok(t);
        }
        let t = Self::new(bands)?;
        Ok(SHARED[bands].get_or_init(|| t))
    }

    /// Band count.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// The kept entries with i ≤ j ≤ k (Γ is symmetric in all three), sorted by (i, j, k); for
    /// generating unrolled GPU code.
    pub fn unique_entries(&self) -> &[([u16; 3], f64)] {
        &self.unique
    }

    /// Number of kept ordered entries (i, j, k).
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// Whether no entry is kept (never: Γ_000 = Y00).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Γ_ijk (0 for dropped entries or indices out of range).
    pub fn get(&self, i: usize, j: usize, k: usize) -> f64 {
        let mut key = [i, j, k];
        key.sort_unstable();
        if key[2] >= self.bands * self.bands {
            return 0.0;
        }
        let key = key.map(|x| x as u16);
        self.unique
            .binary_search_by(|(e, _)| e.cmp(&key))
            .map(|p| self.unique[p].1)
            .unwrap_or(0.0)
    }

    /// `(a • b)` onto `out_bands` bands. `a` and `b` are whole numbers of bands; every band count
    /// must be ≤ this tensor's.
    pub fn product<C: Coeff, S: Copy + Into<f64>>(&self, a: &[C], b: &[S], out_bands: usize) -> ShResult<Vec<C>> {
        let ba = bands_of("product: first operand", a)?;
        let bb = bands_of("product: second operand", b)?;
        check_bands(out_bands)?;
        if ba.max(bb).max(out_bands) > self.bands {
            return Err(ShError::Bands(ba.max(bb).max(out_bands)));
        }
        let (na, nb) = (a.len(), b.len());
        let mut out = vec![C::default(); out_bands * out_bands];
        for (k, o) in out.iter_mut().enumerate() {
            let r = self.row_start[k]..self.row_start[k + 1];
            for (&(i, j), v) in self.pairs[r.clone()].iter().zip(&self.values[r]) {
                let (i, j) = (i as usize, j as usize);
                if i < na && j < nb {
                    *o += a[i].scale(v * b[j].into());
                }
            }
        }
        Ok(out)
    }
}

/// The product of two SH functions projected onto `bands` bands (the height-field thesis Eq. 3.25), using the
/// shared tensor of the largest band count involved. `a` may be RGB and `b` scalar (light •
/// visibility). Truncated products are what the seeds use; they are not associative.
pub fn product<C: Coeff, S: Copy + Into<f64>>(a: &[C], b: &[S], bands: usize) -> ShResult<Vec<C>> {
    let ba = bands_of("product: first operand", a)?;
    let bb = bands_of("product: second operand", b)?;
    check_bands(bands)?;
    TripleProductTensor::shared(ba.max(bb).max(bands))?.product(a, b, bands)
}

/// The triple-product term list `sh_product` in `glsl/common/sh.glsl` consumes, for `bands`
/// bands (1..=[`GLSL_MAX_BANDS`](super::GLSL_MAX_BANDS)): one `[packed, bits]` per ordered
/// (i, j, k) with Γ_ijk kept, `packed = i | j << 8 | k << 16` and `bits` the f32 bits of Γ_ijk.
/// Ordered by the distinct (i ≤ j ≤ k) entries, then their distinct permutations, so the GPU's
/// summation order is fixed.
pub fn product_terms(bands: usize) -> ShResult<Vec<[u32; 2]>> {
    // The GLSL's coefficient arrays hold 8 bands; a longer list would only be skipped there.
    if !(1..=super::GLSL_MAX_BANDS).contains(&bands) {
        return Err(ShError::Range {
            what: "bands of a GPU product term list",
            range: "1..=8",
            got: bands as f64,
        });
    }
    let gamma = TripleProductTensor::shared(bands)?;
    let mut out = Vec::with_capacity(gamma.len());
    for &([a, b, c], v) in gamma.unique_entries() {
        let mut perms = [[a, b, c], [a, c, b], [b, a, c], [b, c, a], [c, a, b], [c, b, a]];
        perms.sort_unstable();
        let mut last = None;
        for p @ [i, j, k] in perms {
            if last != Some(p) {
                out.push([i as u32 | (j as u32) << 8 | (k as u32) << 16, (v as f32).to_bits()]);
                last = Some(p);
            }
        }
    }
    Ok(out)
}

/// `M` with `(a • b) = M b` for every `b` of `bands` bands (the height-field thesis Eq. 3.29–3.30,
/// `M_kj = Σ_i a_i Γ_ijk = ∫ a y_j y_k`), row-major `bands² × bands²`.
#[derive(Debug, Clone, PartialEq)]
pub struct ProductMatrix<C> {
    dim: usize,
    data: Vec<C>,
}

impl<C: Coeff> ProductMatrix<C> {
    /// Rows (= columns) = bands².
    pub fn dim(&self) -> usize {
        self.dim
    }
    /// Row-major entries.
    pub fn as_slice(&self) -> &[C] {
        &self.data
    }
    /// `M b`; `b.len()` must be [`ProductMatrix::dim`].
    pub fn apply<S: Copy + Into<f64>>(&self, b: &[S]) -> ShResult<Vec<C>> {
        if b.len() != self.dim {
            return Err(ShError::Length {
                what: "product matrix operand",
                expected: self.dim,
                got: b.len(),
            });
        }
        Ok(self
            .data
            .chunks_exact(self.dim)
            .map(|row| {
                row.iter()
                    .zip(b)
                    .fold(C::default(), |acc, (m, x)| acc + m.scale((*x).into()))
            })
            .collect())
    }
}

/// The product matrix of `a` (any whole number of bands) for operands and results of `bands`
/// bands.
pub fn product_matrix<C: Coeff>(a: &[C], bands: usize) -> ShResult<ProductMatrix<C>> {
    let ba = bands_of("product matrix operand", a)?;
    check_bands(bands)?;
    let t = TripleProductTensor::shared(ba.max(bands))?;
    let dim = bands * bands;
    let mut data = vec![C::default(); dim * dim];
    for k in 0..dim {
        let r = t.row_start[k]..t.row_start[k + 1];
        for (&(i, j), v) in t.pairs[r.clone()].iter().zip(&t.values[r]) {
            let (i, j) = (i as usize, j as usize);
            if i < a.len() && j < dim {
                data[k * dim + j] += a[i].scale(*v);
            }
        }
    }
    Ok(ProductMatrix { dim, data })
}
