//! Spherical harmonics: the core every SH lighting method shares (the height-field thesis's height-field
//! shadows, the Ca3D-Engine thesis's SH light-maps, Staniszewski 2005's GPU transfer). CPU side here; the GPU side
//! (basis evaluation, z/ZH/general rotation, kernels, windows, the triple product over
//! [`product_terms`], texel solid angles) is `glsl/common/sh.glsl`, which follows exactly the
//! same conventions and algorithms, and the projection of environment images
//! (equirectangular or cube) is a compute pass, [`ShProjector`] (`gpu.rs`, `glsl/sh/`).
//!
//! # Conventions (one for the whole crate; the GLSL matches)
//!
//! * **Real SH, orthonormal over the sphere**: ∫ y_i y_j dω = δ_ij.
//!   `y_l^m = √2·K_l^m·cos(mφ)·P_l^m(cos θ)` for m > 0, `K_l^0·P_l^0(cos θ)` for m = 0 and
//!   `√2·K_l^|m|·sin(|m|φ)·P_l^|m|(cos θ)` for m < 0, with
//!   `K_l^m = √((2l+1)/(4π)·(l−m)!/(l+m)!)`. This is the definition of the height-field thesis (Eq. 3.19–3.20),
//!   of the Ca3D-Engine thesis §5.1.1 and of Green's "Gritty Details", which Staniszewski 2005 cites.
//! * **Condon–Shortley phase included**: `P_m^m = (−1)^m (2m−1)!! (1−x²)^{m/2}` (the height-field thesis
//!   Eq. 3.10). Hence `y_1^{−1} = −0.488603·y`, `y_1^0 = +0.488603·z`, `y_1^1 = −0.488603·x`
//!   (the Ca3D-Engine thesis §5.1 test 1). Staniszewski 2005's appendix prints the constants without signs; only
//!   consistency matters, and every piece of penumbra uses this one.
//! * **Flat index** `i = l(l+1) + m`; "n bands" means l = 0..n−1, i.e. n² coefficients (the height-field thesis's
//!   "order 3" and "4 bands" are both 16 coefficients). [`MAX_BANDS`] = 16 bands are supported
//!   everywhere on the CPU; the GLSL evaluates up to 8 bands.
//! * **SH frame: z up.** θ is the polar angle from +z, φ the azimuth from +x toward +y:
//!   `(sin θ cos φ, sin θ sin φ, cos θ)`. All functions of this module take and return
//!   directions **in the SH frame** unless their name says `world`.
//! * **penumbra's world is right-handed, y up.** It maps to the SH frame by the proper rotation
//!   `sh = (x_w, −z_w, y_w)` ([`world_to_sh`]; inverse [`sh_to_world`]; as matrices
//!   [`WORLD_TO_SH`] / [`SH_TO_WORLD`]): world up (+y) is the SH pole +z, world +x stays +x, and
//!   world −z (where the default camera looks) is SH +y. A height field lying in the world xz
//!   plane therefore has its horizon in the SH equator, and the height-field thesis's azimuth φ is measured from
//!   world +x toward world −z: a horizontal world direction (dx, 0, dz) has SH azimuth
//!   atan2(−dz, dx).
//! * **Rotations** act on functions: rotating `f` by a rotation matrix `R` (in the SH frame) gives
//!   `g(ω) = f(Rᵀω)`, so a lobe around axis `a` ends up around `R·a`. z-rotation by α is the
//!   special case `R = R_z(α)` (the height-field thesis §1.6 formulas).
//! * **Coefficients are projections**: `c_i = ∫ f(ω) y_i(ω) dω` (no 1/π or 4π folded in). The
//!   dot product of two coefficient vectors is `∫ f g dω`. Irradiance from radiance is
//!   `E(n) = Σ A_l L_lm y_lm(n)` with `A_l = π, 2π/3, π/4, 0, −π/24, …` ([`lambert_kernel`]);
//!   Lambertian exit radiance is `ρ/π · E`.
//! * Errors: public functions never panic on bad input; they return [`ShError`] or clamp a
//!   documented range (directions are normalised, a zero or non-finite direction is +z).
//!
//! Values and tests come from the digests in the notes on the source documents: seed-001 §7 A (SH core), §1.6
//! (z-rotation), §1.8 (cap ZH), seed-000 §5.1–5.2, seed-002 §5 and its appendix A.

mod basis;
mod gpu;
mod product;
mod projection;
mod rotation;
mod window;
mod zonal;

#[cfg(test)]
mod tests;

pub use basis::{basis, dot, eval, eval_basis, eval_basis_f64, eval_f64};
pub use gpu::{EnvImage, EnvLayout, ShProjector, GPU_PROJECTION_MAX_BANDS};
pub use product::{product, product_matrix, product_terms, ProductMatrix, TripleProductTensor};
pub use projection::{
    cube_texel_dir_world, cube_texel_solid_angle, equirect_texel_dir_world, equirect_texel_solid_angle, gauss_legendre,
    project, project_cubemap, project_equirect, project_scalar, Quadrature,
};
pub use rotation::{rotate_z, rotation_z_to, zh_rotate, ShRotation};
pub use window::{apply_window, hanning, lanczos, zonal_minimum};
pub use zonal::{
    cap_zh, clamped_cosine_zh, convolve, eval_zonal, hemisphere_zh, irradiance, lambert_kernel, legendre, project_zonal,
};

use glam::{DVec3, Mat3, Vec3};
use std::ops::{Add, AddAssign, Sub};

