//! Rotations of SH functions: about z (per-band cos/sin mα mixing), of zonal functions to an
//! arbitrary axis, and by an arbitrary rotation matrix (Ivanic–Ruedenberg recurrence).
//!
//! All rotate the *function*: the result g satisfies g(ω) = f(Rᵀω) (see `mod.rs`).

use super::basis::eval_unit;
use super::{bands_of, check_bands, unit_dir, Coeff, ShError, ShResult, MAX_BANDS, SH_TO_WORLD, WORLD_TO_SH};
use glam::{DMat3, DVec3, Mat3, Vec3};
use std::f64::consts::PI;

/// Rotates `coeffs` (a whole number of bands) in place about the SH z axis by `angle` radians
/// (counter-clockwise seen from +z, i.e. φ → φ + angle). Per band, for m > 0 (cos mφ) and −m
/// (sin mφ) — the height-field thesis §1.6, which derives it for the wedge tables:
/// `c'_m = c_m cos mα − c_−m sin mα`, `c'_−m = c_m sin mα + c_−m cos mα`; m = 0 is unchanged.
/// The Condon–Shortley sign is the same for ±m, so it does not enter.
pub fn rotate_z<C: Coeff>(coeffs: &mut [C], angle: f64) -> ShResult<()> {
    let bands = bands_of("rotate_z coefficients", coeffs)?;
    if !angle.is_finite() {
        return Err(ShError::NonFinite("rotation angle"));
    }
    for m in 1..bands {
        let (s, c) = (m as f64 * angle).sin_cos();
        for l in m..bands {
            let (ip, im) = (l * (l + 1) + m, l * (l + 1) - m);
            let (a, b) = (coeffs[ip], coeffs[im]);
            coeffs[ip] = a.scale(c) - b.scale(s);
            coeffs[im] = a.scale(s) + b.scale(c);
        }
    }
    Ok(())
}

/// Rotates a zonal function, given by its ZH coefficients `zh[l]` (the m = 0 coefficients of a
/// function symmetric about +z), so that its axis points along `axis` (SH frame; normalised,
/// zero → +z): `c_lm = √(4π/(2l+1))·z_l·y_lm(axis)` (Sloan; the height-field thesis Eq. 3.36 as corrected in
/// the digest §1.1). Returns `zh.len()²` coefficients.
pub fn zh_rotate<C: Coeff>(zh: &[C], axis: Vec3) -> ShResult<Vec<C>> {
    let bands = zh.len();
    check_bands(bands)?;
    let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
    eval_unit(unit_dir(axis.as_dvec3()), bands, &mut y);
    let mut out = vec![C::default(); bands * bands];
    for (l, z) in zh.iter().enumerate() {
        let k = (4.0 * PI / (2 * l + 1) as f64).sqrt();
        for i in l * l..(l + 1) * (l + 1) {
            out[i] = z.scale(k * y[i]);
        }
    }
    Ok(out)
}

/// The SH rotation matrix of a 3×3 rotation, block diagonal with one (2l+1)² block per band,
/// built by the Ivanic–Ruedenberg recurrence (J. Phys. Chem. 100 (1996) 6342, with the 1998
/// corrections) from the band-1 block, which is R itself with rows/columns ordered (y, z, x).
/// The recurrence is written for the real SH *without* the Condon–Shortley phase; our basis is
/// `D·y` with `D = diag((−1)^m)`, so each block is conjugated: `M_cs = D M D`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShRotation {
    bands: usize,
    /// `blocks[l]`: (2l+1)² row-major, row = output m + l, column = input m + l.
    blocks: Vec<Vec<f64>>,
}

