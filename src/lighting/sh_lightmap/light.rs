//! The run-time light (the Ca3D-Engine thesis §5.5): distant sources projected to SH radiance coefficients, RGB,
//! every frame — the scene's environment (projected once), its directional lights (deltas, turning
//! about the vertical at the method's `sun_speed`), or the CIE clear sky around the sun.

use glam::{DVec3, Vec3};

use super::config::{Config, Sky};
use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::scene::{Light, Scene};
use crate::sh;

/// Light coefficient groups per channel in the shaders' uniform block (8 bands: 64 / 4).
pub const GROUPS: usize = 16;

/// The light the method shades with, before the per-frame parts.
pub struct Lights {
    bands: usize,
    /// The environment's radiance coefficients (RGB), projected once.
    environment: Vec<DVec3>,
    /// (direction toward the light, irradiance RGB) at time 0.
    suns: Vec<(DVec3, DVec3)>,
    sun_speed: f64,
    sky: Sky,
    cie_zenith: f64,
}

impl Lights {
    pub fn new(scene: &Scene, env: &EnvironmentMap, config: &Config) -> Result<Lights> {
        let bands = config.transfer.bands;
        let sh_err = |e: sh::ShError| Error::Usage(format!("{}: SH light-map light projection: {e}", scene.source));
        let _ = sh_err;
        // A constant is c₀₀ = 2√π·L exactly, here; an image is projected on the device every
        // frame by the SH core's pass ([`super::EnvProjection`]) and added in the shader.
        let mut environment = vec![DVec3::ZERO; bands * bands];
        if config.sky == Sky::Scene && is_constant(env) {
            environment[0] = Vec3::from_slice(&env.texels[0][..3]).as_dvec3() * sh::CONSTANT_ONE_C00;
        }
        let suns = scene
            .lights
            .iter()
            .filter_map(|l| match l {
                Light::Directional {
                    direction, irradiance, ..
                } => Some((-direction.as_dvec3().normalize(), irradiance.as_dvec3())),
                _ => None,
            })
            .collect();
        Ok(Lights {
            bands,
            environment,
            suns,
            sun_speed: config.sun_speed,
            sky: config.sky,
            cie_zenith: config.cie_zenith,
        })
    }

    /// The directions toward the suns at `time_s` (turned about world up).
    pub fn suns_at(&self, time_s: f64) -> Vec<(DVec3, DVec3)> {
        let a = (self.sun_speed * time_s).to_radians();
        let (s, c) = a.sin_cos();
        self.suns
            .iter()
            .map(|&(d, e)| (DVec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z), e))
            .collect()
    }

    /// The RGB radiance coefficients at `time_s`.
    pub fn coefficients(&self, time_s: f64) -> Vec<DVec3> {
        let mut c = self.environment.clone();
        let dim = self.bands * self.bands;
        let mut y = vec![0.0; dim];
        let suns = self.suns_at(time_s);
        for &(to_light, e) in &suns {
            // A delta of irradiance E at normal incidence: coefficients E·y(ω).
            if sh::eval_basis_f64(world_to_sh(to_light), self.bands, &mut y).is_ok() {
                for (ci, yi) in c.iter_mut().zip(&y) {
                    *ci += e * *yi;
                }
            }
        }
        if self.sky == Sky::Cie {
            let sun = suns.first().map_or(DVec3::Y, |s| s.0);
            for (ci, v) in c.iter_mut().zip(cie_clear_sky(sun, self.bands, self.cie_zenith)) {
                *ci += DVec3::splat(v);
            }
        }
        c
    }

    /// The uniform block of the shaders: per channel, `GROUPS` vec4 of coefficients (faithful
    /// mode: the luminance in channel 0, the Ca3D-Engine thesis's monochrome light).
    pub fn uniform(&self, time_s: f64, monochrome: bool) -> Vec<f32> {
        let c = self.coefficients(time_s);
        let mut out = vec![0.0f32; 3 * 4 * GROUPS];
        for (i, v) in c.iter().enumerate() {
            if monochrome {
                out[i] = (0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z) as f32;
            } else {
                for ch in 0..3 {
                    out[ch * 4 * GROUPS + i] = v[ch] as f32;
                }
            }
        }
        out
    }
}

/// The scene's environment is one constant (a 1×1 equirect map), not an image.
pub fn is_constant(env: &EnvironmentMap) -> bool {
    env.width == 1 && env.height == 1 && !env.cube
}

