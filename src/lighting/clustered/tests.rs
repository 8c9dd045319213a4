//! The clustered method's CPU side: the camera recovered from the view-projection, the cone's
//! bounding sphere, ranges, and the grid's boxes covering the view.

use glam::{Mat4, Vec3};

use super::assign::{self, block, cone_sphere, decompose, froxel_bounds, range, LightVolume};
use super::config::Config;
use crate::gpu_scene::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT};
use crate::scene::Camera;
use crate::world::level_gen::Rng;

fn camera() -> Camera {
    Camera {
        position: Vec3::new(1.0, 4.0, 6.0),
        target: Vec3::new(-1.0, 0.0, -2.0),
        up: Vec3::Y,
        fov_y_deg: 55.0,
        near: 0.1,
    }
}

#[test]
fn the_camera_is_recovered_from_the_view_projection() {
    let cam = camera();
    let aspect = 4.0 / 3.0;
    let (view, sx, sy, near) = decompose(&cam.view_projection(aspect).to_cols_array()).unwrap();
    let f = 1.0 / (0.5 * cam.fov_y_deg.to_radians()).tan();
    assert!(
        (near - cam.near).abs() < 1e-5 && (sx - aspect / f).abs() < 1e-5 && (sy - 1.0 / f).abs() < 1e-5,
        "{near} {sx} {sy}"
    );
    assert!(
        view.abs_diff_eq(cam.view_matrix(), 1e-5),
        "{view} vs {}",
        cam.view_matrix()
    );
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
                assert!(
                    (p - c).length() <= r * (1.0 + 1e-5),
                    "outer {outer_deg}: {p} outside ({c}, {r})"
                );
            }
        }
        // Never larger than the plain sphere about the apex.
        assert!(r <= 3.0 + 1e-6, "{outer_deg}: {r}");
    }
}

#[test]
fn ranges_come_from_the_radius_or_the_cutoff() {
    let point = GpuLight {
        position: [0.0, 0.0, 0.0, LIGHT_POINT],
        direction: [0.0; 4],
        intensity: [4.0, 1.0, 2.0, 0.0],
        cone: [0.0; 4],
    };
    assert_eq!(range(&point, 2.5, 0.01), 2.5);
    assert!((range(&point, 0.0, 0.01) - 20.0).abs() < 1e-4);
    let dark = GpuLight {
        intensity: [0.0; 4],
        ..point
    };
    assert_eq!(range(&dark, 0.0, 0.01), 0.0);
    let sun = GpuLight {
        position: [0.0, 0.0, 0.0, LIGHT_DIRECTIONAL],
        ..point
    };
    assert!(range(&sun, 0.0, 0.01).is_infinite());
    let v = assign::light_volumes(&[dark, sun], &[], 0.01, &Mat4::IDENTITY);
    assert!(v[0].sphere[3] < 0.0 && v[1].sphere[3].is_infinite());
}

/// Every point the camera sees between the near plane and the far depth lies in the box of the
/// cluster its pixel and depth select (the shader's `cluster_at`).
#[test]
fn the_cluster_boxes_cover_the_view() {
    let cam = camera();
    let config = Config {
        tiles: [7, 5],
        slices: 9,
        ..Config::default()
    };
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
                assert!(
                    p.cmpge(min).all() && p.cmple(max).all(),
                    "pixel ({i},{j}) t {t}: {p} outside {min}..{max}"
                );
                let touching = LightVolume {
                    sphere: p.extend(0.0).into(),
                    ..LightVolume::default()
                };
                assert!(
                    assign::reaches_column(&b, x, y, &touching),
                    "pixel ({i},{j}) t {t}: a point in the column is not reached"
                );
            }
        }
    }
}

/// A spot light as `light_volumes` builds it (view = world), from `apex` along `axis` with an
/// outer half-angle of `outer_deg` and `range`.
fn spot_volume(apex: Vec3, axis: Vec3, outer_deg: f32, range: f32) -> LightVolume {
    let cos_outer = outer_deg.to_radians().cos();
    let spot = GpuLight {
        position: apex.extend(LIGHT_SPOT).into(),
        direction: axis.extend(0.0).into(),
        intensity: [1.0; 4],
        cone: [1.0, cos_outer, 0.0, 0.0],
    };
    assign::light_volumes(&[spot], &[range], 0.01, &Mat4::IDENTITY)[0]
}

