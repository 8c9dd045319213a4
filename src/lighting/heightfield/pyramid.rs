//! The smoothing pyramid of the height-field thesis (§4.2.1, §5.1; digest §1.3–1.4, §5.1–5.2): its layout and a
//! CPU mirror of `glsl/heightfield/decimate.comp` and `reconstruct.comp`.
//!
//! - n = ls·log2(res) + 1 levels (Eq. 4.4); level k has about res·2^(−k/ls) texels per side,
//!   decimated from level k − 1 (tent or cubic B-spline filter as wide as the target texel);
//! - every level is reconstructed back to full resolution with the uniform cubic B-spline, so
//!   each pyramid sample is one bilinear fetch (x, y, level);
//! - nearest-first sampling (digest §5.1): sample i lies at d_i = s_r^i texels (s_r = 2^(1/ls),
//!   d_0 = 1 texel, d_{n−1} = res) and reads level clamp(⌊i − ls·lo⌋, 0, n − 1), the level offset
//!   lo moving samples toward finer levels (the thesis's ceiling in its far-first indexing).

use super::settings::Decimation;

/// Number of levels (Eq. 4.4): ls·⌊log2 res⌋ + 1.
pub fn level_count(res: u32, ls: u32) -> u32 {
    ls * res.max(1).ilog2() + 1
}

/// Texels per side of level k: round(res·2^(−k/ls)), at least 1.
pub fn level_size(res: u32, ls: u32, k: u32) -> u32 {
    ((res as f64) * (-(k as f64) / ls as f64).exp2()).round().max(1.0) as u32
}

/// Distance of sample i from the receiver, texels: s_r^i.
pub fn sample_distance(ls: u32, i: u32) -> f64 {
    (i as f64 / ls as f64).exp2()
}

/// The level sample i reads with level offset lo.
pub fn sample_level(i: u32, ls: u32, lo: f32, levels: u32) -> u32 {
    let l = (i as f64 - ls as f64 * lo as f64).floor();
    l.clamp(0.0, (levels - 1) as f64) as u32
}

/// A square grid of values, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub size: u32,
    pub values: Vec<f32>,
}

impl Grid {
    pub fn at(&self, x: i64, y: i64) -> f32 {
        let n = self.size as i64;
        self.values[(y.clamp(0, n - 1) * n + x.clamp(0, n - 1)) as usize]
    }

    /// Bilinear value at continuous texel coordinates (centres at integers), clamped.
    pub fn bilinear(&self, x: f64, y: f64) -> f64 {
        let (fx, fy) = (x.floor(), y.floor());
        let (tx, ty) = (x - fx, y - fy);
        let (ix, iy) = (fx as i64, fy as i64);
        let a = self.at(ix, iy) as f64 * (1.0 - tx) + self.at(ix + 1, iy) as f64 * tx;
        let b = self.at(ix, iy + 1) as f64 * (1.0 - tx) + self.at(ix + 1, iy + 1) as f64 * tx;
        a * (1.0 - ty) + b * ty
    }
}

fn kernel(x: f64, q: f64, decimation: Decimation) -> f64 {
    let a = x.abs() / q;
    match decimation {
        Decimation::Bilinear => (1.0 - a).max(0.0),
        Decimation::Bicubic if a < 1.0 => (4.0 - 6.0 * a * a + 3.0 * a * a * a) / 6.0,
        Decimation::Bicubic if a < 2.0 => (2.0 - a).powi(3) / 6.0,
        Decimation::Bicubic => 0.0,
    }
}

/// One decimation step, `src` → `dst_size²` (mirrors `decimate.comp`).
pub fn decimate(src: &Grid, dst_size: u32, decimation: Decimation) -> Grid {
    let q = src.size as f64 / dst_size as f64;
    let radius = match decimation {
        Decimation::Bilinear => q,
        Decimation::Bicubic => 2.0 * q,
    };
    let mut values = Vec::with_capacity((dst_size * dst_size) as usize);
    for ty in 0..dst_size {
        for tx in 0..dst_size {
            let (ux, uy) = ((tx as f64 + 0.5) * q - 0.5, (ty as f64 + 0.5) * q - 0.5);
            let (x0, x1) = ((ux - radius).ceil() as i64, (ux + radius).floor() as i64);
            let (y0, y1) = ((uy - radius).ceil() as i64, (uy + radius).floor() as i64);
            let wx_sum: f64 = (x0..=x1).map(|x| kernel(x as f64 - ux, q, decimation)).sum();
            let mut sum = 0.0;
            let mut wy_sum = 0.0;
            for y in y0..=y1 {
                let wy = kernel(y as f64 - uy, q, decimation);
                wy_sum += wy;
                for x in x0..=x1 {
                    sum += wy * kernel(x as f64 - ux, q, decimation) * src.at(x, y) as f64;
                }
            }
            values.push((sum / (wx_sum * wy_sum)) as f32);
        }
    }
    Grid { size: dst_size, values }
}

