//! The near-clip volume of a light (Everitt & Kilgard 2002, "Practical and Robust Stenciled
//! Shadow Volumes for Hardware-Accelerated Rendering"): the hull of the light and the near
//! plane's rectangle, that is every segment from a point of the rectangle to the light (for a
//! directional light, every ray from it toward the light). A shadow volume contains a point of
//! the rectangle only if its triangle meets this hull, so when no casting triangle does, z-pass
//! counts exactly what z-fail counts, without the caps. The silhouette pass tests triangles
//! against these planes.

use glam::{Mat4, Vec3, Vec4};

/// The rectangle is grown by this factor about its centre, and each plane pushed out by
/// [`SLACK`] of the scene's scale, so rounding can only keep z-fail, never lose a volume.
const GROW: f32 = 1.05;
const SLACK: f32 = 1e-4;

/// The near-clip volume of `light` (homogeneous: `(position, 1)` or `(toward, 0)`) for a camera
/// with the infinite-far `view_proj` (near plane at depth 0). Its planes `(n, offset)`: a point
/// `p` lies outside when `n·p + offset > 0` for some plane. Five for a point light
/// (four through the light and a rectangle edge, and the rectangle's own), five for a
/// directional one (four along the direction, and the rectangle's). `None` when the hull is
/// too thin to bound (the light in the near plane, or a directional light along it); the caller
/// then keeps z-fail.
pub fn near_clip(view_proj: &[f32; 16], light: Vec4) -> Option<NearClip> {
    let inverse = Mat4::from_cols_array(view_proj).inverse();
    let corner = |x: f32, y: f32| {
        let h = inverse * Vec4::new(x, y, 0.0, 1.0);
        h.truncate() / h.w
    };
    let rect = [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ];
    if !rect.iter().all(|c| c.is_finite()) || !light.is_finite() {
        return None;
    }
    let centre = rect.iter().sum::<Vec3>() / 4.0;
    let rect = rect.map(|c| centre + (c - centre) * GROW);
    let size = (rect[2] - rect[0]).length();
    let point = light.w != 0.0;
    let position = light.truncate() / if point { light.w } else { 1.0 };
    let scale = 1.0 + centre.length().max(if point { position.length() } else { 0.0 });
    // A point inside the hull, by which each plane is turned to face out.
    let inside = if point {
        (rect.iter().sum::<Vec3>() + position) / 5.0
    } else {
        centre + position.normalize_or_zero() * size
    };
    let plane = |n: Vec3, on: Vec3| -> Option<Vec4> {
        // Thin when the normal is tiny beside the edges it came from.
        let n = n.try_normalize()?;
        let offset = -n.dot(on);
        let depth = n.dot(inside) + offset;
        if depth.abs() < 1e-3 * size {
            return None;
        }
        let n = if depth > 0.0 { -n } else { n };
        Some(n.extend(-n.dot(on) - SLACK * scale))
    };
    let mut planes = [Vec4::ZERO; 5];
    for k in 0..4 {
        let (a, b) = (rect[k], rect[(k + 1) % 4]);
        let across = if point { position - a } else { position };
        planes[k] = plane((b - a).cross(across), a)?;
    }
    planes[4] = plane((rect[1] - rect[0]).cross(rect[3] - rect[0]), rect[0])?;
    Some(NearClip {
        planes,
        corners: rect.map(|c| c.extend(SLACK * scale)),
    })
}

/// The near-clip volume as the silhouette pass takes it: its planes, and its rectangle's corners
/// (w: the slack by which a triangle's plane must clear them, in world units). A triangle
/// misses the hull when all of its corners lie outside one plane, or when the hull (the
/// corners, and the light) lies wholly on one side of the triangle's own plane: the second
/// catches the large floors and walls that straddle the hull's planes without meeting it.
#[derive(Clone, Copy, Debug)]
pub struct NearClip {
    pub planes: [Vec4; 5],
    pub corners: [Vec4; 4],
}

impl NearClip {
    /// The light, the planes and the corners, as the shader's `light_positions` reads them.
    pub fn with_light(&self, light: Vec4) -> [Vec4; 10] {
        let mut out = [light; 10];
        out[1..6].copy_from_slice(&self.planes);
        out[6..].copy_from_slice(&self.corners);
        out
    }

