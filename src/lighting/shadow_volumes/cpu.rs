//! The method's shading on the CPU, mirroring `glsl/shadow_volumes/light.frag` and
//! `ambient.frag`: the seed's attenuation functions, its lighting equation (Eq. 5, *faithful*)
//! and the radiometric variant (*physical*), and spot lights as point lights times the forward
//! method's falloff. Used by the known-answer tests.

use glam::Vec3;

use super::plan::Spot;
use crate::lighting::brdf::{brdf_times_cos, spot_falloff, Surface};

/// The factor a light's cone puts on its contribution at `p`: 1 for a point light (`None`),
/// else the forward method's `spot_falloff` of the angle from the axis — the same in both
/// modes (the seed has no spot lights, so with Eq. 5 this is an extension).
pub fn spot_factor(spot: Option<&Spot>, light_pos: Vec3, p: Vec3) -> f32 {
    match spot {
        None => 1.0,
        Some(s) => {
            let d = p - light_pos;
            spot_falloff(s.cos_outer, s.cos_inner, d.dot(s.direction) / d.length().max(1e-12))
        }
    }
}

/// The seed's specular exponent (Listing 1: `pow(spec, 32)`).
pub const FAITHFUL_EXPONENT: i32 = 32;

/// The seed's attenuation functions (§4.1.5) of the distance `d` to a light of radius `r`
/// (metres; `r = 0` is an infinite radius, where 2–4 are 1):
/// 1. `saturate(2/d − 0.01)`: the seed's Cg form `saturate(2000/d − 0.01)` with d in
///    millimetres (Cafu's unit), here in metres; never reaches 0, so no culling;
/// 2. `max(1 − d/r, 0)`;
/// 3. `max(1 − d/r, 0)²` (the digest's `max((1 − d/r)², 0)` would be 1 again at d = 2r);
/// 4. `max(1 − (d/r)², 0)`, the seed's final choice and the default.
pub fn attenuation(kind: u32, d: f32, r: f32) -> f32 {
    if kind == 1 {
        return (2.0 / d.max(1e-6) - 0.01).clamp(0.0, 1.0);
    }
    if r <= 0.0 {
        return 1.0;
    }
    let x = d / r;
    match kind {
        2 => (1.0 - x).max(0.0),
        3 => {
            let a = (1.0 - x).max(0.0);
            a * a
        }
        _ => (1.0 - x * x).max(0.0),
    }
}

/// The faithful light colour `L_C` of a directional light of irradiance `E` (W/m²): the seed
/// has no sun in its lighting equation, so, as for a point light below, `L_C` makes the
/// faithful diffuse term `ρ·L_C·cos` equal the radiometric `ρ/π·E·cos`: `E/π`, with no
/// attenuation (the light is at infinity).
pub fn faithful_sun_colour(irradiance: Vec3) -> Vec3 {
    irradiance / std::f32::consts::PI
}

/// The faithful light colour `L_C` of a point light of intensity `I` (W/sr) and radius `r`: the
/// seed's colours are unitless, so `L_C` is chosen to make the faithful diffuse term
/// `ρ·L_C·atten(d)·cos` equal the radiometric `ρ/π·I/d²·cos` at half the radius,
/// `L_C = I / (π·(r/2)²·atten(r/2))` (at 1 m when the radius is infinite).
pub fn faithful_light_colour(intensity: Vec3, radius: f32, kind: u32) -> Vec3 {
    let d0 = if radius > 0.0 { 0.5 * radius } else { 1.0 };
    let a = attenuation(kind, d0, radius);
    intensity / (std::f32::consts::PI * d0 * d0 * if a > 0.0 { a } else { 1.0 })
}