/// Uniform cubic B-spline weights at fraction u (Eq. 4.9–4.12).
pub fn bspline_weights(u: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [
        (1.0 - u).powi(3) / 6.0,
        (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0,
        (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0,
        u3 / 6.0,
    ]
}

/// A level reconstructed to `res²` with the cubic B-spline (mirrors `reconstruct.comp`).
pub fn reconstruct(level: &Grid, res: u32) -> Grid {
    let n = level.size as f64;
    let mut values = Vec::with_capacity((res * res) as usize);
    for y in 0..res {
        for x in 0..res {
            let (ux, uy) = (
                (x as f64 + 0.5) * n / res as f64 - 0.5,
                (y as f64 + 0.5) * n / res as f64 - 0.5,
            );
            let (fx, fy) = (ux.floor(), uy.floor());
            let (wx, wy) = (bspline_weights(ux - fx), bspline_weights(uy - fy));
            let mut sum = 0.0;
            for (j, wyj) in wy.iter().enumerate() {
                for (i, wxi) in wx.iter().enumerate() {
                    sum += wyj * wxi * level.at(fx as i64 - 1 + i as i64, fy as i64 - 1 + j as i64) as f64;
                }
            }
            values.push(sum as f32);
        }
    }
    Grid { size: res, values }
}

/// Every level, decimated (level 0 is the input) and reconstructed to full resolution; with
/// `exact_level0` (the corrected mode) level 0 is the input itself.
pub fn build(heights: &Grid, ls: u32, decimation: Decimation, exact_level0: bool) -> Vec<Grid> {
    let res = heights.size;
    let n = level_count(res, ls);
    let mut decimated = vec![heights.clone()];
    for k in 1..n {
        let next = decimate(&decimated[k as usize - 1], level_size(res, ls, k), decimation);
        decimated.push(next);
    }
    decimated
        .iter()
        .enumerate()
        .map(|(k, l)| {
            if k == 0 && exact_level0 {
                l.clone()
            } else {
                reconstruct(l, res)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_matches_the_thesis() {
        // Eq. 4.4 for 256²: ls = 1, 2, 3, 4 give 9, 17, 25, 33 levels.
        assert_eq!([1, 2, 3, 4].map(|ls| level_count(256, ls)), [9, 17, 25, 33]);
        // Digest §1.3: 256, 215, 181, 152, 128, 108, …, 1.
        assert_eq!(
            (0..6).map(|k| level_size(256, 4, k)).collect::<Vec<_>>(),
            vec![256, 215, 181, 152, 128, 108]
        );
        assert_eq!(level_size(256, 4, 32), 1);
        assert!((sample_distance(4, 32) - 256.0).abs() < 1e-9);
        // lo = 4 octaves at ls = 4: the first 16 samples read level 0, sample 20 level 4.
        assert_eq!(sample_level(15, 4, 4.0, 33), 0);
        assert_eq!(sample_level(20, 4, 4.0, 33), 4);
        assert_eq!(sample_level(20, 4, 0.0, 33), 20);
        assert_eq!(sample_level(40, 4, 0.0, 33), 32);
    }

    #[test]
    fn smoothing_keeps_planes_and_means() {
        // A linear ramp is kept by both filters away from the borders; a constant everywhere.
        let res = 32;
        let ramp = Grid {
            size: res,
            values: (0..res * res).map(|i| (i % res) as f32 * 0.5).collect(),
        };
        for d in [Decimation::Bilinear, Decimation::Bicubic] {
            let levels = build(&ramp, 2, d, false);
            assert_eq!(levels.len(), 11);
            for l in &levels[..5] {
                let v = l.at(16, 16) as f64;
                assert!((v - 8.0).abs() < 0.3, "{d:?}: {v}");
            }
            let flat = Grid {
                size: res,
                values: vec![3.0; (res * res) as usize],
            };
            for l in build(&flat, 2, d, false) {
                assert!(l.values.iter().all(|v| (v - 3.0).abs() < 1e-5));
            }
        }
    }
}
