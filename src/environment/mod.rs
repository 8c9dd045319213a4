//! The scene's environment, loaded once and checked, for every consumer: the raster methods'
//! sky and irradiance (`raster`), the height-field methods' SH projection ([`EnvironmentMap::reduced`])
//! and the path tracer. Every texel is checked on the way in: a NaN, an infinity or a negative
//! radiance is one error line naming the file and the pixel, never a silently wrong image.
//!
//! For the path tracer, an equirectangular radiance map taken as piecewise
//! constant over its texels (nearest lookup), and the 2D distribution `glsl/reference/pathtrace.comp`
//! samples it with, proportional to luminance × sin θ so that directions are drawn in proportion
//! to the power arriving from them.
//!
//! Mapping (as [`Environment::equirect_uv`](crate::scene::Environment::equirect_uv)): texel
//! (i, j) of a W × H map covers u ∈ [i/W, (i+1)/W], v ∈ [j/H, (j+1)/H], with v = θ/π from straight
//! up; a solid angle is dω = 2π² sin θ du dv.
//!
//! A cube map is held the same way, its six `size`² faces stacked top to bottom in layer order
//! (+X, −X, +Y, −Y, +Z, −Z) as one `size` × 6·`size` map, so that one row/column CDF pair serves
//! both; its texels are weighted by their exact solid angle, and a texel is sampled uniformly in
//! face coordinates (s, t), where dω = ds dt / (1 + s² + t²)^{3/2}.

use std::path::Path;

use glam::Vec3;

use crate::backend::BackendError;
use crate::error::{Error, Result};
use crate::scene::{CubeFaces, Environment, Scene, CUBE_FACE_KEYS};

pub(crate) mod raster;

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
    /// A cube map (faces stacked in layer order, `height` = 6 · `width`), not an equirect one.
    pub cube: bool,
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
        out.push(if total > 0.0 {
            (acc / total) as f32
        } else {
            (k + 1) as f32 / weights.len() as f32
        });
    }
    *out.last_mut().expect("one entry per weight plus the 0") = 1.0;
    out
}

impl EnvironmentMap {
    /// Loads an `.hdr`/`.exr` radiance map, multiplied by `scale`. `source` names the scene file
    /// in errors.
    pub fn load(path: &Path, scale: f32, source: &str) -> Result<EnvironmentMap> {
        let img = image::open(path)
            .map_err(|e| {
                Error::Usage(format!(
                    "{source}: environment.path: {}: cannot load: {e}",
                    path.display()
                ))
            })?
            .to_rgba32f();
        let (width, height) = img.dimensions();
        if (width as usize) * (height as usize) > MAX_TEXELS {
            return Err(Error::Backend(BackendError::Unsupported(format!(
                "{source}: environment.path: {}: {width}x{height} is more than the {MAX_TEXELS} texels the reference renderer can upload",
                path.display()
            ))));
        }
        if let Some((i, p)) = img
            .pixels()
            .enumerate()
            .find(|(_, p)| p.0[..3].iter().any(|c| !c.is_finite() || *c < 0.0))
        {
            let (x, y) = (i as u32 % width, i as u32 / width);
            return Err(Error::Usage(format!(
                "{source}: environment.path: {}: pixel ({x}, {y}) is ({}, {}, {}); radiance must be finite and not negative (fix or clamp the image)",
                path.display(),
                p[0],
                p[1],
                p[2]
            )));
        }
        let texels = img
            .pixels()
            .map(|p| [p[0] * scale, p[1] * scale, p[2] * scale, 0.0])
            .collect();
        Ok(EnvironmentMap::from_texels(width, height, texels))
    }