impl ShRotation {
    /// The rotation of SH functions by `r` (a rotation in the SH frame), up to `bands` bands.
    /// `r` must be orthonormal within 1e−3 with determinant > 0 (it is re-orthonormalised in
    /// f64 so the blocks are orthogonal to rounding).
    pub fn new(r: Mat3, bands: usize) -> ShResult<Self> {
        check_bands(bands)?;
        let r = orthonormalize(r.as_dmat3())?;
        // Band 1 in the (y, z, x) order of m = −1, 0, 1 (no CS phase).
        let p = [1usize, 2, 0];
        let mut b1 = vec![0.0; 9];
        for i in 0..3 {
            for j in 0..3 {
                b1[i * 3 + j] = r.col(p[j])[p[i]];
            }
        }
        let mut blocks = vec![vec![1.0]];
        if bands > 1 {
            blocks.push(b1);
        }
        for l in 2..bands {
            let next = band_block(l, &blocks[1], &blocks[l - 1]);
            blocks.push(next);
        }
        // Condon–Shortley: conjugate by diag((−1)^m).
        for (l, block) in blocks.iter_mut().enumerate() {
            let w = 2 * l + 1;
            for i in 0..w {
                for j in 0..w {
                    if (i + j) % 2 == 1 {
                        // (−1)^(m+n) with m = i − l, n = j − l: the parity of i + j.
                        block[i * w + j] = -block[i * w + j];
                    }
                }
            }
        }
        Ok(Self { bands, blocks })
    }

    /// The same rotation given in penumbra's world frame (y up): conjugated into the SH frame,
    /// `R_sh = WORLD_TO_SH · r_world · SH_TO_WORLD`.
    pub fn from_world(r_world: Mat3, bands: usize) -> ShResult<Self> {
        Self::new(WORLD_TO_SH * r_world * SH_TO_WORLD, bands)
    }

    /// Band count this rotation was built for.
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// The (2l+1)² row-major block of band `l` (`None` beyond [`ShRotation::bands`]).
    pub fn band_matrix(&self, l: usize) -> Option<&[f64]> {
        self.blocks.get(l).map(Vec::as_slice)
    }

    /// Rotates `input` (a whole number of bands, at most [`ShRotation::bands`]) into `output` of
    /// the same length.
    pub fn apply<C: Coeff>(&self, input: &[C], output: &mut [C]) -> ShResult<()> {
        let bands = bands_of("rotation input", input)?;
        if bands > self.bands {
            return Err(ShError::Length {
                what: "rotation input (bands² of the rotation)",
                expected: self.bands * self.bands,
                got: input.len(),
            });
        }
        if output.len() != input.len() {
            return Err(ShError::Length {
                what: "rotation output",
                expected: input.len(),
                got: output.len(),
            });
        }
        for (l, block) in self.blocks.iter().enumerate().take(bands) {
            let (w, base) = (2 * l + 1, l * l);
            for i in 0..w {
                let mut acc = C::default();
                for j in 0..w {
                    acc += input[base + j].scale(block[i * w + j]);
                }
                output[base + i] = acc;
            }
        }
        Ok(())
    }

    /// [`ShRotation::apply`] into a new vector.
    pub fn rotate<C: Coeff>(&self, input: &[C]) -> ShResult<Vec<C>> {
        let mut out = vec![C::default(); input.len()];
        self.apply(input, &mut out)?;
        Ok(out)
    }
}

/// Validates and re-orthonormalises a rotation matrix (Gram–Schmidt on the columns).
fn orthonormalize(r: DMat3) -> ShResult<DMat3> {
    if !r.is_finite() {
        return Err(ShError::NonFinite("rotation matrix"));
    }
    let e = r.transpose() * r - DMat3::IDENTITY;
    let err = [e.x_axis, e.y_axis, e.z_axis]
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0, f64::max);
    let det = r.determinant();
    if err > 1e-3 || det <= 0.0 {
        return Err(ShError::NotRotation {
            orthogonality_error: err,
            det,
        });
    }
    let c0 = r.x_axis.normalize();
    let c1 = (r.y_axis - c0 * c0.dot(r.y_axis)).normalize();
    Ok(DMat3::from_cols(c0, c1, c0.cross(c1)))
}

/// Element (m, n) of a centred (2l+1)² block.
fn at(block: &[f64], l: usize, m: i64, n: i64) -> f64 {
    let w = 2 * l as i64 + 1;
    block[((m + l as i64) * w + (n + l as i64)) as usize]
}

