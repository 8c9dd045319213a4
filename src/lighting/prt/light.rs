//! The light side of PRT (digest §1.7, §3.2 item 8): the scene's distant light projected to SH
//! once — the environment (constant, equirect or cube, exact texel solid angles, full sphere,
//! no cosine) plus each directional light as a delta, `E · y_i(−direction)` — and, for a
//! rotating environment, turned by SH rotation every frame instead of re-projected.
//!
//! Shading: `L_o = ρ/π · Σ_i T_i L_i` (the document's Listing 2.8 multiplies by the diffuse
//! colour alone; with plain projections that is π too bright, so both modes state ρ/π).

use glam::{DVec3, Mat3, Vec3};

use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::scene::{Light, Scene};
use crate::sh;

/// The SH coefficients (RGB, `bands²`) of the scene's distant light.
pub fn project(scene: &Scene, env: &EnvironmentMap, bands: usize) -> Result<Vec<Vec3>> {
    let err = |e: sh::ShError| Error::Usage(format!("{}: prt light projection: {e}", scene.source));
    let mut out = if env.width == 1 && env.height == 1 && !env.cube {
        // A constant: exactly its radiance times ∫ y_00 = 2√π.
        let mut c = vec![Vec3::ZERO; bands * bands];
        let t = env.texels[0];
        c[0] = Vec3::new(t[0], t[1], t[2]) * sh::CONSTANT_ONE_C00 as f32;
        c
    } else {
        let rgb: Vec<[f32; 3]> = env.texels.iter().map(|t| [t[0], t[1], t[2]]).collect();
        if env.cube {
            sh::project_cubemap(&rgb, env.width as usize, bands).map_err(err)?
        } else {
            sh::project_equirect(&rgb, env.width as usize, env.height as usize, bands).map_err(err)?
        }
    };
    let mut y = vec![0.0f64; bands * bands];
    for l in &scene.lights {
        if let Light::Directional {
            direction, irradiance, ..
        } = l
        {
            let from = -direction.normalize().as_dvec3();
            sh::eval_basis_f64(world_to_sh(from), bands, &mut y).map_err(err)?;
            for (c, yi) in out.iter_mut().zip(&y) {
                *c += *irradiance * *yi as f32;
            }
        }
    }
    Ok(out)
}

fn world_to_sh(d: DVec3) -> DVec3 {
    DVec3::new(d.x, -d.z, d.y)
}

/// The light turned by `angle` radians about world up: SH rotation (Ivanic–Ruedenberg, the SH
/// core's), the same as re-projecting the rotated environment.
pub fn rotate(coeffs: &[Vec3], angle: f64) -> Result<Vec<Vec3>> {
    let bands = sh::bands_of_len(coeffs.len()).map_err(|e| Error::Usage(format!("prt light rotation: {e}")))?;
    let r = sh::ShRotation::from_world(Mat3::from_rotation_y(angle as f32), bands)
        .map_err(|e| Error::Usage(format!("prt light rotation: {e}")))?;
    r.rotate(coeffs)
        .map_err(|e| Error::Usage(format!("prt light rotation: {e}")))
}

/// The light uniform block of glsl/prt/shade.vert: 16 RGB coefficients (zero past `count`,
/// which drops the document's incomplete 8 or 12), then the SH keys (first key, second key,
/// receivers per key, coefficient count), the blend, and the transfer's storage (its format, as
/// `Storage::device_format`, and words per key).
pub fn uniform(coeffs: &[Vec3], count: usize, keys: (u32, u32, f32), per_key: u32, storage: (u32, u32)) -> Vec<f32> {
    let mut out = Vec::with_capacity(16 * 4 + 12);
    for i in 0..16 {
        let c = if i < count {
            coeffs.get(i).copied().unwrap_or(Vec3::ZERO)
        } else {
            Vec3::ZERO
        };
        out.extend([c.x, c.y, c.z, 0.0]);
    }
    out.extend([
        f32::from_bits(keys.0),
        f32::from_bits(keys.1),
        f32::from_bits(per_key),
        f32::from_bits(count as u32),
    ]);
    out.extend([keys.2, 0.0, 0.0, 0.0]);
    out.extend([f32::from_bits(storage.0), f32::from_bits(storage.1), 0.0, 0.0]);
    out
}
