//! Per-vertex transfer samples shadows at the receivers' vertices only: a shadow narrower than
//! the vertex spacing falls between vertices and is blurred or missed. One warning line per
//! receiver whose vertices are too far apart for the smallest object that can shadow it.

use glam::Vec3;

/// One object as the check sees it: its name and its triangles in world space.
pub struct Object {
    pub name: String,
    pub triangles: Vec<[Vec3; 3]>,
}

impl Object {
    /// The side of a square of the mean triangle's doubled area: the spacing of its vertices
    /// (the side of a quad split in two).
    fn vertex_spacing(&self) -> f32 {
        let area: f32 = self
            .triangles
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length())
            .sum();
        (2.0 * area / self.triangles.len().max(1) as f32).sqrt()
    }

    /// The largest side of its bounds: about the width of its shadow's core.
    pub fn extent(&self) -> f32 {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in self.triangles.iter().flatten() {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if lo.is_finite() {
            (hi - lo).max_element()
        } else {
            0.0
        }
    }
}

/// Vertices per shadow width below which the shadow is undersampled.
const VERTICES_ACROSS: f32 = 2.0;

/// Per object, the vertex spacing its shadows need: half the extent of the smallest other
/// object that can shadow it (`None` where no other object has an extent), and that object.
pub fn needed_spacing(objects: &[Object]) -> Vec<Option<(f32, usize)>> {
    (0..objects.len())
        .map(|i| {
            let (j, o) = objects
                .iter()
                .enumerate()
                .filter(|(j, o)| *j != i && o.extent() > 0.0)
                .min_by(|a, b| a.1.extent().total_cmp(&b.1.extent()))?;
            Some((o.extent() / VERTICES_ACROSS, j))
        })
        .collect()
}

/// The receivers whose vertices are farther apart than half the smallest other object's extent,
/// each as one line naming both and the spacing that would hold its shadow.
pub fn undersampled(objects: &[Object]) -> Vec<String> {
    let mut out = Vec::new();
    for (r, need) in objects.iter().zip(needed_spacing(objects)) {
        let Some((want, j)) = need else { continue };
        let spacing = r.vertex_spacing();
        if spacing > want {
            let o = &objects[j];
            out.push(format!(
                "object {:?}'s vertices are {spacing:.3} m apart, more than half the {:.3} m of object {:?} that can shadow it: its per-vertex transfer blurs or misses that shadow (subdivide {:?} to {want:.3} m or finer)",
                r.name,
                o.extent(),
                o.name,
                r.name
            ));
        }
    }
    out
}

/// The longest edge a receiver may keep so that every object's shadow is held (half the
/// smallest object's extent, two significant digits), and that object; `None` with fewer than
/// two objects.
pub fn max_edge(objects: &[Object]) -> Option<(f64, usize)> {
    if objects.iter().filter(|o| o.extent() > 0.0).count() < 2 {
        return None;
    }
    let (j, o) = (objects.iter().enumerate())
        .filter(|(_, o)| o.extent() > 0.0)
        .min_by(|a, b| a.1.extent().total_cmp(&b.1.extent()))?;
    Some((
        crate::lighting::plan::round2(f64::from(o.extent() / VERTICES_ACROSS)),
        j,
    ))
}