    /// CPU mirror of the silhouette pass's `misses_near_clip`: whether triangle `p` surely
    /// misses the hull of `light`.
    #[cfg(test)]
    pub fn misses(&self, light: Vec4, p: [Vec3; 3]) -> bool {
        let outside_plane = self
            .planes
            .iter()
            .any(|h| p.iter().all(|&v| h.truncate().dot(v) + h.w > 0.0));
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let side = |sign: f32| {
            let corners = self
                .corners
                .iter()
                .all(|c| sign * n.dot(c.truncate() - p[0]) > c.w * n.length());
            let apex = if light.w != 0.0 {
                sign * n.dot(light.truncate() / light.w - p[0]) > 0.0
            } else {
                sign * n.dot(light.truncate()) >= 0.0
            };
            corners && apex
        };
        outside_plane || side(1.0) || side(-1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    fn inside(hull: &NearClip, p: Vec3) -> bool {
        hull.planes.iter().all(|h| h.truncate().dot(p) + h.w <= 0.0)
    }

    fn view_proj() -> [f32; 16] {
        let camera = Camera {
            position: Vec3::new(0.0, 1.0, 4.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 60.0,
            near: 0.05,
        };
        camera.view_projection(16.0 / 9.0).to_cols_array()
    }

    fn near_rect(vp: &[f32; 16]) -> Vec<Vec3> {
        let inv = Mat4::from_cols_array(vp).inverse();
        let mut out = Vec::new();
        for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (0.3, -0.7)] {
            let h = inv * Vec4::new(x, y, 0.0, 1.0);
            out.push(h.truncate() / h.w);
        }
        out
    }

    #[test]
    fn the_hull_holds_every_segment_from_the_near_rectangle_to_the_light() {
        let vp = view_proj();
        let light = Vec3::new(2.0, 3.0, -1.0);
        let planes = near_clip(&vp, light.extend(1.0)).unwrap();
        for q in near_rect(&vp) {
            for t in [0.0, 0.01, 0.5, 0.99, 1.0] {
                assert!(inside(&planes, q.lerp(light, t)), "{q} t = {t}");
            }
            // Beyond the light, and behind the near plane, are outside.
            assert!(!inside(&planes, q.lerp(light, 1.2)));
            assert!(!inside(&planes, q.lerp(light, -0.5)));
        }
        // The ground under the camera, well away from the segments, is outside.
        assert!(!inside(&planes, Vec3::new(0.0, 0.0, 0.0)));
    }

    #[test]
    fn a_triangle_misses_the_hull_only_when_no_segment_crosses_it() {
        let vp = view_proj();
        let light = Vec3::new(2.0, 3.0, -1.0);
        let hull = near_clip(&vp, light.extend(1.0)).unwrap();
        let rect = near_rect(&vp);
        let small = |c: Vec3, r: f32| {
            [
                c + Vec3::new(-r, 0.0, -r),
                c + Vec3::new(r, 0.0, -r),
                c + Vec3::new(0.0, 0.0, r),
            ]
        };
        // Across a segment from the rectangle to the light (small and horizontal, or a wall).
        let mid = rect[4].lerp(light, 0.5);
        assert!(!hull.misses(light.extend(1.0), small(mid, 0.05)));
        assert!(!hull.misses(light.extend(1.0), small(mid, 50.0)));
        // A floor far larger than the hull, below it: it straddles every side plane, and its
        // own plane separates it.
        let floor = small(Vec3::new(0.0, -0.5, 0.0), 100.0);
        assert!(hull
            .planes
            .iter()
            .all(|h| floor.iter().any(|&v| h.truncate().dot(v) + h.w <= 0.0)));
        assert!(hull.misses(light.extend(1.0), floor));
        // A small triangle off to the side, and one beyond the light.
        assert!(hull.misses(light.extend(1.0), small(Vec3::new(-3.0, 1.0, 0.0), 0.1)));
        assert!(hull.misses(light.extend(1.0), small(rect[4].lerp(light, 1.5), 0.1)));
        // Under a directional light, the ground between the camera and the light's direction is
        // crossed by the rays from the rectangle: a ceiling above, not a floor below.
        let toward = Vec3::new(0.0, 1.0, 0.0);
        let sun = near_clip(&vp, toward.extend(0.0)).unwrap();
        assert!(!sun.misses(toward.extend(0.0), small(Vec3::new(0.0, 10.0, 4.0), 100.0)));
        assert!(sun.misses(toward.extend(0.0), floor));
    }

    #[test]
    fn a_directional_light_s_hull_runs_to_infinity_toward_it() {
        let vp = view_proj();
        let toward = Vec3::new(0.3, 1.0, 0.2).normalize();
        let planes = near_clip(&vp, toward.extend(0.0)).unwrap();
        for q in near_rect(&vp) {
            for t in [0.0, 1.0, 100.0, 1e4] {
                assert!(inside(&planes, q + toward * t), "{q} t = {t}");
            }
            assert!(!inside(&planes, q - toward * 0.5));
        }
        assert!(!inside(&planes, Vec3::ZERO));
    }

    #[test]
    fn a_light_in_the_near_plane_gives_no_hull() {
        let vp = view_proj();
        let rect = near_rect(&vp);
        let in_plane = rect[0] + (rect[1] - rect[0]) * 3.0;
        assert!(near_clip(&vp, in_plane.extend(1.0)).is_none());
        let along = (rect[1] - rect[0]).normalize();
        assert!(near_clip(&vp, along.extend(0.0)).is_none());
    }
}
