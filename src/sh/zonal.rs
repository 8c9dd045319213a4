//! Zonal harmonics (functions symmetric about +z, one coefficient z_l = c_{l,0} per band):
//! closed forms for the clamped cosine (Lambert kernel), spherical caps and the hemisphere, and
//! convolution with a zonal kernel (irradiance from radiance).
//!
//! Both closed forms reduce to integrals of Legendre polynomials, using
//! `(2l+1) P_l = P'_{l+1} − P'_{l−1}` and `P_k(1) = 1`:
//! * `∫_c^1 P_l(x) dx = (P_{l−1}(c) − P_{l+1}(c)) / (2l+1)` for l ≥ 1 (and `1 − c` for l = 0),
//! * `x P_l = ((l+1) P_{l+1} + l P_{l−1}) / (2l+1)`.
//!
//! With `y_l0 = N_l P_l(cos θ)`, `N_l = √((2l+1)/(4π))`, a zonal `f(cos θ)` has
//! `z_l = 2π N_l ∫ f(x) P_l(x) dx`.

use super::{bands_of, check_bands, Coeff, ShError, ShResult};
use std::f64::consts::PI;

/// Legendre polynomials `P_0(x) … P_n(x)` (n + 1 values) by Bonnet's recurrence. `n` is
/// clamped to 65536.
pub fn legendre(n: usize, x: f64) -> Vec<f64> {
    let n = n.min(1 << 16);
    let mut p = Vec::with_capacity(n + 1);
    p.push(1.0);
    if n >= 1 {
        p.push(x);
    }
    for k in 2..=n {
        let v = ((2 * k - 1) as f64 * x * p[k - 1] - (k - 1) as f64 * p[k - 2]) / k as f64;
        p.push(v);
    }
    p
}

fn n_l(l: usize) -> f64 {
    ((2 * l + 1) as f64 / (4.0 * PI)).sqrt()
}

/// `∫_c^1 P_k(x) dx` for k = 0..=n, from `P_0(c) … P_{n+1}(c)`.
fn legendre_tail_integrals(n: usize, c: f64) -> Vec<f64> {
    let p = legendre(n + 1, c);
    (0..=n)
        .map(|k| {
            if k == 0 {
                1.0 - c
            } else {
                (p[k - 1] - p[k + 1]) / (2 * k + 1) as f64
            }
        })
        .collect()
}

/// ZH coefficients of the clamped cosine `max(cos θ, 0)` about +z:
/// `z_l = 2π N_l ∫_0^1 x P_l(x) dx` = √π/2, √(π/3), √(5π)/8, 0, −√π/16, 0, √(13π)/128, 0, …
/// (0.886227, 1.023327, 0.495416, 0, −0.110778, 0, 0.049927, 0: the Ca3D-Engine thesis §5.1 test 4;
/// the height-field thesis §1.7 lists the first four times 1/π). Odd l > 1 vanish.
pub fn clamped_cosine_zh(bands: usize) -> ShResult<Vec<f64>> {
    check_bands(bands)?;
    let tail = legendre_tail_integrals(bands, 0.0);
    Ok((0..bands)
        .map(|l| {
            // ∫_0^1 x P_l = ((l+1) ∫P_{l+1} + l ∫P_{l−1}) / (2l+1)
            let lower = if l > 0 { l as f64 * tail[l - 1] } else { 0.0 };
            let j = ((l + 1) as f64 * tail[l + 1] + lower) / (2 * l + 1) as f64;
            2.0 * PI * n_l(l) * j
        })
        .collect())
}

/// The Lambert convolution kernel `A_l = √(4π/(2l+1))·z_l` of the clamped cosine:
/// π, 2π/3, π/4, 0, −π/24, 0, π/64, … (Ramamoorthi–Hanrahan; Staniszewski 2005 §5 test 1 `Â_l`).
/// Irradiance is `E_lm = A_l L_lm`.
pub fn lambert_kernel(bands: usize) -> ShResult<Vec<f64>> {
    Ok(clamped_cosine_zh(bands)?
        .into_iter()
        .enumerate()
        .map(|(l, z)| (4.0 * PI / (2 * l + 1) as f64).sqrt() * z)
        .collect())
}

