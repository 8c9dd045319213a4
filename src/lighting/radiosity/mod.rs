//! Radiosity light-maps (seed 000 §3, CaLight; digest §1.2): patches on the static geometry, one
//! per light-map texel ([`patches`]), form factors ([`form_factor`]) and progressive-refinement
//! shooting ([`solve`]), faithful to CaLight or corrected (exact form factors, energy that
//! closes).
//!
//! Status: the baker's core on the CPU, tested against closed forms (form factors, closed-box
//! energy balance). The light-map atlas, the GPU shooting pass, the base term that draws
//! `diffuse × lightmap` and its registry entry are still to come (issue 12).

pub mod form_factor;
pub mod patches;
pub mod solve;

#[cfg(test)]
mod tests;