    /// Loads a cube environment's six faces (see [`CubeFaces::load`]), multiplied by `scale`.
    pub fn load_cube(faces: &[std::path::PathBuf; 6], scale: f32, source: &str) -> Result<EnvironmentMap> {
        let c = load_cube_faces(faces, scale, source)?;
        if 6 * (c.size as usize).pow(2) > MAX_TEXELS {
            return Err(Error::Backend(BackendError::Unsupported(format!(
                "{source}: environment: six {0}x{0} cube faces are more than the {MAX_TEXELS} texels the reference renderer can upload",
                c.size
            ))));
        }
        Ok(EnvironmentMap::from_cube(c.size, c.texels))
    }

    /// The scene's environment: its map, a 1×1 map of a constant, or one black texel.
    pub fn of_scene(scene: &Scene) -> Result<EnvironmentMap> {
        Ok(match &scene.environment {
            Some(Environment::Image { path, scale }) => EnvironmentMap::load(path, *scale, &scene.source)?,
            Some(Environment::Cube { faces, scale }) => EnvironmentMap::load_cube(faces, *scale, &scene.source)?,
            Some(Environment::Constant { radiance }) => {
                EnvironmentMap::from_texels(1, 1, vec![radiance.extend(0.0).into()])
            }
            None => EnvironmentMap::from_texels(1, 1, vec![[0.0; 4]]),
        })
    }

    /// The map box-filtered so that an equirect map is at most `max_width` wide and a cube face
    /// at most `max_width / 4` a side (about the same texel count), as (width or face size,
    /// texels). An SH projection needs no more.
    pub fn reduced(&self, max_width: u32) -> (u32, Vec<[f32; 4]>) {
        if self.cube {
            let n = self.width;
            let f = n.div_ceil((max_width / 4).max(1)).max(1);
            let m = (n / f).max(1);
            let mut out = vec![[0.0f32; 4]; (6 * m * m) as usize];
            for face in 0..6 {
                let src = &self.texels[(face * n * n) as usize..((face + 1) * n * n) as usize];
                box_filter(
                    src,
                    n,
                    n,
                    f,
                    m,
                    m,
                    &mut out[(face * m * m) as usize..((face + 1) * m * m) as usize],
                );
            }
            (m, out)
        } else {
            let (w, h) = (self.width, self.height);
            let f = w.div_ceil(max_width.max(1)).max(1);
            let (nw, nh) = ((w / f).max(1), (h / f).max(1));
            let mut out = vec![[0.0f32; 4]; (nw * nh) as usize];
            box_filter(&self.texels, w, h, f, nw, nh, &mut out);
            (nw, out)
        }
    }

    pub fn from_texels(width: u32, height: u32, texels: Vec<[f32; 4]>) -> EnvironmentMap {
        let h = height as f64;
        EnvironmentMap::build(width, height, texels, false, |_, j| {
            (std::f64::consts::PI * (j as f64 + 0.5) / h).sin()
        })
    }

    /// A cube map from its six `size`² faces in layer order (as [`CubeFaces::texels`]).
    pub fn from_cube(size: u32, texels: Vec<[f32; 4]>) -> EnvironmentMap {
        let n = size as usize;
        EnvironmentMap::build(size, 6 * size, texels, true, |i, j| {
            crate::sh::cube_texel_solid_angle(i, j % n, n)
        })
    }

    /// The CDFs of texel luminance × `solid_angle(i, j)` (anything proportional to it).
    fn build(
        width: u32,
        height: u32,
        texels: Vec<[f32; 4]>,
        cube: bool,
        solid_angle: impl Fn(usize, usize) -> f64,
    ) -> EnvironmentMap {
        let (w, h) = (width as usize, height as usize);
        let mut rows = Vec::with_capacity(h);
        let mut columns = Vec::with_capacity(h * (w + 1));
        for j in 0..h {
            let weights: Vec<f64> = texels[j * w..(j + 1) * w]
                .iter()
                .enumerate()
                .map(|(i, &t)| luminance(t).max(0.0) * solid_angle(i, j))
                .collect();
            rows.push(weights.iter().sum::<f64>());
            columns.extend(cdf_of(&weights));
        }
        let has_power = rows.iter().sum::<f64>() > 0.0;
        let mut cdf = cdf_of(&rows);
        cdf.extend(columns);
        EnvironmentMap {
            width,
            height,
            texels,
            cdf,
            has_power,
            cube,
        }
    }

