//! Unit tests of the SH core. Test names cite the digest section whose value they reproduce
//! (the notes on the source documents); every test asserts a number that a wrong implementation
//! would get wrong.

mod basis;
mod glsl;
mod product;
mod projection;
mod rotation;
mod window;
mod zonal;

use glam::{DVec3, Mat3, Quat};

/// Deterministic test randomness (SplitMix64): no extra dependency, same numbers every run.
pub(super) struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [−1, 1).
    pub fn signed(&mut self) -> f64 {
        2.0 * self.f64() - 1.0
    }
    /// Uniform on the unit sphere.
    pub fn dir(&mut self) -> DVec3 {
        let z = self.signed();
        let phi = std::f64::consts::TAU * self.f64();
        let s = (1.0 - z * z).sqrt();
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
    /// Random coefficients in [−1, 1) for `bands` bands.
    pub fn coeffs(&mut self, bands: usize) -> Vec<f64> {
        (0..bands * bands).map(|_| self.signed()).collect()
    }
    /// A random rotation (uniform unit quaternion).
    pub fn rotation(&mut self) -> Mat3 {
        let q = Quat::from_xyzw(
            self.signed() as f32,
            self.signed() as f32,
            self.signed() as f32,
            self.signed() as f32,
        );
        Mat3::from_quat(q.normalize())
    }
}

/// Largest absolute difference of two equally long slices.
pub(super) fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "length mismatch");
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Asserts |actual − expected| ≤ tol with a readable message.
#[track_caller]
pub(super) fn close(actual: f64, expected: f64, tol: f64) {
    assert!(
        (actual - expected).abs() <= tol,
        "got {actual}, expected {expected} ± {tol} (diff {:e})",
        (actual - expected).abs()
    );
}

/// The exact projection rule for products up to total degree `degree`, f64.
pub(super) fn exact_rule(degree: usize) -> super::Quadrature {
    super::Quadrature::exact_for_degree(degree).expect("valid rule")
}

/// Projection of the f64 SH function `c` evaluated through `g(ω) = c(Rᵀω)`: the brute-force
/// reference for rotations.
pub(super) fn reproject_rotated(c: &[f64], r: glam::DMat3, bands: usize) -> Vec<f64> {
    let q = exact_rule(2 * bands);
    q.project_scalar(|d| super::eval_f64(c, r.transpose() * d).expect("valid"), bands)
        .expect("valid")
}
