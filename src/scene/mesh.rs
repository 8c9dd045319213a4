//! CPU triangle meshes: attribute generation, validation, transformation and topology checks.

use std::collections::HashMap;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

use super::error::SceneError;

/// An indexed triangle list. All attribute arrays have one entry per vertex.
///
/// Front faces are counter-clockwise seen from outside (right-handed). `uvs` use the Vulkan/image
/// convention: (0, 0) is the top-left texel, v grows downward (OBJ `vt` v is flipped on load).
/// `tangents.xyz` points toward +u; the bitangent `tangents.w * normal.cross(tangent.xyz)` points
/// toward **−v** (up in the image), so an OpenGL-convention normal map decodes as
/// `T * n.x + B * n.y + N * n.z`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub tangents: Vec<Vec4>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Vertex indices of each triangle. Assumes validated indices (see [`Mesh::validate`]).
    pub fn triangles(&self) -> impl Iterator<Item = [usize; 3]> + '_ {
        self.indices
            .chunks_exact(3)
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
    }

    fn corners(&self, t: [usize; 3]) -> Option<[Vec3; 3]> {
        Some([
            *self.positions.get(t[0])?,
            *self.positions.get(t[1])?,
            *self.positions.get(t[2])?,
        ])
    }

    /// Total surface area.
    pub fn area(&self) -> f32 {
        let area = |t| {
            self.corners(t)
                .map_or(0.0, |[a, b, c]| 0.5 * (b - a).cross(c - a).length())
        };
        self.triangles().map(area).sum()
    }

    /// Axis-aligned bounds (min, max); `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// Checks counts, index ranges and finiteness. `file` names the mesh in the error, whose
    /// field is e.g. `vertex 12` or `triangle 3` (0-based indices into this mesh).
    pub fn validate(&self, file: &str) -> Result<(), SceneError> {
        let n = self.positions.len();
        let err = |field: String, msg: String| SceneError::new(file, None, field, msg);
        if !self.indices.len().is_multiple_of(3) {
            return Err(err(
                "indices".into(),
                format!("{} indices is not a multiple of 3", self.indices.len()),
            ));
        }
        if n > u32::MAX as usize {
            return Err(err(
                "positions".into(),
                format!("{n} vertices is more than u32 indices address"),
            ));
        }
        for (name, len) in [
            ("normals", self.normals.len()),
            ("uvs", self.uvs.len()),
            ("tangents", self.tangents.len()),
        ] {
            if len != n {
                return Err(err(name.into(), format!("{len} entries for {n} vertices")));
            }
        }
        for (t, tri) in self.indices.chunks_exact(3).enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(err(
                    format!("triangle {t}"),
                    format!("vertex index {i} out of range (mesh has {n} vertices)"),
                ));
            }
        }
        for i in 0..n {
            let bad = |what: &str, v: String| err(format!("vertex {i}"), format!("{what} is not finite: {v}"));
            if let Some(p) = self.positions.get(i).filter(|p| !p.is_finite()) {
                return Err(bad("position", format!("{p}")));
            }
            if let Some(v) = self.normals.get(i).filter(|v| !v.is_finite()) {
                return Err(bad("normal", format!("{v}")));
            }
            if let Some(v) = self.uvs.get(i).filter(|v| !v.is_finite()) {
                return Err(bad("uv", format!("{v}")));
            }
            if let Some(v) = self.tangents.get(i).filter(|v| !v.is_finite()) {
                return Err(bad("tangent", format!("{v}")));
            }
        }
        Ok(())
    }

    /// For each vertex, the index of the first vertex with a bit-identical position (−0 and +0
    /// equal). Generated and loaded meshes split vertices at uv seams and hard edges; welding by
    /// position recovers the surface's connectivity (shadow-volume adjacency needs it).
    pub fn weld_map(&self) -> Vec<u32> {
        let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits); // + 0 turns −0 into +0
        let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(self.positions.len());
        let mut out = Vec::with_capacity(self.positions.len());
        for (i, &p) in self.positions.iter().enumerate() {
            out.push(*first.entry(key(p)).or_insert(i as u32));
        }
        out
    }

    /// Directed-edge counts over welded vertices; `None` if a triangle repeats a welded vertex.
    fn directed_edges(&self) -> Option<HashMap<(u32, u32), u32>> {
        let weld = self.weld_map();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.indices.len());
        for t in self.indices.chunks_exact(3) {
            let w = [t[0], t[1], t[2]].map(|i| weld.get(i as usize).copied().unwrap_or(i));
            if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
                return None;
            }
            for k in 0..3 {
                *edges.entry((w[k], w[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        Some(edges)
    }

    /// True when the surface (vertices welded by position) is a closed, consistently oriented
    /// 2-manifold: every undirected edge is used by exactly two triangles, once in each direction,
    /// and no triangle is degenerate (repeats a vertex). An empty mesh counts as closed.
    pub fn is_closed_manifold(&self) -> bool {
        self.directed_edges().is_some_and(|edges| {
            edges
                .iter()
                .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
        })
    }

    /// Number of undirected edges (welded by position) used by exactly one triangle.
    pub fn boundary_edge_count(&self) -> usize {
        let weld = self.weld_map();
        let mut count: HashMap<(u32, u32), u32> = HashMap::new();
        for t in self.indices.chunks_exact(3) {
            let w = [t[0], t[1], t[2]].map(|i| weld.get(i as usize).copied().unwrap_or(i));
            for k in 0..3 {
                let (a, b) = (w[k], w[(k + 1) % 3]);
                if a != b {
                    *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
        }
        count.values().filter(|&&n| n == 1).count()
    }

    /// Replaces `normals` with smooth vertex normals, each face's normal weighted by its angle at
    /// the vertex (so the result does not depend on how polygons were triangulated). Vertices
    /// sharing a position share a normal, so uv seams do not show as creases. Vertices on no
    /// (non-degenerate) triangle get +y.
    pub fn compute_smooth_normals(&mut self) {
        let weld = self.weld_map();
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in self.triangles() {
            let Some(p) = self.corners(t) else { continue };
            let Some(face_n) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() else {
                continue;
            };
            for k in 0..3 {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let angle = a.angle_between(b);
                let slot = t
                    .get(k)
                    .and_then(|&i| weld.get(i))
                    .and_then(|&w| acc.get_mut(w as usize));
                if let (Some(slot), true) = (slot, angle.is_finite()) {
                    *slot += face_n * angle;
                }
            }
        }
        self.normals = weld
            .iter()
            .map(|&w| {
                acc.get(w as usize)
                    .copied()
                    .unwrap_or(Vec3::ZERO)
                    .try_normalize()
                    .unwrap_or(Vec3::Y)
            })
            .collect();
    }

    /// Makes every normal unit length; zero or non-finite ones are recomputed smoothly.
    pub fn normalize_normals(&mut self) {
        if self.normals.len() != self.positions.len() {
            return self.compute_smooth_normals();
        }
        let mut smooth: Option<Vec<Vec3>> = None;
        for i in 0..self.normals.len() {
            let Some(n) = self.normals.get(i).copied() else {
                continue;
            };
            let fixed = match n.try_normalize() {
                Some(u) => u,
                None => {
                    let s = smooth.get_or_insert_with(|| {
                        let mut m = self.clone();
                        m.compute_smooth_normals();
                        m.normals
                    });
                    s.get(i).copied().unwrap_or(Vec3::Y)
                }
            };
            if let Some(slot) = self.normals.get_mut(i) {
                *slot = fixed;
            }
        }
    }

    /// Computes `tangents` from positions, normals and uvs (per-vertex sums of per-triangle uv
    /// derivatives, Gram-Schmidt against the normal). Where the uvs give no direction (missing or
    /// degenerate uvs), any unit tangent orthogonal to the normal is used with w = +1.
    /// Requires `normals` to be set and unit length.
    pub fn compute_tangents(&mut self) {
        let n = self.positions.len();
        let mut tan = vec![Vec3::ZERO; n];
        let mut bitan = vec![Vec3::ZERO; n];
        if self.uvs.len() == n {
            for t in self.triangles() {
                let (Some([p0, p1, p2]), Some(u0), Some(u1), Some(u2)) = (
                    self.corners(t),
                    self.uvs.get(t[0]),
                    self.uvs.get(t[1]),
                    self.uvs.get(t[2]),
                ) else {
                    continue;
                };
                let (e1, e2) = (p1 - p0, p2 - p0);
                // Bitangent toward −v: differentiate with v flipped.
                let (d1, d2) = ((*u1 - *u0) * Vec2::new(1.0, -1.0), (*u2 - *u0) * Vec2::new(1.0, -1.0));
                let det = d1.x * d2.y - d2.x * d1.y;
                if !det.is_finite() || det.abs() < 1e-12 {
                    continue;
                }
                let t_dir = (e1 * d2.y - e2 * d1.y) / det;
                let b_dir = (e2 * d1.x - e1 * d2.x) / det;
                // Weight by triangle area in 3D so slivers do not dominate.
                let w = 0.5 * e1.cross(e2).length();
                let (t_dir, b_dir) = (t_dir.normalize_or_zero() * w, b_dir.normalize_or_zero() * w);
                for i in t {
                    if let (Some(ts), Some(bs)) = (tan.get_mut(i), bitan.get_mut(i)) {
                        *ts += t_dir;
                        *bs += b_dir;
                    }
                }
            }
        }
        self.tangents = (0..n)
            .map(|i| {
                let nrm = self.normals.get(i).copied().unwrap_or(Vec3::Y);
                let t = tan.get(i).copied().unwrap_or(Vec3::ZERO);
                let b = bitan.get(i).copied().unwrap_or(Vec3::ZERO);
                match (t - nrm * nrm.dot(t)).try_normalize() {
                    Some(t) => {
                        let w = if nrm.cross(t).dot(b) < 0.0 { -1.0 } else { 1.0 };
                        t.extend(w)
                    }
                    None => nrm.any_orthonormal_vector().extend(1.0),
                }
            })
            .collect();
    }

    /// Fills missing attributes: zero uvs, smooth normals (or normalises given ones), tangents.
    pub fn complete_attributes(&mut self) {
        if self.uvs.len() != self.positions.len() {
            self.uvs = vec![Vec2::ZERO; self.positions.len()];
        }
        self.normalize_normals();
        self.compute_tangents();
    }

    /// This mesh under `m`: positions as points, normals by the inverse transpose, tangents by
    /// `m` (re-orthogonalised). A mirroring `m` (negative determinant) reverses every triangle so
    /// front faces stay counter-clockwise from outside, and flips the bitangent sign.
    pub fn transformed(&self, m: &Mat4) -> Mesh {
        let lin = Mat3::from_mat4(*m);
        let det = lin.determinant();
        let normal_m = if det.abs() > f32::MIN_POSITIVE {
            lin.inverse().transpose()
        } else {
            lin
        };
        let flip = det < 0.0;
        let normals: Vec<Vec3> = self
            .normals
            .iter()
            .map(|&n| (normal_m * n).try_normalize().unwrap_or(n))
            .collect();
        let tangents = self
            .tangents
            .iter()
            .zip(normals.iter().chain(std::iter::repeat(&Vec3::Y)))
            .map(|(t, &n)| {
                let d = lin * t.truncate();
                let d = (d - n * n.dot(d))
                    .try_normalize()
                    .unwrap_or_else(|| n.any_orthonormal_vector());
                d.extend(if flip { -t.w } else { t.w })
            })
            .collect();
        let mut indices = self.indices.clone();
        if flip {
            for tri in indices.chunks_exact_mut(3) {
                tri.swap(1, 2);
            }
        }
        Mesh {
            positions: self.positions.iter().map(|&p| m.transform_point3(p)).collect(),
            normals,
            uvs: self.uvs.clone(),
            tangents,
            indices,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Checks the invariants every finished mesh must satisfy.
    pub(crate) fn assert_well_formed(m: &Mesh) {
        m.validate("test").unwrap();
        for (i, (n, t)) in m.normals.iter().zip(&m.tangents).enumerate() {
            assert!((n.length() - 1.0).abs() < 1e-4, "normal {i} = {n}");
            assert!((t.truncate().length() - 1.0).abs() < 1e-4, "tangent {i} = {t}");
            assert!(n.dot(t.truncate()).abs() < 1e-4, "tangent {i} not orthogonal");
            assert!(t.w == 1.0 || t.w == -1.0, "tangent {i} w = {}", t.w);
        }
    }

    fn tetrahedron() -> Mesh {
        let mut m = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            indices: vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
            ..Default::default()
        };
        m.complete_attributes();
        m
    }

    #[test]
    fn tetrahedron_is_closed_and_open_when_a_face_is_removed() {
        let mut m = tetrahedron();
        assert_well_formed(&m);
        assert!(m.is_closed_manifold());
        assert_eq!(m.boundary_edge_count(), 0);
        m.indices.truncate(9);
        assert!(!m.is_closed_manifold());
        assert_eq!(m.boundary_edge_count(), 3);
    }

    #[test]
    fn inconsistent_orientation_is_not_manifold() {
        let mut m = tetrahedron();
        m.indices.swap(10, 11);
        assert!(!m.is_closed_manifold());
    }

    #[test]
    fn smooth_normals_point_outward() {
        let m = tetrahedron();
        let centre = Vec3::splat(0.25);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(n.dot(*p - centre) > 0.0);
        }
    }

    #[test]
    fn validate_names_bad_vertex_and_triangle() {
        let mut m = tetrahedron();
        m.positions[2].y = f32::NAN;
        let e = m.validate("x.obj").unwrap_err();
        assert_eq!(e.field, "vertex 2");
        let mut m = tetrahedron();
        m.indices[4] = 9;
        let e = m.validate("x.obj").unwrap_err();
        assert_eq!(e.field, "triangle 1");
        assert!(
            e.to_string()
                .starts_with("x.obj: triangle 1: vertex index 9 out of range"),
            "{e}"
        );
    }

    #[test]
    fn transformed_keeps_invariants_and_handles_mirroring() {
        let m = tetrahedron();
        let xf = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 0.5, 1.0),
            glam::Quat::from_rotation_y(0.7),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let t = m.transformed(&xf);
        assert_well_formed(&t);
        assert!(t.is_closed_manifold());
        let mirror = m.transformed(&Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        assert_well_formed(&mirror);
        assert!(mirror.is_closed_manifold());
        // Still outward after mirroring: each face normal (from winding) agrees with vertex normals.
        for tri in mirror.triangles() {
            let [a, b, c] = tri.map(|i| mirror.positions[i]);
            let face_n = (b - a).cross(c - a);
            let avg: Vec3 = tri.iter().map(|&i| mirror.normals[i]).sum();
            assert!(face_n.dot(avg) > 0.0);
        }
    }
}
