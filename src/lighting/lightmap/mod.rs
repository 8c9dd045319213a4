//! The light-map substrate that the Ca3D-Engine thesis's two light-mapped methods share (radiosity light-maps
//! and SH light-maps, `lighting::radiosity` and `lighting::sh_lightmap`): static geometry as
//! charts of patches (planar, or curved within a quarter patch of a plane) on a world-aligned grid ([`patches`], [`geometry`]), the atlas
//! (`atlas`), the surface-visibility matrix ([`visibility`]), form factors (`form_factor`),
//! the progressive-refinement shooting loop over any payload ([`solve`]), the border passes
//! ([`border`]) and CaLight's tone reproduction (`tone`). It knows nothing of the lighting
//! layer: the techniques build on it.

pub(crate) mod atlas;
pub mod border;
pub mod buried;
pub mod cut;
pub(crate) mod form_factor;
pub mod geometry;
pub(crate) mod mesh;
pub mod patches;
pub mod solve;
pub(crate) mod tone;
pub mod visibility;
