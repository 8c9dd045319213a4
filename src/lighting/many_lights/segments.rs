//! Segmentation (§1.3): each convex polygon fan-triangulated, then every triangle split 1→4 at
//! its edge midpoints until no piece is larger than the maximum area.
//!
//! Two corrections to the thesis: the fan stops at `n − 2` triangles (the thesis's loop runs one
//! too far), and all triangles of a polygon are split to the same depth — the depth its largest
//! triangle needs — so no T-junction appears inside a polygon. `d` rounds of midpoint splitting
//! are the barycentric grid of `2^d` steps per edge, built directly with the parent's winding.
//! Vertices are shared within a polygon, never between polygons: each polygon has its own
//! normal and, in the BSP system, its own shadows.

use std::collections::HashMap;

use glam::DVec3;

use crate::world::Polygon;

/// More segments than this is refused: 4 M triangles is ~200 MB of set-up data per system and
/// far beyond what the thesis's scenes need.
pub const MAX_SEGMENTS: usize = 1 << 22;

#[derive(Clone, Debug, Default)]
pub struct Segments {
    pub positions: Vec<DVec3>,
    /// Per vertex: its polygon's unit normal.
    pub normals: Vec<DVec3>,
    pub vertex_polygon: Vec<u32>,
    /// Counter-clockwise seen from the front of the polygon, like the polygon.
    pub triangles: Vec<[u32; 3]>,
    pub triangle_polygon: Vec<u32>,
}

impl Segments {
    /// Segments no larger than `max_area` (world units²) over `polygons`, or why not.
    pub fn build<'a>(
        polygons: impl IntoIterator<Item = &'a Polygon> + Clone,
        max_area: f64,
    ) -> Result<Segments, String> {
        if !(max_area.is_finite() && max_area > 0.0) {
            return Err(format!(
                "the maximum segment area must be a positive number (got {max_area})"
            ));
        }
        let depths: Vec<u32> = polygons.clone().into_iter().map(|p| depth_for(p, max_area)).collect();
        let total: f64 = polygons
            .clone()
            .into_iter()
            .zip(&depths)
            .map(|(p, &d)| (p.vertices.len().saturating_sub(2)) as f64 * 4f64.powi(d as i32))
            .sum();
        if total > MAX_SEGMENTS as f64 {
            return Err(format!(
                "{total:.0} segments at a maximum area of {max_area} (the limit is {MAX_SEGMENTS}): raise the area"
            ));
        }
        let mut s = Segments::default();
        for (pi, (p, &depth)) in polygons.into_iter().zip(&depths).enumerate() {
            s.add_polygon(p, pi as u32, depth);
        }
        Ok(s)
    }

    fn add_polygon(&mut self, p: &Polygon, polygon: u32, depth: u32) {
        let m = 1u32 << depth;
        let Segments {
            positions,
            normals,
            vertex_polygon,
            triangles,
            triangle_polygon,
        } = self;
        let mut index: HashMap<[u64; 3], u32> = HashMap::new();
        let a = p.vertices[0];
        for k in 1..p.vertices.len().saturating_sub(1) {
            let (b, c) = (p.vertices[k], p.vertices[k + 1]);
            // Grid vertex (i, j): a + (b − a)·i/m + (c − a)·j/m. Edges shared by neighbouring fan
            // triangles evaluate to the same bits (a term with a zero weight adds exactly 0).
            let mut vertex = |i: u32, j: u32| -> u32 {
                let q = a + (b - a) * (i as f64 / m as f64) + (c - a) * (j as f64 / m as f64);
                let key = [q.x.to_bits(), q.y.to_bits(), q.z.to_bits()];
                *index.entry(key).or_insert_with(|| {
                    positions.push(q);
                    normals.push(p.plane.normal);
                    vertex_polygon.push(polygon);
                    (positions.len() - 1) as u32
                })
            };
            for j in 0..m {
                for i in 0..m - j {
                    let (v00, v10, v01) = (vertex(i, j), vertex(i + 1, j), vertex(i, j + 1));
                    triangles.push([v00, v10, v01]);
                    triangle_polygon.push(polygon);
                    if i + j + 1 < m {
                        let v11 = vertex(i + 1, j + 1);
                        triangles.push([v10, v11, v01]);
                        triangle_polygon.push(polygon);
                    }
                }
            }
        }
    }

    pub fn triangle_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        0.5 * (b - a).cross(c - a).length()
    }

    pub fn centroid(&self, t: usize) -> DVec3 {
        self.triangles[t]
            .iter()
            .map(|&i| self.positions[i as usize])
            .sum::<DVec3>()
            / 3.0
    }
}

/// Rounds of 1→4 splitting the polygon's largest fan triangle needs to be at most `max_area`.
fn depth_for(p: &Polygon, max_area: f64) -> u32 {
    let a = p.vertices[0];
    let largest = (1..p.vertices.len().saturating_sub(1))
        .map(|k| 0.5 * (p.vertices[k] - a).cross(p.vertices[k + 1] - a).length())
        .fold(0.0, f64::max);
    let mut depth = 0;
    let mut area = largest;
    while area > max_area && depth < 16 {
        area /= 4.0;
        depth += 1;
    }
    depth
}