/// One light's term of Eq. 5 (Listing 1): `atten · L_C · (diffuse·N·L + specular·(N·H)^32)`,
/// the specular gated on `N·L > 0`, all clamped dot products. `n`, `l_ts` and `e_ts` are in
/// tangent space (`n` the normal-map normal, unit; the light and eye vectors need not be unit);
/// `dist` is the world-space distance used for the attenuation only — the seed's separate
/// light vectors.
#[allow(clippy::too_many_arguments)]
pub fn faithful_light(
    n: Vec3,
    l_ts: Vec3,
    e_ts: Vec3,
    dist: f32,
    diffuse: Vec3,
    specular: Vec3,
    colour: Vec3,
    kind: u32,
    radius: f32,
) -> Vec3 {
    let l = l_ts.normalize();
    let e = e_ts.normalize();
    let diff = n.dot(l).clamp(0.0, 1.0);
    let spec = if diff > 0.0 {
        n.dot((l + e).normalize()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    attenuation(kind, dist, radius) * colour * (diff * diffuse + spec.powi(FAITHFUL_EXPONENT) * specular)
}

/// Eq. 5's light-independent part: `diffuse·lightmap·N_z + luminance` (N_z of the tangent-space
/// normal when `use_nz`, else 1).
pub fn faithful_ambient(diffuse: Vec3, lightmap: Vec3, n_z: f32, use_nz: bool, luminance: Vec3) -> Vec3 {
    diffuse * lightmap * if use_nz { n_z } else { 1.0 } + luminance
}

/// One point light in the physical mode: the renderer's BRDF (Lambert + normalised
/// Blinn-Phong) times `I/d²·cos`, zero beyond the light's radius (when it has one).
pub fn physical_light(p: Vec3, n: Vec3, eye: Vec3, s: &Surface, light_pos: Vec3, intensity: Vec3, radius: f32) -> Vec3 {
    let d = light_pos - p;
    let dist2 = d.length_squared().max(1e-12);
    if radius > 0.0 && dist2 > radius * radius {
        return Vec3::ZERO;
    }
    brdf_times_cos(n, (eye - p).normalize(), d / dist2.sqrt(), s) * intensity / dist2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attenuation_values_of_the_digest() {
        let r = 8.0;
        let at = |k, d| attenuation(k, d, r);
        for (k, want) in [
            (2, [1.0, 0.5, 0.0, 0.0]),
            (3, [1.0, 0.25, 0.0, 0.0]),
            (4, [1.0, 0.75, 0.0, 0.0]),
        ] {
            let got = [at(k, 0.0), at(k, r / 2.0), at(k, r), at(k, 2.0 * r)];
            assert_eq!(got, want, "atten{k} at 0, r/2, r, 2r");
        }
        // Derivatives just inside the radius: −1/r (atten2, G0 only), 0 (atten3, G1), −2/r (atten4).
        let h = 1e-3;
        for (k, want) in [(2, -1.0 / r), (3, 0.0), (4, -2.0 / r)] {
            let slope = (at(k, r - h) - at(k, r - 2.0 * h)) / h;
            assert!((slope - want).abs() < 2e-3, "atten{k}' at r⁻: {slope} vs {want}");
        }
        // atten1 (Cg form, metres for the seed's millimetres): 1 at 1 m (clamped from 1.99),
        // 0.49 at 4 m, never 0.
        assert_eq!(attenuation(1, 1.0, r), 1.0);
        assert!((attenuation(1, 4.0, r) - 0.49).abs() < 1e-6);
        assert!(attenuation(1, 150.0, r) > 0.0);
        // Infinite radius: no falloff for 2–4.
        assert_eq!(attenuation(4, 1e3, 0.0), 1.0);
    }

    #[test]
    fn faithful_matches_physical_diffuse_at_half_radius() {
        let (i, r) = (Vec3::new(10.0, 5.0, 2.0), 6.0);
        for k in 1..=4 {
            let c = faithful_light_colour(i, r, k);
            let d = r / 2.0;
            let faithful = faithful_light(Vec3::Z, Vec3::Z * d, Vec3::Z, d, Vec3::ONE, Vec3::ZERO, c, k, r);
            let physical = i / (d * d) / std::f32::consts::PI;
            assert!(
                (faithful - physical).abs().max_element() < 1e-5,
                "atten{k}: {faithful} vs {physical}"
            );
        }
    }

    #[test]
    fn specular_is_gated_on_the_diffuse_term() {
        // Light below the surface, eye above: N·L < 0, so no specular even though N·H could be > 0.
        let out = faithful_light(
            Vec3::Z,
            Vec3::new(1.0, 0.0, -0.01),
            Vec3::new(-1.0, 0.0, 0.2),
            1.0,
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::ONE,
            4,
            0.0,
        );
        assert_eq!(out, Vec3::ZERO);
        let lit = faithful_light(
            Vec3::Z,
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, 1.0),
            1.0,
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::ONE,
            4,
            0.0,
        );
        assert!((lit - Vec3::ONE).abs().max_element() < 1e-6, "N = L = E: (N·H)^32 = 1");
    }
}
