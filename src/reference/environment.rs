//! Image environments for the path tracer: an equirectangular radiance map taken as piecewise
//! constant over its texels (nearest lookup), and the 2D distribution `glsl/reference/pathtrace.comp`
//! samples it with, proportional to luminance × sin θ so that directions are drawn in proportion
//! to the power arriving from them.
//!
//! Mapping (as [`Environment::equirect_uv`](crate::scene::Environment::equirect_uv)): texel
//! (i, j) of a W × H map covers u ∈ [i/W, (i+1)/W], v ∈ [j/H, (j+1)/H], with v = θ/π from straight
//! up; a solid angle is dω = 2π² sin θ du dv.

use std::path::Path;

use glam::{Vec2, Vec3};

use crate::backend::BackendError;
use crate::error::{Error, Result};
use crate::scene::Environment;

/// Texel data must fit a storage buffer of the range every Vulkan device supports (2^27 bytes).
const MAX_TEXELS: usize = (1 << 27) / 16;

#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    /// Radiance, rows top (straight up) to bottom; alpha unused.
    pub texels: Vec<[f32; 4]>,
    /// The sampling distribution: `height + 1` entries of the row CDF, then for each row its
    /// `width + 1` entries of the column CDF. Every CDF runs from 0 to 1.
    pub cdf: Vec<f32>,
    /// False when the map is black: nothing to sample.
    pub has_power: bool,
}

fn luminance(c: [f32; 4]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// Running sums of `weights` scaled to end at 1 (uniform when they sum to 0).
fn cdf_of(weights: &[f64]) -> Vec<f32> {
    let total: f64 = weights.iter().sum();
    let mut out = Vec::with_capacity(weights.len() + 1);
    let mut acc = 0.0;
    out.push(0.0);
    for (k, w) in weights.iter().enumerate() {
        acc += w;
        out.push(if total > 0.0 { (acc / total) as f32 } else { (k + 1) as f32 / weights.len() as f32 });
    }
    *out.last_mut().expect("one entry per weight plus the 0") = 1.0;
    out
}

impl EnvironmentMap {
    /// Loads an `.hdr`/`.exr` radiance map, multiplied by `scale`. `source` names the scene file
    /// in errors.
    pub fn load(path: &Path, scale: f32, source: &str) -> Result<EnvironmentMap> {
        let img = image::open(path)
            .map_err(|e| Error::Usage(format!("{source}: environment.path: {}: cannot load: {e}", path.display())))?
            .to_rgba32f();
        let (width, height) = img.dimensions();
        if (width as usize) * (height as usize) > MAX_TEXELS {
            return Err(Error::Backend(BackendError::Unsupported(format!(
                "{source}: environment.path: {}: {width}x{height} is more than the {MAX_TEXELS} texels the reference renderer can upload",
                path.display()
            ))));
        }
        let texels = img.pixels().map(|p| [p[0] * scale, p[1] * scale, p[2] * scale, 0.0]).collect();
        Ok(EnvironmentMap::from_texels(width, height, texels))
    }

    pub fn from_texels(width: u32, height: u32, texels: Vec<[f32; 4]>) -> EnvironmentMap {
        let (w, h) = (width as usize, height as usize);
        let mut rows = Vec::with_capacity(h);
        let mut columns = Vec::with_capacity(h * (w + 1));
        for j in 0..h {
            let sin_theta = (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin();
            let weights: Vec<f64> = texels[j * w..(j + 1) * w].iter().map(|&t| luminance(t).max(0.0) * sin_theta).collect();
            rows.push(weights.iter().sum::<f64>());
            columns.extend(cdf_of(&weights));
        }
        let has_power = rows.iter().sum::<f64>() > 0.0;
        let mut cdf = cdf_of(&rows);
        cdf.extend(columns);
        EnvironmentMap { width, height, texels, cdf, has_power }
    }

    fn texel_at(&self, uv: Vec2) -> (usize, usize) {
        let i = ((uv.x * self.width as f32) as usize).min(self.width as usize - 1);
        let j = ((uv.y * self.height as f32) as usize).min(self.height as usize - 1);
        (i, j)
    }

    /// Radiance arriving from direction `dir` (the same nearest lookup as the shader).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let (i, j) = self.texel_at(Environment::equirect_uv(dir));
        let t = self.texels[j * self.width as usize + i];
        Vec3::new(t[0], t[1], t[2])
    }

    /// Solid-angle density with which the shader samples `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let uv = Environment::equirect_uv(dir);
        let (i, j) = self.texel_at(uv);
        let (w, h) = (self.width as usize, self.height as usize);
        let row = self.cdf[j + 1] - self.cdf[j];
        let col = &self.cdf[h + 1 + j * (w + 1)..];
        let sin_theta = (uv.y * std::f32::consts::PI).sin();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        row * (col[i + 1] - col[i]) * (w * h) as f32 / (2.0 * std::f32::consts::PI * std::f32::consts::PI * sin_theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> EnvironmentMap {
        let (w, h) = (16, 8);
        let texels = (0..w * h).map(|k| {
            let v = if k == 2 * w + 5 { 50.0 } else { 0.2 + (k % w) as f32 * 0.05 };
            [v, 0.5 * v, 0.1, 0.0]
        });
        EnvironmentMap::from_texels(w as u32, h as u32, texels.collect())
    }

    #[test]
    fn cdfs_are_monotone_and_end_at_one() {
        let m = map();
        let (w, h) = (m.width as usize, m.height as usize);
        assert_eq!(m.cdf.len(), h + 1 + h * (w + 1));
        let mut runs = vec![&m.cdf[..h + 1]];
        runs.extend(m.cdf[h + 1..].chunks(w + 1));
        for run in runs {
            assert_eq!((run[0], run[run.len() - 1]), (0.0, 1.0));
            assert!(run.windows(2).all(|p| p[0] <= p[1]));
        }
    }

    #[test]
    fn pdf_integrates_to_one_over_the_sphere() {
        let m = map();
        let n = 400;
        let mut sum = 0.0f64;
        for a in 0..n {
            for b in 0..2 * n {
                let uv = Vec2::new((b as f32 + 0.5) / (2 * n) as f32, (a as f32 + 0.5) / n as f32);
                let d_omega = 2.0 * std::f64::consts::PI.powi(2) * (uv.y as f64 * std::f64::consts::PI).sin() / (2 * n * n) as f64;
                sum += m.pdf(Environment::equirect_dir(uv)) as f64 * d_omega;
            }
        }
        assert!((sum - 1.0).abs() < 1e-3, "{sum}");
        // The bright texel is sampled far more often than its neighbours.
        let bright = Environment::equirect_dir(Vec2::new(5.5 / 16.0, 2.5 / 8.0));
        let dim = Environment::equirect_dir(Vec2::new(6.5 / 16.0, 2.5 / 8.0));
        assert!(m.pdf(bright) > 50.0 * m.pdf(dim));
        assert_eq!(m.radiance(bright).x, 50.0);
    }
}