/// Largest band count any function here accepts (l = 0..15, 256 coefficients).
pub const MAX_BANDS: usize = 16;
/// Band count of the GLSL helpers' loop-based evaluation (`SH_MAX_BANDS` in `sh.glsl`).
pub const GLSL_MAX_BANDS: usize = 8;
/// `y_0^0 = 1/(2√π)`.
pub const Y00: f64 = 0.282_094_791_773_878_14;
/// The coefficient of the constant function 1: `∫ y_0^0 dω = 2√π` (the Ca3D-Engine thesis §5.1 test 3).
pub const CONSTANT_ONE_C00: f64 = 3.544_907_701_811_032;

/// Everything the SH functions can reject.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShError {
    #[error("band count {0} is outside 1..={MAX_BANDS}")]
    Bands(usize),
    #[error("{0} coefficients is not a whole number of bands (1, 4, 9, 16, … up to {max})", max = MAX_BANDS * MAX_BANDS)]
    NotBands(usize),
    #[error("{what}: expected {expected} values, got {got}")]
    Length {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{0} must be finite")]
    NonFinite(&'static str),
    #[error("{what} must be in {range}, got {got}")]
    Range {
        what: &'static str,
        range: &'static str,
        got: f64,
    },
    #[error("not a rotation matrix: |RᵀR − I| = {orthogonality_error:.3e}, det = {det:.4}")]
    NotRotation { orthogonality_error: f64, det: f64 },
}

/// Result type of this module.
pub type ShResult<T> = Result<T, ShError>;

/// A coefficient type: scalar (`f32`, `f64`) or RGB (`Vec3`, `DVec3`). Every linear operation
/// (rotation, convolution, windowing, reconstruction, products with a scalar function) is
/// generic over it, so colour and visibility vectors share one code path.
pub trait Coeff: Copy + Default + Add<Output = Self> + Sub<Output = Self> + AddAssign {
    /// `self · s` (scale factors are computed in f64).
    fn scale(self, s: f64) -> Self;
}
impl Coeff for f32 {
    fn scale(self, s: f64) -> Self {
        (self as f64 * s) as f32
    }
}
impl Coeff for f64 {
    fn scale(self, s: f64) -> Self {
        self * s
    }
}
impl Coeff for Vec3 {
    fn scale(self, s: f64) -> Self {
        (self.as_dvec3() * s).as_vec3()
    }
}
impl Coeff for DVec3 {
    fn scale(self, s: f64) -> Self {
        self * s
    }
}

/// Number of coefficients of `bands` bands: `bands²`.
pub const fn coeff_count(bands: usize) -> usize {
    bands * bands
}

/// Flat index `l(l+1)+m`. `m` is clamped to `[−l, l]`; `l` saturates at 2³¹ (no overflow).
pub fn index(l: usize, m: i32) -> usize {
    let l = l.min(1 << 31) as i64;
    (l * (l + 1) + (m as i64).clamp(-l, l)) as usize
}

/// `(l, m)` of flat index `i` (inverse of [`index`]).
pub fn band_of(i: usize) -> (usize, i32) {
    let i = i as u128;
    let mut l = (i as f64).sqrt() as u128;
    // Correct a possible off-by-one of the float square root (u128: no overflow).
    while (l + 1) * (l + 1) <= i {
        l += 1;
    }
    while l * l > i {
        l -= 1;
    }
    (l as usize, (i as i128 - (l * (l + 1)) as i128) as i32)
}

/// Checks `1 ≤ bands ≤ MAX_BANDS`.
pub fn check_bands(bands: usize) -> ShResult<()> {
    if (1..=MAX_BANDS).contains(&bands) {
        Ok(())
    } else {
        Err(ShError::Bands(bands))
    }
}

/// The band count of a coefficient vector of length `len` (must be a square 1..=256).
pub fn bands_of_len(len: usize) -> ShResult<usize> {
    let b = (len as f64).sqrt().round() as usize;
    if !(1..=MAX_BANDS).contains(&b) || b * b != len {
        return Err(ShError::NotBands(len));
    }
    Ok(b)
}

/// World (y up, right-handed) → SH frame (z up): `(x, −z, y)`. A proper rotation.
pub fn world_to_sh(dir: Vec3) -> Vec3 {
    Vec3::new(dir.x, -dir.z, dir.y)
}

/// SH frame → world: `(x, z, −y)`; inverse of [`world_to_sh`].
pub fn sh_to_world(dir: Vec3) -> Vec3 {
    Vec3::new(dir.x, dir.z, -dir.y)
}

/// [`world_to_sh`] as a matrix (`WORLD_TO_SH * w`).
pub const WORLD_TO_SH: Mat3 = Mat3::from_cols(
    Vec3::new(1.0, 0.0, 0.0),  // world +x → SH +x
    Vec3::new(0.0, 0.0, 1.0),  // world +y → SH +z
    Vec3::new(0.0, -1.0, 0.0), // world +z → SH −y
);
/// [`sh_to_world`] as a matrix; the transpose of [`WORLD_TO_SH`].
pub const SH_TO_WORLD: Mat3 = Mat3::from_cols(
    Vec3::new(1.0, 0.0, 0.0),
    Vec3::new(0.0, 0.0, -1.0),
    Vec3::new(0.0, 1.0, 0.0),
);

/// Checks a coefficient slice is a whole number of bands and returns the band count.
fn bands_of<C>(what: &'static str, c: &[C]) -> ShResult<usize> {
    bands_of_len(c.len()).map_err(|_| ShError::Length {
        what,
        expected: {
            // The nearest valid length, to make the message useful.
            let b = ((c.len() as f64).sqrt().round() as usize).clamp(1, MAX_BANDS);
            b * b
        },
        got: c.len(),
    })
}

/// A unit direction in f64; zero, non-finite or denormal input becomes +z (documented clamp).
fn unit_dir(dir: DVec3) -> DVec3 {
    dir.try_normalize().unwrap_or(DVec3::Z)
}