    /// The texel `dir` falls in, as (column, row) of the stored map, and the density (per unit
    /// solid angle) that sampling uniformly within that texel's parameter rectangle gives `dir`
    /// per unit of the texel's probability.
    fn texel_of(&self, dir: Vec3) -> ((usize, usize), f32) {
        let (w, h) = (self.width as usize, self.height as usize);
        if self.cube {
            let (face, s, t) = Environment::cube_face(dir);
            let cell = |c: f32| (((c + 1.0) * 0.5 * w as f32) as usize).min(w - 1);
            // A texel spans (2/w)² of (s, t); dω/ds dt = (1 + s² + t²)^(-3/2).
            let density = (w * w) as f32 / 4.0 * (1.0 + s * s + t * t).powf(1.5);
            ((cell(s), face * w + cell(t)), density)
        } else {
            let uv = Environment::equirect_uv(dir);
            let i = ((uv.x * self.width as f32) as usize).min(w - 1);
            let j = ((uv.y * self.height as f32) as usize).min(h - 1);
            let sin_theta = (uv.y * std::f32::consts::PI).sin();
            let density = if sin_theta > 0.0 {
                (w * h) as f32 / (2.0 * std::f32::consts::PI * std::f32::consts::PI * sin_theta)
            } else {
                0.0
            };
            ((i, j), density)
        }
    }

    /// Radiance arriving from direction `dir` (the same nearest lookup as the shader).
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let ((i, j), _) = self.texel_of(dir);
        let t = self.texels[j * self.width as usize + i];
        Vec3::new(t[0], t[1], t[2])
    }

    /// Solid-angle density with which the shader samples `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let ((i, j), density) = self.texel_of(dir);
        let (w, h) = (self.width as usize, self.height as usize);
        let row = self.cdf[j + 1] - self.cdf[j];
        let col = &self.cdf[h + 1 + j * (w + 1)..];
        row * (col[i + 1] - col[i]) * density
    }
}

/// Averages `f`×`f` blocks of a `w`×`h` image into the `nw`×`nh` `out` (edges clamped).
fn box_filter(src: &[[f32; 4]], w: u32, h: u32, f: u32, nw: u32, nh: u32, out: &mut [[f32; 4]]) {
    for y in 0..nh {
        for x in 0..nw {
            let mut acc = [0.0f32; 4];
            for sy in 0..f {
                for sx in 0..f {
                    let p = src[(((y * f + sy).min(h - 1)) * w + (x * f + sx).min(w - 1)) as usize];
                    for c in 0..3 {
                        acc[c] += p[c] / (f * f) as f32;
                    }
                }
            }
            out[(y * nw + x) as usize] = acc;
        }
    }
}

