//! SH light-maps (seed 000 §5, CaSHL; digest §1.5–1.8): per light-map texel, the SH coefficients
//! of its transfer function (shadowed diffuse plus interreflections), so that a distant light of
//! any shape (sky, sun, an environment image) moves at run time for one dot product per texel.

pub mod gpu;
pub mod normals;
pub mod samples;
pub mod storage;
pub mod transfer;

#[cfg(test)]
mod tests;
pub mod vq;