/// The cone test is conservative: no box holding a point of the cut cone is culled, for
/// half-angles from 3° to 170° and boxes from 2 cm to 3 m, the box's points sampled on a 7³
/// grid. And it culls: without it, a good share of the boxes near the cone but outside it
/// would be kept.
#[test]
fn the_cone_test_keeps_every_box_the_cut_cone_reaches() {
    let mut rng = Rng::new(7);
    let mut rand = move || rng.unit() as f32;
    let (mut reached, mut culled_outside, mut outside) = (0, 0, 0);
    for case in 0..400 {
        let apex = Vec3::new(rand() * 4.0 - 2.0, rand() * 4.0 - 2.0, rand() * 4.0 - 2.0);
        let axis = Vec3::new(rand() - 0.5, rand() - 0.5, rand() - 0.5).normalize();
        let outer_deg = [3.0, 15.0, 30.0, 45.0, 60.0, 89.0, 90.0, 120.0, 170.0][case % 9];
        let range = 0.5 + 4.0 * rand();
        let volume = spot_volume(apex, axis, outer_deg, range);
        for _ in 0..20 {
            let half = Vec3::splat(0.01 + 1.5 * rand() * rand());
            let centre = apex + Vec3::new(rand() - 0.5, rand() - 0.5, rand() - 0.5) * 2.5 * range;
            let (min, max) = (centre - half, centre + half);
            let inside_cut_cone = |p: Vec3| {
                let d = p - apex;
                d.length() <= range && d.dot(axis) >= d.length() * outer_deg.to_radians().cos()
            };
            let grid = (0..7 * 7 * 7)
                .map(|k| min + (max - min) * Vec3::new((k % 7) as f32, (k / 7 % 7) as f32, (k / 49) as f32) / 6.0);
            let hits = grid.clone().any(inside_cut_cone) || inside_cut_cone(centre);
            let sphere_only = LightVolume {
                axis: [0.0, 0.0, 0.0, -1.0],
                ..volume
            };
            let kept = assign::touches(&volume, min, max);
            if hits {
                reached += 1;
                assert!(kept, "case {case}: a box at {centre} (half {half}) holds a point of the cone ({outer_deg}°, range {range}) and was culled");
            } else if assign::touches(&sphere_only, min, max) {
                outside += 1;
                culled_outside += usize::from(!kept);
            }
        }
    }
    assert!(
        reached > 500 && outside > 500,
        "{reached} boxes in reach, {outside} outside the cone but in its sphere"
    );
    assert!(
        culled_outside * 3 > outside,
        "the cone test culled {culled_outside} of {outside} boxes outside the cone"
    );
}

/// A 30° spot 4 m above a floor, aimed straight down with a 7 m range: its bounding sphere
/// covers a disc of 4 m radius on the floor, its cone one of 2.3 m. A floor box 3.5 m from
/// the axis lies in the sphere but outside the cone, and is culled; one 2 m out is kept.
#[test]
fn a_spot_light_is_not_assigned_beside_its_cone() {
    let volume = spot_volume(Vec3::new(0.0, 4.0, 0.0), -Vec3::Y, 30.0, 7.0);
    let floor_box = |x: f32| (Vec3::new(x - 0.25, -0.05, -0.25), Vec3::new(x + 0.25, 0.05, 0.25));
    let (min, max) = floor_box(3.5);
    let sphere_only = LightVolume {
        axis: [0.0, 0.0, 0.0, -1.0],
        ..volume
    };
    assert!(
        assign::touches(&sphere_only, min, max),
        "the bounding sphere reaches the box beside the cone"
    );
    assert!(
        !assign::touches(&volume, min, max),
        "a box beside the cone was assigned the spot light"
    );
    let (min, max) = floor_box(2.0);
    assert!(
        assign::touches(&volume, min, max),
        "a box in the cone's footprint lost the spot light"
    );
}

/// The assignment shader's limits are copies of the Rust ones (the config checks against these,
/// the shader's loops and shared masks are sized by its own).
#[test]
fn the_assignment_shader_has_the_same_limits() {
    let shader = include_str!("../../../glsl/clustered/assign.comp");
    for line in [
        format!("const uint MAX_LIGHTS = {}u;", super::MAX_LIGHTS),
        format!("const uint MAX_SLICES = {}u;", super::MAX_SLICES),
    ] {
        assert!(
            shader.lines().any(|l| l.trim() == line),
            "glsl/clustered/assign.comp lacks `{line}`"
        );
    }
    // The coarse pass strides its masks by MAX_LIGHTS / 32 words, as the assignment reads them,
    // and the coarse buffer is sized by the Rust COARSE.
    let coarse = include_str!("../../../glsl/clustered/coarse.comp");
    let line = format!("const uint MAX_LIGHTS = {}u;", super::MAX_LIGHTS);
    assert!(
        coarse.lines().any(|l| l.trim() == line),
        "glsl/clustered/coarse.comp lacks `{line}`"
    );
    let common = include_str!("../../../glsl/clustered/clusters.glsl");
    let line = format!("const uint COARSE = {}u;", super::COARSE);
    assert!(
        common.lines().any(|l| l.trim() == line),
        "glsl/clustered/clusters.glsl lacks `{line}`"
    );
}
