//! CaSHL's shared sample set (the Ca3D-Engine thesis §5.1.3, digest §1.5): one set of directions for every
//! patch, so that bounces can work on coefficient vectors (Eq. 11/12). A √N × √N grid of cell
//! centres, not jittered: `x = (i + ½)/√N`, `θ = 2·acos(√(1 − x))` (uniform in cos θ),
//! `φ = 2π·(j + ½)/√N`; each sample weighs 4π/N.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::sh;

/// The seed's range of sample counts.
pub const MIN_SAMPLES: usize = 20;
pub const MAX_SAMPLES: usize = 100_000;

pub struct SampleSet {
    /// Directions in penumbra's world frame (y up).
    pub dirs: Vec<DVec3>,
    /// `bands²` basis values per direction, direction-major.
    pub basis: Vec<f64>,
    pub bands: usize,
    /// The Monte Carlo weight 4π/N.
    pub weight: f64,
}

impl SampleSet {
    /// About `count` samples (the grid's side is ⌈√count⌉), for `bands` bands.
    pub fn new(count: usize, bands: usize) -> Result<SampleSet> {
        if !(MIN_SAMPLES..=MAX_SAMPLES).contains(&count) {
            return Err(Error::Usage(format!(
                "SH light-map samples: {count} is outside {MIN_SAMPLES}..={MAX_SAMPLES}"
            )));
        }
        sh::check_bands(bands).map_err(|e| Error::Usage(format!("SH light-map bands: {e}")))?;
        let side = (count as f64).sqrt().ceil() as usize;
        let n = side * side;
        let dim = bands * bands;
        let mut dirs = Vec::with_capacity(n);
        let mut basis = vec![0.0; n * dim];
        for i in 0..side {
            let x = (i as f64 + 0.5) / side as f64;
            let theta = 2.0 * (1.0 - x).sqrt().acos();
            for j in 0..side {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / side as f64;
                let s = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let k = dirs.len();
                sh::eval_basis_f64(s, bands, &mut basis[k * dim..(k + 1) * dim])
                    .map_err(|e| Error::Usage(format!("SH light-map basis: {e}")))?;
                // The SH frame's z is world up (`sh::sh_to_world`), in f64.
                dirs.push(DVec3::new(s.x, s.z, -s.y));
            }
        }
        Ok(SampleSet {
            weight: 4.0 * std::f64::consts::PI / n as f64,
            dirs,
            basis,
            bands,
        })
    }

    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }

    pub fn dim(&self) -> usize {
        self.bands * self.bands
    }

    /// The basis values of sample `k`.
    pub fn y(&self, k: usize) -> &[f64] {
        &self.basis[k * self.dim()..(k + 1) * self.dim()]
    }
}