/// [`CubeFaces::load`] with its error as the renderer reports it: the scene file and the face's key.
pub fn load_cube_faces(faces: &[std::path::PathBuf; 6], scale: f32, source: &str) -> Result<CubeFaces> {
    CubeFaces::load(faces, scale)
        .map_err(|(k, msg)| Error::Usage(format!("{source}: environment.{}: {msg}", CUBE_FACE_KEYS[k])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn map() -> EnvironmentMap {
        let (w, h) = (16, 8);
        let texels = (0..w * h).map(|k| {
            let v = if k == 2 * w + 5 {
                50.0
            } else {
                0.2 + (k % w) as f32 * 0.05
            };
            [v, 0.5 * v, 0.1, 0.0]
        });
        EnvironmentMap::from_texels(w as u32, h as u32, texels.collect())
    }

    /// The scene's cube layout (`Environment::cube_dir`) and the SH core's texel directions agree
    /// (the SH core cannot use the scene module: it sits below it).
    #[test]
    fn cube_texel_directions_match_the_sh_core() {
        for face in 0..6 {
            let n = 8;
            for (x, y) in [(0, 0), (3, 6), (7, 7)] {
                let (s, t) = (
                    2.0 * (x as f32 + 0.5) / n as f32 - 1.0,
                    2.0 * (y as f32 + 0.5) / n as f32 - 1.0,
                );
                assert_eq!(
                    Environment::cube_dir(face, s, t),
                    crate::sh::cube_texel_dir_world(face, x, y, n)
                );
            }
        }
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

    /// ∫ pdf dω over the sphere by the midpoint rule in n × 2n equirect cells.
    fn pdf_integral(m: &EnvironmentMap, n: usize) -> f64 {
        let mut sum = 0.0f64;
        for a in 0..n {
            for b in 0..2 * n {
                let uv = Vec2::new((b as f32 + 0.5) / (2 * n) as f32, (a as f32 + 0.5) / n as f32);
                let d_omega = 2.0 * std::f64::consts::PI.powi(2) * (uv.y as f64 * std::f64::consts::PI).sin()
                    / (2 * n * n) as f64;
                sum += m.pdf(Environment::equirect_dir(uv)) as f64 * d_omega;
            }
        }
        sum
    }

    #[test]
    fn pdf_integrates_to_one_over_the_sphere() {
        let m = map();
        let sum = pdf_integral(&m, 400);
        assert!((sum - 1.0).abs() < 1e-3, "{sum}");
        // The bright texel is sampled far more often than its neighbours.
        let bright = Environment::equirect_dir(Vec2::new(5.5 / 16.0, 2.5 / 8.0));
        let dim = Environment::equirect_dir(Vec2::new(6.5 / 16.0, 2.5 / 8.0));
        assert!(m.pdf(bright) > 50.0 * m.pdf(dim));
        assert_eq!(m.radiance(bright).x, 50.0);
    }

    /// Six 6² faces: face k is k + 1 everywhere but one bright texel on −Z.
    fn cube() -> EnvironmentMap {
        let n = 6;
        let texels = (0..6 * n * n).map(|k| {
            let v = if k == 5 * n * n + 2 * n + 4 {
                40.0
            } else {
                (k / (n * n)) as f32 + 1.0
            };
            [v, v, v, 0.0]
        });
        EnvironmentMap::from_cube(n as u32, texels.collect())
    }

    #[test]
    fn cube_pdf_integrates_to_one_and_follows_the_texels() {
        let m = cube();
        assert_eq!((m.width, m.height, m.cdf.len()), (6, 36, 37 + 36 * 7));
        // Quadrature over the sphere in equirect cells (the pdf is piecewise smooth).
        let sum = pdf_integral(&m, 600);
        assert!((sum - 1.0).abs() < 2e-3, "{sum}");
        // Radiance is face k + 1 along each axis; the bright texel is -Z's (4, 2).
        let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        for (k, a) in axes.into_iter().enumerate() {
            assert_eq!(m.radiance(a + Vec3::splat(0.01)).x, k as f32 + 1.0, "{a}");
        }
        let bright = Environment::cube_dir(5, 2.0 * 4.5 / 6.0 - 1.0, 2.0 * 2.5 / 6.0 - 1.0).normalize();
        assert_eq!(m.radiance(bright).x, 40.0);
        // A constant map picks texels by solid angle, so at texel centres the density is close
        // to uniform 1/4π (not exactly: within a texel, sampling is uniform in (s, t)).
        let n = 16;
        let flat = EnvironmentMap::from_cube(n as u32, vec![[1.0, 1.0, 1.0, 0.0]; 6 * n * n]);
        let mut worst = 0.0f32;
        for (face, x, y) in [(2, 0, 0), (0, 7, 8), (5, 15, 3), (3, 15, 15)] {
            let p = flat.pdf(crate::sh::cube_texel_dir_world(face, x, y, n).normalize()) * 4.0 * std::f32::consts::PI;
            worst = worst.max((p - 1.0).abs());
        }
        assert!(worst < 0.01, "{worst}");
    }
}
