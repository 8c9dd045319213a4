//! Known-answer tests of the forward method, read back from the radiance target: every covered
//! pixel is compared with the closed form at the point the pixel's centre ray hits.

mod common;

use glam::Vec3;
use penumbra::forward::cpu::{shade, Surface};
use penumbra::image_io::HdrImage;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;

const W: u32 = 64;
const H: u32 = 48;

fn render(toml: &str) -> (HdrImage, Scene) {
    let scene = Scene::from_str(toml, "<test>", std::path::Path::new(".")).expect("test scene parses");
    let gpu = common::test_gpu();
    let mut r = Renderer::new(gpu, scene.clone(), None, (W, H), 1).unwrap();
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    (img, scene)
}

/// Where pixel (i, j)'s centre ray meets the plane y = 0, if it does within `half` of the origin.
fn hit_ground(scene: &Scene, i: u32, j: u32, half: f32) -> Option<Vec3> {
    let (o, d) = scene.camera.pixel_center_ray(i, j, W, H);
    if d.y >= 0.0 {
        return None;
    }
    let p = o + d * (-o.y / d.y);
    (p.x.abs() < half && p.z.abs() < half).then_some(p)
}

const CAMERA: &str = r#"
[camera]
position = [0.3, 2.5, 2.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 50
"#;

#[test]
fn lambertian_plane_under_directional_light() {
    let toml = format!(
        r#"{CAMERA}
[[materials]]
name = "grey"
albedo = [0.5, 0.25, 0.8]

[[objects]]
mesh = "plane"
size = [40, 40]
material = "grey"

[[lights]]
type = "directional"
direction = [-1.0, -2.0, -0.5]
irradiance = [3.0, 2.0, 1.0]
"#
    );
    let (img, scene) = render(&toml);
    let dir = Vec3::new(-1.0, -2.0, -0.5).normalize();
    let cos = Vec3::Y.dot(-dir);
    let albedo = Vec3::new(0.5, 0.25, 0.8);
    let expected = albedo / std::f32::consts::PI * Vec3::new(3.0, 2.0, 1.0) * cos;
    let mut covered = 0;
    for j in 0..H {
        for i in 0..W {
            if hit_ground(&scene, i, j, 19.0).is_none() {
                continue;
            }
            covered += 1;
            let p = img.get(i, j);
            for c in 0..3 {
                let rel = (p[c] - expected[c]).abs() / expected[c];
                assert!(rel <= 1e-3, "pixel ({i},{j}) channel {c}: {} vs {} (rel {rel})", p[c], expected[c]);
            }
        }
    }
    assert!(covered > (W * H / 2) as usize, "the plane covers most of the image ({covered} pixels)");
}

#[test]
fn point_light_falls_off_with_inverse_square() {
    let toml = format!(
        r#"{CAMERA}
[[materials]]
name = "white"
albedo = [0.9, 0.9, 0.9]

[[objects]]
mesh = "plane"
size = [6, 6]
material = "white"

[[lights]]
type = "point"
position = [0.2, 1.0, -0.3]
intensity = [10.0, 10.0, 10.0]
"#
    );
    let (img, scene) = render(&toml);
    let light = Vec3::new(0.2, 1.0, -0.3);
    let (mut near, mut far) = (f32::MAX, 0.0f32);
    for j in 0..H {
        for i in 0..W {
            // Skip the plane's border pixels, which the rasteriser may cover partly.
            let Some(p) = hit_ground(&scene, i, j, 2.9) else { continue };
            let d = light - p;
            let r2 = d.length_squared();
            let expected = 0.9 / std::f32::consts::PI * 10.0 * (d.y / r2.sqrt()) / r2;
            let got = img.get(i, j)[0];
            let rel = (got - expected).abs() / expected;
            assert!(rel <= 1e-3, "pixel ({i},{j}) at {p}: {got} vs {expected} (rel {rel})");
            near = near.min(r2);
            far = far.max(r2);
        }
    }
    // The check spans a real range of distances, so a wrong exponent could not pass.
    assert!(far / near > 4.0, "distance² range {near}..{far}");
}

#[test]
fn blinn_phong_highlight_position_and_value() {
    let toml = format!(
        r#"{CAMERA}
[[materials]]
name = "shiny"
albedo = [0.1, 0.1, 0.1]
specular = [0.6, 0.6, 0.6]
exponent = 64

[[objects]]
mesh = "plane"
size = [6, 6]
material = "shiny"

[[lights]]
type = "point"
position = [-0.4, 1.2, -0.6]
intensity = [5.0, 5.0, 5.0]
"#
    );
    let (img, scene) = render(&toml);
    let surface = Surface { albedo: Vec3::splat(0.1), specular: Vec3::splat(0.6), exponent: 64.0, emission: Vec3::ZERO };
    let light = penumbra::renderer::GpuLight {
        position: [-0.4, 1.2, -0.6, penumbra::renderer::LIGHT_POINT],
        direction: [0.0; 4],
        intensity: [5.0; 4],
        cone: [0.0; 4],
    };
    let (mut gpu_best, mut cpu_best) = ((0, 0, 0.0f32), (0, 0, 0.0f32));
    for j in 0..H {
        for i in 0..W {
            let Some(p) = hit_ground(&scene, i, j, 2.9) else { continue };
            let want = shade(p, Vec3::Y, scene.camera.position, &surface, &[light], Vec3::ZERO).x;
            let got = img.get(i, j)[0];
            assert!((got - want).abs() <= 1e-3 * want.max(1e-3), "pixel ({i},{j}): {got} vs {want}");
            if got > gpu_best.2 {
                gpu_best = (i, j, got);
            }
            if want > cpu_best.2 {
                cpu_best = (i, j, want);
            }
        }
    }
    assert_eq!((gpu_best.0, gpu_best.1), (cpu_best.0, cpu_best.1), "highlight pixel");
    // A real highlight: much brighter than the diffuse floor around it.
    assert!(gpu_best.2 > 10.0 * img.get(0, H - 1)[0], "highlight {} vs corner {}", gpu_best.2, img.get(0, H - 1)[0]);
}
