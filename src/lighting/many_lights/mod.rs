//! The shared core of Ridderhof 2002's two many-light systems (virtualised light sources and the BSP
//! shadow system): the scene as convex polygons, their segmentation into small triangles, the
//! light models, the thesis's geometric primitives and a ray-cast truth. Pure CPU and `f64`, no
//! GPU types: both methods' set-up (a bake) and their tests use it as it is.
//!
//! The digest is the notes on the source document; section numbers below are its.

pub mod geometry;
pub(crate) mod light_model;
pub(crate) mod occluders;
pub(crate) mod polygons;
pub(crate) mod segments;

#[cfg(test)]
mod tests;

pub use light_model::{LightModel, ManyLight};
pub use occluders::Occluders;
pub use polygons::{scene_polygons, ScenePolygon};
pub use segments::Segments;