/// Block of band `l ≥ 2` from band 1 (`r1`) and band l − 1 (`prev`): M_mn = u U + v V + w W.
fn band_block(l: usize, r1: &[f64], prev: &[f64]) -> Vec<f64> {
    let li = l as i64;
    let w = 2 * l + 1;
    // Ivanic–Ruedenberg's helper P (their Table 2).
    let p = |i: i64, a: i64, b: i64| -> f64 {
        if b == li {
            at(r1, 1, i, 1) * at(prev, l - 1, a, li - 1) - at(r1, 1, i, -1) * at(prev, l - 1, a, -li + 1)
        } else if b == -li {
            at(r1, 1, i, 1) * at(prev, l - 1, a, -li + 1) + at(r1, 1, i, -1) * at(prev, l - 1, a, li - 1)
        } else {
            at(r1, 1, i, 0) * at(prev, l - 1, a, b)
        }
    };
    let delta = |a: i64, b: i64| if a == b { 1.0 } else { 0.0 };
    let mut out = vec![0.0; w * w];
    for m in -li..=li {
        for n in -li..=li {
            let d0 = delta(m, 0);
            let denom = if n.abs() == li {
                (2 * li * (2 * li - 1)) as f64
            } else {
                ((li + n) * (li - n)) as f64
            };
            let am = m.abs();
            let u = (((li + m) * (li - m)) as f64 / denom).sqrt();
            let v = 0.5 * ((1.0 + d0) * ((li + am - 1) * (li + am)) as f64 / denom).sqrt() * (1.0 - 2.0 * d0);
            let ww = -0.5 * (((li - am - 1) * (li - am)) as f64 / denom).sqrt() * (1.0 - d0);
            let mut val = 0.0;
            if u != 0.0 {
                val += u * p(0, m, n);
            }
            if v != 0.0 {
                let vv = if m == 0 {
                    p(1, 1, n) + p(-1, -1, n)
                } else if m > 0 {
                    p(1, m - 1, n) * (1.0 + delta(m, 1)).sqrt() - p(-1, -m + 1, n) * (1.0 - delta(m, 1))
                } else {
                    // The 1998 correction: (1 − δ) on the first term, √(1 + δ) on the second.
                    p(1, m + 1, n) * (1.0 - delta(m, -1)) + p(-1, -m - 1, n) * (1.0 + delta(m, -1)).sqrt()
                };
                val += v * vv;
            }
            if ww != 0.0 {
                let wv = if m > 0 {
                    p(1, m + 1, n) + p(-1, -m - 1, n)
                } else {
                    p(1, m - 1, n) - p(-1, -m + 1, n)
                };
                val += ww * wv;
            }
            out[((m + li) as usize) * w + (n + li) as usize] = val;
        }
    }
    out
}

/// The rotation (SH frame) taking +z to `axis` by the shortest arc (180° about x for −z);
/// `axis` is normalised, zero → identity. With [`ShRotation`] it rotates a zonal function the
/// long way, which the tests compare with [`zh_rotate`].
pub fn rotation_z_to(axis: Vec3) -> Mat3 {
    rotation_z_to_f64(axis.as_dvec3()).as_mat3()
}

pub(crate) fn rotation_z_to_f64(axis: DVec3) -> DMat3 {
    let a = unit_dir(axis);
    let c = a.z;
    if c < -1.0 + 1e-12 {
        return DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0)); // 180° about x
    }
    let v = DVec3::Z.cross(a);
    let k = 1.0 / (1.0 + c);
    DMat3::from_cols(
        DVec3::new(v.x * v.x * k + c, v.x * v.y * k + v.z, v.x * v.z * k - v.y),
        DVec3::new(v.y * v.x * k - v.z, v.y * v.y * k + c, v.y * v.z * k + v.x),
        DVec3::new(v.z * v.x * k + v.y, v.z * v.y * k - v.x, v.z * v.z * k + c),
    )
}
