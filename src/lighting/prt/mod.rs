//! Per-vertex precomputed radiance transfer baked on the GPU (seed 002, digest
//! `seed-002-gpu-sh-transfer.md`): for every vertex the SH coefficients of its shadowed
//! clamped-cosine transfer `T_i = ∫ V(ω) max(0, n·ω) y_i(ω) dω`, so that a distant light of any
//! shape shades it for one dot product, `L_o = ρ/π · Σ T_i L_i`.

pub mod config;
pub mod mapping;
pub mod raster;
pub mod raycast;
pub mod receivers;
