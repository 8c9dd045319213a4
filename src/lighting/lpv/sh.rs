//! Two-band SH (4 coefficients) as the LPV stores light: order (Y00, x, y, z), the real
//! Cartesian band 1 with a positive sign (digest §2.2), and the clamped-cosine lobe that
//! reflected light, propagated faces and irradiance look-ups are projected with.

use glam::DVec3;

/// Y00 = 1/(2√π), the SH core's.
pub const Y00: f64 = crate::sh::Y00;
/// The band-1 factor √(3/(4π)).
pub const Y1: f64 = 0.488_602_511_902_919_9;
/// The clamped cosine's projection: √π/2 and √(π/3).
pub const COS0: f64 = 0.886_226_925_452_758;
pub const COS1: f64 = 1.023_326_707_946_488_5;

/// The basis at a unit direction.
pub fn basis(d: DVec3) -> [f64; 4] {
    [Y00, Y1 * d.x, Y1 * d.y, Y1 * d.z]
}

/// The projection of max(0, n·ω): the lobe of a Lambertian emitter facing `n`.
pub fn cosine_lobe(n: DVec3) -> [f64; 4] {
    [COS0, COS1 * n.x, COS1 * n.y, COS1 * n.z]
}

pub fn dot(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}

/// The reconstruction at a unit direction.
pub fn eval(c: &[f64; 4], d: DVec3) -> f64 {
    dot(c, &basis(d))
}

/// The flux of an intensity distribution stored as `c` (W/sr → W): ∫ c·Y dω = 2√π c₀.
pub fn flux(c: &[f64; 4]) -> f64 {
    2.0 * std::f64::consts::PI.sqrt() * c[0]
}

/// The power received through a surface of normal `n` from intensity `c` arriving along
/// directions with −n·ω > 0: c · coslobe(−n). Divided by the cell's area it is irradiance.
pub fn incident(c: &[f64; 4], n: DVec3) -> f64 {
    dot(c, &cosine_lobe(-n))
}

/// The coefficients of a VPL: flux `phi` leaving a Lambertian surfel facing `n`, I(ω) = Φ/π·max(0, n·ω).
pub fn vpl(phi: f64, n: DVec3) -> [f64; 4] {
    cosine_lobe(n).map(|c| c * phi / std::f64::consts::PI)
}
