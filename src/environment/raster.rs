//! The scene's environment for the raster methods: its irradiance as 3-band SH (exact for a
//! constant sky, Ramamoorthi–Hanrahan's approximation for a map; no visibility), and the map
//! itself for the sky seen behind the geometry (nearest texel, as the reference looks it up). A
//! cube map is uploaded as the reference holds it, its faces stacked into one 2D image
//! (`glsl/common/cube.glsl`), so the sky pass keeps one binding for both layouts.

use glam::Vec3;

use super::EnvironmentMap;
use crate::backend::{vk, Gpu, ImageDesc, ImageId};
use crate::error::{Error, Result};
use crate::graph::{Access, ResourceStates};
use crate::scene::{Environment, Scene};

pub struct EnvironmentLighting {
    /// Irradiance E(n) = Σ c_i·Y_i(n) in the SH frame (`sh::world_to_sh`), RGB in xyz.
    pub irradiance_sh: [[f32; 4]; 9],
    /// RGBA32F equirectangular radiance (1×1 for a constant sky, black without environment), or
    /// a cube map's faces stacked top to bottom in layer order.
    pub map: ImageId,
    /// `map` is a stacked cube map.
    pub cube: bool,
}

/// Irradiance SH of a uniform sky of radiance `l`.
pub fn constant_irradiance_sh(l: Vec3) -> Result<[[f32; 4]; 9]> {
    let mut radiance = vec![Vec3::ZERO; 9];
    radiance[0] = l * (4.0 * std::f32::consts::PI).sqrt();
    let e: Vec<Vec3> = crate::sh::irradiance(&radiance).map_err(|e| Error::Usage(format!("environment SH: {e}")))?;
    let mut out = [[0.0; 4]; 9];
    for (o, c) in out.iter_mut().zip(e) {
        *o = c.extend(0.0).into();
    }
    Ok(out)
}

/// Irradiance SH of an equirect or cube radiance map (exact texel solid angles, 3 bands).
pub fn irradiance_sh(map: &EnvironmentMap) -> Result<[[f32; 4]; 9]> {
    let pixels: Vec<[f32; 3]> = map.texels.iter().map(|t| [t[0], t[1], t[2]]).collect();
    let sh_err = |e: crate::sh::ShError| Error::Usage(format!("environment SH projection: {e}"));
    let radiance = if map.cube {
        crate::sh::project_cubemap(&pixels, map.width as usize, 3).map_err(sh_err)?
    } else {
        crate::sh::project_equirect(&pixels, map.width as usize, map.height as usize, 3).map_err(sh_err)?
    };
    let e: Vec<Vec3> = crate::sh::irradiance(&radiance).map_err(sh_err)?;
    let mut out = [[0.0; 4]; 9];
    for (o, c) in out.iter_mut().zip(e) {
        *o = c.extend(0.0).into();
    }
    Ok(out)
}

impl EnvironmentLighting {
    /// Uploads `map`, the scene's environment as [`EnvironmentMap::of_scene`] loaded it.
    pub fn upload(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        scene: &Scene,
        map: &EnvironmentMap,
    ) -> Result<EnvironmentLighting> {
        let irradiance_sh = match &scene.environment {
            // Exact: a constant is band 0 alone (∫Y00 = √(4π)), and one texel is no quadrature.
            Some(Environment::Constant { radiance }) => constant_irradiance_sh(*radiance)?,
            Some(Environment::Image { .. } | Environment::Cube { .. }) => irradiance_sh(map)?,
            None => [[0.0; 4]; 9],
        };
        let image = gpu.create_image(
            &ImageDesc::new_2d("environment", vk::Format::R32G32B32A32_SFLOAT, map.width, map.height)
                .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
        )?;
        gpu.upload_image(image, 0, bytemuck::cast_slice(&map.texels))?;
        states.set_image(
            gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )?;
        Ok(EnvironmentLighting {
            irradiance_sh,
            map: image,
            cube: map.cube,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_sky_irradiance_is_pi_l_in_every_direction() {
        let sh = constant_irradiance_sh(Vec3::new(2.0, 1.0, 0.5)).unwrap();
        for dir in [Vec3::Y, Vec3::X, Vec3::new(0.3, -0.8, 0.2).normalize()] {
            let mut y = [0.0f32; 9];
            crate::sh::eval_basis(crate::sh::world_to_sh(dir), 3, &mut y).unwrap();
            let e: f32 = (0..9).map(|i| sh[i][0] * y[i]).sum();
            assert!((e - 2.0 * std::f32::consts::PI).abs() < 1e-4, "{dir}: {e}");
        }
    }

    #[test]
    fn sky_above_black_ground_gives_the_clamped_cosine_irradiance() {
        // Upper hemisphere radiance 1, lower 0: E(up) = π, E(down) ≈ 0, E(horizon) = π/2 — the
        // 3-band approximation is within a few per cent of these.
        let (w, h) = (64u32, 32u32);
        let texels = (0..w * h)
            .map(|i| if i / w < h / 2 { [1.0, 1.0, 1.0, 0.0] } else { [0.0; 4] })
            .collect();
        let sh = irradiance_sh(&EnvironmentMap::from_texels(w, h, texels)).unwrap();
        let e = |dir: Vec3| {
            let mut y = [0.0f32; 9];
            crate::sh::eval_basis(crate::sh::world_to_sh(dir), 3, &mut y).unwrap();
            (0..9).map(|i| sh[i][0] * y[i]).sum::<f32>()
        };
        let pi = std::f32::consts::PI;
        assert!((e(Vec3::Y) - pi).abs() < 0.05 * pi, "{}", e(Vec3::Y));
        assert!(e(Vec3::NEG_Y).abs() < 0.05 * pi, "{}", e(Vec3::NEG_Y));
        assert!((e(Vec3::X) - pi / 2.0).abs() < 0.02 * pi, "{}", e(Vec3::X));
    }
}
