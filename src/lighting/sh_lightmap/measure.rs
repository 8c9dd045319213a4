//! What compression costs: PSNR of bare-SHL shading, compressed against
//! native, over random directional lights, and the seed's storage model beside it.

use glam::DVec3;

use super::storage::{compression_ratio, StorageReport};
use super::vq::Quantized;
use super::Baked;
use crate::sh;

/// `count` directions uniform on the sphere (world frame), reproducible.
pub fn random_directions(count: usize, seed: u64) -> Vec<DVec3> {
    let mut s = seed | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..count)
        .map(|_| {
            let z = 2.0 * next() - 1.0;
            let phi = 2.0 * std::f64::consts::PI * next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            DVec3::new(r * phi.cos(), z, r * phi.sin())
        })
        .collect()
}

/// PSNR (dB) of `max(T·L, 0)` over every texel that holds a transfer (gap texels are never
/// drawn) and every light of `dirs` (unit directional lights), the quantised transfers against
/// the native ones; the peak is the native images' maximum. Infinite when they are equal.
pub fn shaded_psnr(baked: &Baked, q: &Quantized, dirs: &[DVec3]) -> f64 {
    let dim = baked.bands * baked.bands;
    let lights: Vec<Vec<f64>> = dirs
        .iter()
        .map(|d| {
            let mut y = vec![0.0; dim];
            let _ = sh::eval_basis_f64(DVec3::new(d.x, -d.z, d.y), baked.bands, &mut y);
            y
        })
        .collect();
    let (mut sse, mut n, mut peak) = (0.0f64, 0usize, 0.0f64);
    for (t, native) in baked.coeffs.chunks_exact(dim).enumerate() {
        if native.iter().all(|&c| c == 0.0) {
            continue;
        }
        let rep = q.indices[t] as usize;
        let coded = &q.codebook[rep * dim..(rep + 1) * dim];
        for l in &lights {
            let a: f64 = native.iter().zip(l).map(|(c, y)| *c as f64 * y).sum::<f64>().max(0.0);
            let b: f64 = coded.iter().zip(l).map(|(c, y)| *c as f64 * y).sum::<f64>().max(0.0);
            sse += (a - b) * (a - b);
            peak = peak.max(a);
            n += 1;
        }
    }
    if sse == 0.0 || n == 0 {
        return f64::INFINITY;
    }
    10.0 * (peak * peak / (sse / n as f64)).log10()
}

/// One row of the table: PSNR and the seed model's compression ratio for `q`.
pub struct Row {
    pub bands: usize,
    pub reps: usize,
    pub texels: usize,
    pub iterations: usize,
    pub unused: usize,
    pub psnr_db: f64,
    pub ratio: f64,
    pub vq_seconds: f64,
}

pub fn row(baked: &Baked, q: &Quantized, dirs: &[DVec3], vq_seconds: f64, reps: usize) -> Row {
    let texels = (baked.width * baked.height) as usize;
    let ratio = match (
        StorageReport::uncompressed(texels, baked.bands),
        StorageReport::compressed(texels, baked.bands, reps.max(1)),
    ) {
        (Ok(u), Ok(c)) => compression_ratio(&u, &c),
        _ => f64::NAN,
    };
    Row {
        bands: baked.bands,
        reps,
        texels,
        iterations: q.iterations,
        unused: q.unused,
        psnr_db: shaded_psnr(baked, q, dirs),
        ratio,
        vq_seconds,
    }
}

impl std::fmt::Display for Row {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "| {} | {} | {} | {:.1} | {:.2} | {} | {} | {:.1} |",
            self.bands, self.reps, self.texels, self.psnr_db, self.ratio, self.iterations, self.unused, self.vq_seconds
        )
    }
}