/// ZH coefficients of the indicator of a spherical cap of half-angle `half_angle` (radians,
/// clamped to [0, π]) about +z, i.e. a unit-radiance spherical light seen under that angle:
/// `z_0 = √π (1 − cos α)`, `z_l = √(π/(2l+1))·(P_{l−1}(cos α) − P_{l+1}(cos α))`.
/// For l ≤ 3 this equals the height-field thesis's Appendix A.1 (digest §1.8): `(√(3π)/2) s²`,
/// `(√(5π)/2) c s²`, `(√(7π)/8) s² (5c² − 1)`. The cap's integral, its solid angle
/// `2π(1 − cos α)`, is `z_0·∫y_00 dω = z_0·4π·Y00 = z_0·2√π`.
pub fn cap_zh(half_angle: f64, bands: usize) -> ShResult<Vec<f64>> {
    check_bands(bands)?;
    if half_angle.is_nan() {
        return Err(ShError::NonFinite("cap half-angle"));
    }
    let c = half_angle.clamp(0.0, PI).cos();
    let tail = legendre_tail_integrals(bands - 1, c);
    Ok((0..bands).map(|l| 2.0 * PI * n_l(l) * tail[l]).collect())
}

/// The upper hemisphere's indicator: [`cap_zh`] with α = π/2 — √π, 1.534990, 0, −0.586184, 0,
/// 0.367410, 0, −0.268152 (the Ca3D-Engine thesis §5.1 test 5).
pub fn hemisphere_zh(bands: usize) -> ShResult<Vec<f64>> {
    cap_zh(PI / 2.0, bands)
}

/// Value of the zonal function `zh` at angle θ from its axis: `Σ z_l N_l P_l(cos θ)`.
/// `cos_angle` is clamped to [−1, 1]; an empty `zh` gives 0.
pub fn eval_zonal(zh: &[f64], cos_angle: f64) -> f64 {
    if zh.is_empty() {
        return 0.0;
    }
    let p = legendre(zh.len() - 1, cos_angle.clamp(-1.0, 1.0));
    zh.iter().enumerate().map(|(l, z)| z * n_l(l) * p[l]).sum()
}

/// Numerical ZH projection of a zonal profile `f(cos θ)` that is zero outside
/// `z_min ≤ cos θ ≤ z_max`: `z_l = 2π N_l ∫ f(x) P_l(x) dx` by `nodes`-point Gauss–Legendre on
/// that interval (exact for polynomial f of degree ≤ 2·nodes − bands). For kernels without a
/// closed form (Phong lobes, cosine-weighted caps); the closed forms above are tested with it.
pub fn project_zonal(
    mut f: impl FnMut(f64) -> f64,
    bands: usize,
    z_min: f64,
    z_max: f64,
    nodes: usize,
) -> ShResult<Vec<f64>> {
    check_bands(bands)?;
    if !z_min.is_finite() || !z_max.is_finite() {
        return Err(ShError::NonFinite("zonal integration bounds"));
    }
    let (a, b) = (z_min.clamp(-1.0, 1.0), z_max.clamp(-1.0, 1.0));
    let (x, w) = super::projection::gauss_legendre(nodes)?;
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mut z = vec![0.0; bands];
    for (xi, wi) in x.iter().zip(&w) {
        let t = mid + half * xi;
        let v = f(t) * wi * half;
        let p = legendre(bands - 1, t);
        for (l, zl) in z.iter_mut().enumerate() {
            *zl += 2.0 * PI * n_l(l) * v * p[l];
        }
    }
    Ok(z)
}

/// Convolves `coeffs` in place with the zonal kernel `kernel_zh` (ZH coefficients about +z,
/// at least as many bands as `coeffs`): `(k∗c)_lm = √(4π/(2l+1))·k_l·c_lm` (the height-field thesis Eq. 3.24).
pub fn convolve<C: Coeff>(coeffs: &mut [C], kernel_zh: &[f64]) -> ShResult<()> {
    let bands = bands_of("convolution coefficients", coeffs)?;
    if kernel_zh.len() < bands {
        return Err(ShError::Length {
            what: "convolution kernel bands",
            expected: bands,
            got: kernel_zh.len(),
        });
    }
    for (l, k) in kernel_zh.iter().enumerate().take(bands) {
        let s = (4.0 * PI / (2 * l + 1) as f64).sqrt() * k;
        for c in &mut coeffs[l * l..(l + 1) * (l + 1)] {
            *c = c.scale(s);
        }
    }
    Ok(())
}

/// Irradiance from radiance coefficients: `E_lm = A_l L_lm` ([`lambert_kernel`]). Evaluating
/// the result at a normal n gives `E(n) = ∫ L(ω) max(n·ω, 0) dω` up to band truncation; a
/// Lambertian surface then reflects `ρ/π · E(n)`.
pub fn irradiance<C: Coeff>(radiance: &[C]) -> ShResult<Vec<C>> {
    let bands = bands_of("radiance coefficients", radiance)?;
    let mut e = radiance.to_vec();
    convolve(&mut e, &clamped_cosine_zh(bands)?)?;
    Ok(e)
}
