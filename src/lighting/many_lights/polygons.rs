//! The static scene as convex polygons with their diffuse reflectance: what both of Ridderhof 2002's
//! systems light. Mesh triangles are the polygons (every triangle is convex); the thesis's own
//! scenes were quads, which penumbra's meshes store as two triangles.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::world::{Polygon, Tolerance};

/// One convex polygon of the scene, counter-clockwise seen from the side its normal points to.
#[derive(Clone, Debug)]
pub struct ScenePolygon {
    pub polygon: Polygon,
    /// Diffuse reflectance, RGB (the material's albedo times its map's mean).
    pub albedo: DVec3,
    /// Emitted radiance, RGB (a method drawing the segments draws their emission too).
    pub emission: DVec3,
    /// The scene draw it came from (so a method can draw its segments with the draw's
    /// material and model matrix).
    pub draw: usize,
}

/// The scene's static triangles as polygons. Degenerate triangles (under `tolerance`'s least
/// area) are left out: they can neither receive nor cast a visible shadow. Animated objects are refused: both
/// systems precompute per-light lighting for a static scene (the thesis's first requirement).
pub fn scene_polygons(
    scene_source: &str,
    geometry: &StaticGeometry,
    method: &str,
    tolerance: &Tolerance,
) -> Result<Vec<ScenePolygon>> {
    if let Some(&d) = geometry.entities.first() {
        return Err(Error::Usage(format!("{scene_source}: draw {d} is animated: {method} precomputes lighting for a static scene (Ridderhof's Modelling Multiple Light Sources assumes a static scene)")));
    }
    let mut out = Vec::with_capacity(geometry.triangles.len());
    for (t, tri) in geometry.triangles.iter().enumerate() {
        if let Some(polygon) = Polygon::from_vertices_in(tri.p.to_vec(), tolerance) {
            out.push(ScenePolygon {
                polygon,
                albedo: tri.albedo,
                emission: tri.emission,
                draw: geometry.draw[t],
            });
        }
    }
    Ok(out)
}