fn world_to_sh(d: DVec3) -> DVec3 {
    DVec3::new(d.x, -d.z, d.y)
}

/// The CIE clear sky (CIE S 011, standard clear sky type 12) around the sun toward `sun`, with
/// zenith radiance `zenith`, projected to `bands` bands by a product quadrature over the upper
/// hemisphere (the ground below the horizon is black).
pub fn cie_clear_sky(sun: DVec3, bands: usize, zenith: f64) -> Vec<f64> {
    let sun = sun.normalize();
    let dim = bands * bands;
    let mut out = vec![0.0; dim];
    let mut y = vec![0.0; dim];
    let (nt, np) = (48usize, 96usize);
    for i in 0..nt {
        // Uniform in cos θ over the upper hemisphere.
        let cos_t = (i as f64 + 0.5) / nt as f64;
        let sin_t = (1.0 - cos_t * cos_t).sqrt();
        for j in 0..np {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
            let d = DVec3::new(sin_t * phi.cos(), cos_t, sin_t * phi.sin());
            let l = cie_clear_sky_radiance(d, sun, zenith);
            if sh::eval_basis_f64(world_to_sh(d), bands, &mut y).is_ok() {
                let w = 2.0 * std::f64::consts::PI / (nt * np) as f64;
                for (o, yi) in out.iter_mut().zip(&y) {
                    *o += l * yi * w;
                }
            }
        }
    }
    out
}

/// The CIE clear sky's radiance toward the sky direction `d` (unit, world; 0 below the horizon):
/// `L = L_z·f(γ)·φ(θ) / (f(θ_s)·φ(0))`, `f(γ) = 0.91 + 10·e^(−3γ) + 0.45·cos²γ` (the
/// indicatrix), `φ(θ) = 1 − e^(−0.32/cos θ)` (the gradation), γ the angle to the sun.
pub fn cie_clear_sky_radiance(d: DVec3, sun: DVec3, zenith: f64) -> f64 {
    if d.y <= 0.0 {
        return 0.0;
    }
    let gradation = |cos_t: f64| 1.0 - (-0.32 / cos_t.max(1e-3)).exp();
    let indicatrix = |gamma: f64| 0.91 + 10.0 * (-3.0 * gamma).exp() + 0.45 * gamma.cos().powi(2);
    let theta_s = sun.y.clamp(-1.0, 1.0).acos();
    let gamma = d.dot(sun).clamp(-1.0, 1.0).acos();
    zenith * indicatrix(gamma) * gradation(d.y) / (indicatrix(theta_s) * gradation(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cie_sky_is_the_zenith_radiance_at_the_zenith_and_brightest_near_the_sun() {
        let sun = DVec3::new(0.6, 0.5, 0.2).normalize();
        assert!((cie_clear_sky_radiance(DVec3::Y, sun, 3.0) - 3.0).abs() < 1e-12);
        // The circumsolar region outshines the zenith; the anti-solar sky above the horizon is
        // darker than the zenith (0.68 here, from the formula by hand).
        let near_sun = (sun + DVec3::new(0.0, 0.02, 0.0)).normalize();
        assert!(cie_clear_sky_radiance(near_sun, sun, 1.0) > 2.0);
        let away = DVec3::new(-0.6, 1.2, -0.2).normalize();
        assert!((cie_clear_sky_radiance(away, sun, 1.0) - 0.6841).abs() < 1e-3);
        assert_eq!(
            cie_clear_sky_radiance(DVec3::new(0.0, -0.1, 1.0).normalize(), sun, 1.0),
            0.0
        );
        // The projection's power (c₀₀·2√π = ∫L dω) against an independent quadrature of the
        // same function (a finer θ-φ midpoint grid in sin θ dθ dφ).
        let c = cie_clear_sky(sun, 4, 1.0);
        let (nt, np) = (400usize, 800usize);
        let mut power = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..np {
                let p = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                let d = DVec3::new(t.sin() * p.cos(), t.cos(), t.sin() * p.sin());
                power += cie_clear_sky_radiance(d, sun, 1.0)
                    * t.sin()
                    * (std::f64::consts::FRAC_PI_2 / nt as f64)
                    * (2.0 * std::f64::consts::PI / np as f64);
            }
        }
        let projected = c[0] * sh::CONSTANT_ONE_C00;
        assert!(
            (projected / power - 1.0).abs() < 0.01,
            "projected {projected}, quadrature {power}"
        );
    }
}
