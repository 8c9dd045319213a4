//! Basis evaluation by the stable normalised associated-Legendre recurrences, reconstruction and
//! the SH dot product.
//!
//! Why this recurrence: the textbook route (the height-field thesis Eq. 3.10–3.12 and a factorial table for
//! K_l^m) overflows and loses digits at high bands because it multiplies huge (2m−1)!! by tiny
//! normalisations. Carrying the *normalised* P̄_l^m = K_l^m P_l^m through the recurrence keeps
//! every intermediate of order one. The azimuthal factors come from the complex power
//! (x + iy)^m = sin^m θ·(cos mφ + i sin mφ), so no trigonometric function is called and the
//! poles are exact.

use super::{bands_of, check_bands, unit_dir, Coeff, ShError, ShResult, MAX_BANDS};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// Writes `P̄_l^m(z) / sin^m θ` (normalised, Condon–Shortley phase) for `0 ≤ m ≤ l < bands` into
/// `out[l(l+1)/2 + m]`, calling `sink(l, m, value)` in the same order. `bands ≤ MAX_BANDS`.
///
/// * `P̄_0^0 = 1/√(4π)`, `P̄_m^m = −√((2m+1)/(2m))·sinθ·P̄_{m−1}^{m−1}` (the sinθ is factored out)
/// * `P̄_{m+1}^m = √(2m+3)·z·P̄_m^m`
/// * `P̄_l^m = a_lm (z P̄_{l−1}^m − b_lm P̄_{l−2}^m)`, `a = √((4l²−1)/(l²−m²))`,
///   `b = √(((l−1)²−m²)/(4(l−1)²−1))`.
pub(crate) fn legendre_normalized(z: f64, bands: usize, mut sink: impl FnMut(usize, usize, f64)) {
    let mut pmm = 0.5 / PI.sqrt();
    for m in 0..bands {
        if m > 0 {
            pmm *= -((2 * m + 1) as f64 / (2 * m) as f64).sqrt();
        }
        sink(m, m, pmm);
        if m + 1 >= bands {
            continue;
        }
        let mut p_prev = pmm;
        let mut p = ((2 * m + 3) as f64).sqrt() * z * pmm;
        sink(m + 1, m, p);
        for l in m + 2..bands {
            let (lf, mf) = (l as f64, m as f64);
            let a = ((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf)).sqrt();
            let b = (((lf - 1.0) * (lf - 1.0) - mf * mf) / (4.0 * (lf - 1.0) * (lf - 1.0) - 1.0)).sqrt();
            let next = a * (z * p - b * p_prev);
            p_prev = p;
            p = next;
            sink(l, m, p);
        }
    }
}

/// Core evaluation for a unit direction; `out.len() ≥ bands²`, `bands ≤ MAX_BANDS` (checked by
/// the callers).
pub(crate) fn eval_unit(d: DVec3, bands: usize, out: &mut [f64]) {
    // cos(mφ)·sin^m θ and sin(mφ)·sin^m θ for m = 0..bands, from (x + iy)^m.
    let mut cs = [(1.0f64, 0.0f64); MAX_BANDS];
    for m in 1..bands {
        let (c, s) = cs[m - 1];
        cs[m] = (d.x * c - d.y * s, d.x * s + d.y * c);
    }
    let sqrt2 = std::f64::consts::SQRT_2;
    legendre_normalized(d.z, bands, |l, m, p| {
        let centre = l * (l + 1);
        if m == 0 {
            out[centre] = p;
        } else {
            out[centre + m] = sqrt2 * p * cs[m].0;
            out[centre - m] = sqrt2 * p * cs[m].1;
        }
    });
}

fn check_out(bands: usize, len: usize) -> ShResult<()> {
    check_bands(bands)?;
    if len < bands * bands {
        return Err(ShError::Length {
            what: "basis output",
            expected: bands * bands,
            got: len,
        });
    }
    Ok(())
}

/// Evaluates the `bands²` basis functions at `dir` (SH frame; normalised here, zero or
/// non-finite → +z) into `out[..bands²]`. `out` may be longer; the rest is untouched.
pub fn eval_basis(dir: Vec3, bands: usize, out: &mut [f32]) -> ShResult<()> {
    check_out(bands, out.len())?;
    let mut tmp = [0.0f64; MAX_BANDS * MAX_BANDS];
    eval_unit(unit_dir(dir.as_dvec3()), bands, &mut tmp);
    for (o, t) in out.iter_mut().zip(&tmp[..bands * bands]) {
        *o = *t as f32;
    }
    Ok(())
}

/// [`eval_basis`] in f64 (for precomputation and tests).
pub fn eval_basis_f64(dir: DVec3, bands: usize, out: &mut [f64]) -> ShResult<()> {
    check_out(bands, out.len())?;
    eval_unit(unit_dir(dir), bands, out);
    Ok(())
}

/// The `bands²` basis values at `dir` (SH frame) as a new vector.
pub fn basis(dir: Vec3, bands: usize) -> ShResult<Vec<f32>> {
    let mut out = vec![0.0; bands.min(MAX_BANDS) * bands.min(MAX_BANDS)];
    eval_basis(dir, bands, &mut out)?;
    Ok(out)
}

/// Reconstruction: the SH function `coeffs` (a whole number of bands) evaluated at `dir`
/// (SH frame): `Σ c_i y_i(dir)`.
pub fn eval<C: Coeff>(coeffs: &[C], dir: Vec3) -> ShResult<C> {
    let bands = bands_of("coefficients", coeffs)?;
    let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
    eval_unit(unit_dir(dir.as_dvec3()), bands, &mut y);
    let mut sum = C::default();
    for (c, y) in coeffs.iter().zip(&y) {
        sum += c.scale(*y);
    }
    Ok(sum)
}

/// [`eval`] in f64.
pub fn eval_f64(coeffs: &[f64], dir: DVec3) -> ShResult<f64> {
    let bands = bands_of("coefficients", coeffs)?;
    let mut y = [0.0f64; MAX_BANDS * MAX_BANDS];
    eval_unit(unit_dir(dir), bands, &mut y);
    Ok(coeffs.iter().zip(&y).map(|(c, y)| c * y).sum())
}

/// `∫ f g dω` of two SH functions = `Σ a_i b_i` (orthonormality). Band counts may differ: the
/// missing bands of the shorter one are zero, so the sum over the common bands is exact.
/// `a` may be RGB, `b` scalar (e.g. light · transfer); both must be whole numbers of bands.
pub fn dot<C: Coeff, S: Copy + Into<f64>>(a: &[C], b: &[S]) -> ShResult<C> {
    bands_of("dot: first operand", a)?;
    bands_of("dot: second operand", b)?;
    let mut sum = C::default();
    for (x, y) in a.iter().zip(b) {
        sum += x.scale((*y).into());
    }
    Ok(sum)
}
