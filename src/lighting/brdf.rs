//! The shared BRDF and punctual-light shading on the CPU, mirroring glsl/common/lights.glsl (the
//! forward method computes exactly this on the GPU): used by the
//! known-answer tests and as the analytic check of what the GPU computed.

use glam::Vec3;

use crate::gpu_scene::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_QUAD_FAR, LIGHT_SPOT};

/// Surface reflectance as the shaders see it.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub albedo: Vec3,
    pub specular: Vec3,
    pub exponent: f32,
    pub emission: Vec3,
}

/// `spot_falloff` of glsl/common/lights.glsl: smoothstep from the outer to the inner cone, a hard
/// edge when the two coincide.
pub fn spot_falloff(cos_outer: f32, cos_inner: f32, cos_angle: f32) -> f32 {
    if cos_inner - cos_outer <= 1e-7 {
        return if cos_angle >= cos_outer { 1.0 } else { 0.0 };
    }
    let t = ((cos_angle - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Direction to the light and irradiance at normal incidence at `p`.
pub fn light_incidence(light: &GpuLight, p: Vec3) -> (Vec3, Vec3) {
    let ty = light.position[3];
    let intensity = Vec3::from_slice(&light.intensity[..3]);
    if ty == LIGHT_DIRECTIONAL {
        return (-Vec3::from_slice(&light.direction[..3]), intensity);
    }
    let d = Vec3::from_slice(&light.position[..3]) - p;
    let dist2 = d.length_squared().max(1e-12);
    let to_light = d / dist2.sqrt();
    let mut e = intensity / dist2;
    if ty == LIGHT_SPOT {
        let cos_angle = (-to_light).dot(Vec3::from_slice(&light.direction[..3]));
        e *= spot_falloff(light.cone[1], light.cone[0], cos_angle);
    } else if ty == LIGHT_QUAD_FAR {
        e *= (-to_light).dot(Vec3::from_slice(&light.direction[..3])).max(0.0);
    }
    (to_light, e)
}

/// BRDF times cos θ: Lambert ρ/π plus energy-normalised Blinn-Phong ks (n+8)/(8π) (N·H)^n.
pub fn brdf_times_cos(n: Vec3, v: Vec3, l: Vec3, s: &Surface) -> Vec3 {
    let n_dot_l = n.dot(l);
    if n_dot_l <= 0.0 {
        return Vec3::ZERO;
    }
    let h = (l + v).normalize();
    let n_dot_h = n.dot(h).max(0.0);
    let f = s.albedo / std::f32::consts::PI
        + s.specular * ((s.exponent + 8.0) / (8.0 * std::f32::consts::PI)) * n_dot_h.powf(s.exponent);
    f * n_dot_l
}

/// Outgoing radiance at `p` with normal `n` towards the eye at `eye`.
pub fn shade(p: Vec3, n: Vec3, eye: Vec3, s: &Surface, lights: &[GpuLight], ambient: Vec3) -> Vec3 {
    let v = (eye - p).normalize();
    let n = if n.dot(v) < 0.0 { -n } else { n };
    let mut radiance = s.emission + s.albedo * ambient;
    for light in lights {
        let (l, e) = light_incidence(light, p);
        radiance += brdf_times_cos(n, v, l, s) * e;
    }
    radiance
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu_scene::LIGHT_POINT;

    #[test]
    fn lambert_under_directional_light() {
        let s = Surface {
            albedo: Vec3::splat(0.5),
            specular: Vec3::ZERO,
            exponent: 1.0,
            emission: Vec3::ZERO,
        };
        let light = GpuLight {
            position: [0.0, 0.0, 0.0, LIGHT_DIRECTIONAL],
            direction: [0.0, -1.0, 0.0, 0.0],
            intensity: [2.0, 2.0, 2.0, 0.0],
            cone: [0.0; 4],
        };
        let l = shade(Vec3::ZERO, Vec3::Y, Vec3::new(0.0, 5.0, 1.0), &s, &[light], Vec3::ZERO);
        assert!((l.x - 0.5 / std::f32::consts::PI * 2.0).abs() < 1e-6);
    }

    #[test]
    fn spot_cone_edges() {
        let (o, i) = (30f32.to_radians().cos(), 20f32.to_radians().cos());
        assert!((spot_falloff(o, i, 0.5 * (o + i)) - 0.5).abs() < 1e-6);
        assert_eq!(spot_falloff(o, i, 10f32.to_radians().cos()), 1.0);
        assert_eq!(spot_falloff(o, i, 35f32.to_radians().cos()), 0.0);
        // Equal cones: a hard edge, not smoothstep's undefined result.
        assert_eq!(spot_falloff(o, o, 29f32.to_radians().cos()), 1.0);
        assert_eq!(spot_falloff(o, o, 31f32.to_radians().cos()), 0.0);
    }

    #[test]
    fn point_light_inverse_square() {
        let s = Surface {
            albedo: Vec3::ONE,
            specular: Vec3::ZERO,
            exponent: 1.0,
            emission: Vec3::ZERO,
        };
        let light = GpuLight {
            position: [0.0, 2.0, 0.0, LIGHT_POINT],
            direction: [0.0; 4],
            intensity: [4.0; 4],
            cone: [0.0; 4],
        };
        let a = shade(Vec3::ZERO, Vec3::Y, Vec3::new(0.0, 1.0, 1.0), &s, &[light], Vec3::ZERO).x;
        assert!((a - 1.0 / std::f32::consts::PI).abs() < 1e-6);
        // At (2, 0, 0): distance² = 8, cos θ = 2/√8.
        let b = shade(
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::Y,
            Vec3::new(2.0, 1.0, 1.0),
            &s,
            &[light],
            Vec3::ZERO,
        )
        .x;
        let expected = 4.0 / 8.0 * (2.0 / 8f32.sqrt()) / std::f32::consts::PI;
        assert!((b - expected).abs() < 1e-6);
    }
}
