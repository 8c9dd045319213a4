//! The light models of Ridderhof 2002's systems, evaluated per vertex at a light's full intensity.
//!
//! - [`LightModel::Physical`] (corrected): the scene's radiometric point and spot lights, as
//!   every other penumbra method and the path tracer evaluate them — inverse-square falloff,
//!   the smooth cone of `glsl/common/lights.glsl`, Lambert `ρ/π` — so the result is radiance and
//!   can be compared with the reference.
//! - [`LightModel::Seed`] (faithful, §1.5): the thesis's `k·ρ·max(0, N·L)/d` with a ramp linear
//!   in angle between the full and null cones (the scene's inner and outer angles), times the
//!   light's colour (its intensity). `N·L` is clamped at 0, which the thesis leaves unsaid.
//! - [`LightModel::OpenGl`] (faithful VLS, §1.4): fixed-function diffuse `ρ·max(0, N·L)·I`
//!   with attenuation `1/(kc + kl·d + kq·d²)` and `max(0, cos)^e` inside the null cone. The
//!   thesis does not give its exponent mapping; `e` makes the fall-off ½ at the full cone's edge.
//!   VLS adds the model's global and per-light ambient and its Blinn-Phong specular term in its
//!   shader (`opengl_ambient_specular`), held to their closed form by tests/vls.rs.
//!
//! `glsl/common/many_lights.glsl` is the shader twin; the tests hold them to each other and to
//! closed forms.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::scene::{Light, Scene};

/// A point or spot light as both systems see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManyLight {
    pub position: DVec3,
    /// Unit direction the light travels along its axis (spots).
    pub direction: DVec3,
    /// RGB intensity at full power, W/sr.
    pub intensity: DVec3,
    /// Full (inner) and null (outer) half-angles, radians; `None` for a point light.
    pub cone: Option<(f64, f64)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightModel {
    Physical,
    Seed { k: f64 },
    OpenGl { kc: f64, kl: f64, kq: f64 },
}

impl LightModel {
    /// Shader code of the model (`glsl/common/many_lights.glsl`).
    pub fn code(&self) -> u32 {
        match self {
            LightModel::Physical => 0,
            LightModel::Seed { .. } => 1,
            LightModel::OpenGl { .. } => 2,
        }
    }

    /// The model's constants as the shader reads them: (k, kc, kl, kq).
    pub fn constants(&self) -> [f32; 4] {
        match *self {
            LightModel::Physical => [0.0; 4],
            LightModel::Seed { k } => [k as f32, 0.0, 0.0, 0.0],
            LightModel::OpenGl { kc, kl, kq } => [0.0, kc as f32, kl as f32, kq as f32],
        }
    }
}

/// The thesis's spot ramp (§1.5): 1 inside the full cone, 0 outside the null cone, linear in
/// the angle between (a hard edge when the cones coincide).
pub fn seed_spot_ramp(full: f64, null: f64, angle: f64) -> f64 {
    if angle >= null {
        0.0
    } else if angle <= full || null - full <= 1e-12 {
        1.0
    } else {
        (null - angle) / (null - full)
    }
}

/// `smoothstep(cos_outer, cos_inner, cos)` as `spot_falloff` in glsl/common/lights.glsl.
pub fn physical_spot_falloff(cos_outer: f64, cos_inner: f64, cos_angle: f64) -> f64 {
    if cos_inner - cos_outer <= 1e-7 {
        return if cos_angle >= cos_outer { 1.0 } else { 0.0 };
    }
    let t = ((cos_angle - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The fixed-function exponent standing in for the two-angle spot: `cos(full)^e = ½`.
pub fn opengl_spot_exponent(full: f64) -> f64 {
    let c = full.cos();
    if full <= 1e-6 || c >= 1.0 {
        return 128.0;
    }
    (0.5f64.ln() / c.ln()).clamp(0.0, 128.0)
}

impl ManyLight {
    /// The scene's point and spot lights in file order. Other kinds are refused: the thesis's
    /// systems model point sources only.
    pub fn from_scene(scene: &Scene, method: &str) -> Result<Vec<ManyLight>> {
        let mut out = Vec::with_capacity(scene.lights.len());
        for (i, l) in scene.lights.iter().enumerate() {
            match l {
                Light::Point {
                    position, intensity, ..
                } => out.push(ManyLight {
                    position: position.as_dvec3(),
                    direction: DVec3::NEG_Z,
                    intensity: intensity.as_dvec3(),
                    cone: None,
                }),
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    inner_deg,
                    outer_deg,
                    ..
                } => out.push(ManyLight {
                    position: position.as_dvec3(),
                    direction: direction.as_dvec3().normalize_or(DVec3::NEG_Z),
                    intensity: intensity.as_dvec3(),
                    cone: Some(((*inner_deg as f64).to_radians(), (*outer_deg as f64).to_radians())),
                }),
                _ => {
                    return Err(Error::Usage(format!(
                        "{}: lights[{i}] ({:?}): {method} lights with point and spot lights only, as Ridderhof's Modelling Multiple Light Sources does",
                        scene.source,
                        l.name()
                    )))
                }
            }
        }
        Ok(out)
    }

    /// Angle between the light's axis and the direction to `p`, radians.
    fn angle_to(&self, p: DVec3) -> f64 {
        let d = (p - self.position).normalize_or_zero();
        d.dot(self.direction).clamp(-1.0, 1.0).acos()
    }

    /// The angular factor and the distance and unit direction to the light, or `None` where the
    /// light sends nothing (outside its cone, or at the point itself).
    pub fn reach(&self, model: &LightModel, p: DVec3) -> Option<(f64, f64, DVec3)> {
        let to_light = self.position - p;
        let dist = to_light.length();
        if dist <= 1e-12 {
            return None;
        }
        let factor = match (self.cone, model) {
            (None, _) => 1.0,
            (Some((full, null)), LightModel::Seed { .. }) => seed_spot_ramp(full, null, self.angle_to(p)),
            (Some((full, null)), LightModel::Physical) => {
                physical_spot_falloff(null.cos(), full.cos(), (-to_light / dist).dot(self.direction))
            }
            (Some((full, null)), LightModel::OpenGl { .. }) => {
                let cos = (-to_light / dist).dot(self.direction);
                if cos < null.cos() {
                    0.0
                } else {
                    cos.max(0.0).powf(opengl_spot_exponent(full))
                }
            }
        };
        (factor > 0.0).then_some((factor, dist, to_light / dist))
    }

    /// What this light at full intensity makes a diffuse point reflect: outgoing radiance
    /// (physical) or the thesis's colour (faithful models), unshadowed.
    pub fn shade(&self, model: &LightModel, p: DVec3, n: DVec3, albedo: DVec3) -> DVec3 {
        let Some((factor, dist, l)) = self.reach(model, p) else {
            return DVec3::ZERO;
        };
        let cos = n.dot(l).max(0.0);
        let scale = match *model {
            LightModel::Physical => factor * cos / (dist * dist) / std::f64::consts::PI,
            LightModel::Seed { k } => factor * cos * k / dist,
            LightModel::OpenGl { kc, kl, kq } => factor * cos / (kc + kl * dist + kq * dist * dist).max(1e-12),
        };
        albedo * self.intensity * scale
    }
}
