//! The clustered method's CPU side: the camera recovered from the view-projection, the cone's
//! bounding sphere, ranges, and the grid's boxes covering the view.

use glam::{Mat4, Vec3};

use super::assign::{self, block, cone_sphere, decompose, froxel_bounds, range, LightVolume};
use super::config::Config;
use crate::gpu_scene::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_POINT};
use crate::scene::Camera;

fn camera() -> Camera {
    Camera { position: Vec3::new(1.0, 4.0, 6.0), target: Vec3::new(-1.0, 0.0, -2.0), up: Vec3::Y, fov_y_deg: 55.0, near: 0.1 }
}

#[test]
fn the_camera_is_recovered_from_the_view_projection() {
    let cam = camera();
    let aspect = 4.0 / 3.0;
    let (view, sx, sy, near) = decompose(&cam.view_projection(aspect).to_cols_array()).unwrap();
    let f = 1.0 / (0.5 * cam.fov_y_deg.to_radians()).tan();
    assert!((near - cam.near).abs() < 1e-5 && (sx - aspect / f).abs() < 1e-5 && (sy - 1.0 / f).abs() < 1e-5, "{near} {sx} {sy}");
    assert!(view.abs_diff_eq(cam.view_matrix(), 1e-5), "{view} vs {}", cam.view_matrix());
    assert!(decompose(&Mat4::IDENTITY.to_cols_array()).is_none());
}

#[test]
fn the_cone_sphere_holds_the_cut_cone() {
    let apex = Vec3::new(0.5, 2.0, -1.0);
    let axis = Vec3::new(0.3, -1.0, 0.2).normalize();
    let side = axis.any_orthonormal_vector();
    for outer_deg in [5.0f32, 30.0, 44.0, 46.0, 60.0, 89.0, 90.0] {
        let (c, r) = cone_sphere(apex, axis, outer_deg.to_radians().cos(), 3.0);
        for k in 0..=20 {
            let angle = outer_deg.to_radians() * k as f32 / 20.0;
            for t in [0.0, 0.5, 1.0] {
                let p = apex + (axis * angle.cos() + side * angle.sin()) * 3.0 * t;
                assert!((p - c).length() <= r * (1.0 + 1e-5), "outer {outer_deg}: {p} outside ({c}, {r})");
            }
        }
        // Never larger than the plain sphere about the apex.
        assert!(r <= 3.0 + 1e-6, "{outer_deg}: {r}");
    }
}

#[test]
fn ranges_come_from_the_radius_or_the_cutoff() {
    let point = GpuLight { position: [0.0, 0.0, 0.0, LIGHT_POINT], direction: [0.0; 4], intensity: [4.0, 1.0, 2.0, 0.0], cone: [0.0; 4] };
    assert_eq!(range(&point, 2.5, 0.01), 2.5);
    assert!((range(&point, 0.0, 0.01) - 20.0).abs() < 1e-4);
    let dark = GpuLight { intensity: [0.0; 4], ..point };
    assert_eq!(range(&dark, 0.0, 0.01), 0.0);
    let sun = GpuLight { position: [0.0, 0.0, 0.0, LIGHT_DIRECTIONAL], ..point };
    assert!(range(&sun, 0.0, 0.01).is_infinite());
    let v = assign::light_volumes(&[dark, sun], &[], 0.01, &Mat4::IDENTITY);
    assert!(v[0].sphere[3] < 0.0 && v[1].sphere[3].is_infinite());
}

/// Every point the camera sees between the near plane and the far depth lies in the box of the
/// cluster its pixel and depth select (the shader's `cluster_at`).
#[test]
fn the_cluster_boxes_cover_the_view() {
    let cam = camera();
    let config = Config { tiles: [7, 5], slices: 9, ..Config::default() };
    let (w, h) = (70u32, 50u32);
    let vp = cam.view_projection(w as f32 / h as f32).to_cols_array();
    let b = block(&config, &vp, w, h, 30.0, 0).unwrap();
    let view = Mat4::from_cols_array(&b.view);
    for j in (0..h).step_by(3) {
        for i in (0..w).step_by(3) {
            let (o, d) = cam.pixel_center_ray(i, j, w, h);
            for t in [0.2f32, 1.0, 4.0, 12.0, 29.0] {
                let p = view.transform_point3(o + d * t);
                let depth = -p.z;
                if !(b.depth[0]..b.depth[1]).contains(&depth) {
                    continue;
                }
                let x = ((i as f32 + 0.5) * 7.0 / w as f32) as u32;
                let y = ((j as f32 + 0.5) * 5.0 / h as f32) as u32;
                let k = ((depth / b.depth[0]).ln() * b.depth[3]).floor().clamp(0.0, 8.0) as u32;
                let (min, max) = froxel_bounds(&b, assign::cluster_index(&b, x, y, k));
                assert!(p.cmpge(min).all() && p.cmple(max).all(), "pixel ({i},{j}) t {t}: {p} outside {min}..{max}");
                let touching = LightVolume { sphere: p.extend(0.0).into(), range: [0.0; 4] };
                assert!(assign::reaches_column(&b, x, y, &touching), "pixel ({i},{j}) t {t}: a point in the column is not reached");
            }
        }
    }
}
