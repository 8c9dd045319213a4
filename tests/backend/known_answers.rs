//! Known-answer tests of the forward method, read back from the radiance target: every covered
//! pixel is compared with the closed form at the point the pixel's centre ray hits.

use crate::support as common;

use glam::Vec3;
use penumbra::lighting::brdf::{shade, Surface};
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

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
                assert!(
                    rel <= 1e-3,
                    "pixel ({i},{j}) channel {c}: {} vs {} (rel {rel})",
                    p[c],
                    expected[c]
                );
            }
        }
    }
    assert!(
        covered > (W * H / 2) as usize,
        "the plane covers most of the image ({covered} pixels)"
    );
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
            let Some(p) = hit_ground(&scene, i, j, 2.9) else {
                continue;
            };
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
    let surface = Surface {
        albedo: Vec3::splat(0.1),
        specular: Vec3::splat(0.6),
        exponent: 64.0,
        emission: Vec3::ZERO,
    };
    let light = penumbra::gpu_scene::GpuLight {
        position: [-0.4, 1.2, -0.6, penumbra::gpu_scene::LIGHT_POINT],
        direction: [0.0; 4],
        intensity: [5.0; 4],
        cone: [0.0; 4],
    };
    let (mut gpu_best, mut cpu_best) = ((0, 0, 0.0f32), (0, 0, 0.0f32));
    for j in 0..H {
        for i in 0..W {
            let Some(p) = hit_ground(&scene, i, j, 2.9) else {
                continue;
            };
            let want = shade(p, Vec3::Y, scene.camera.position, &surface, &[light], Vec3::ZERO).x;
            let got = img.get(i, j)[0];
            assert!(
                (got - want).abs() <= 1e-3 * want.max(1e-3),
                "pixel ({i},{j}): {got} vs {want}"
            );
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
    assert!(
        gpu_best.2 > 10.0 * img.get(0, H - 1)[0],
        "highlight {} vs corner {}",
        gpu_best.2,
        img.get(0, H - 1)[0]
    );
}

#[test]
fn spherical_light_is_exact_above_the_horizon_and_drawn_as_an_emitter() {
    let toml = format!(
        r#"{CAMERA}
[[materials]]
name = "white"
albedo = [0.7, 0.7, 0.7]

[[objects]]
mesh = "plane"
size = [6, 6]
material = "white"

[[lights]]
type = "sphere"
center = [0.3, 0.8, -0.2]
radius = 0.25
radiance = [20.0, 10.0, 5.0]
"#
    );
    let (img, scene) = render(&toml);
    let (c, r) = (Vec3::new(0.3, 0.8, -0.2), 0.25f32);
    let radiance = Vec3::new(20.0, 10.0, 5.0);
    let (mut ground, mut emitter) = (0, 0);
    for j in 0..H {
        for i in 0..W {
            let (o, d) = scene.camera.pixel_center_ray(i, j, W, H);
            // Ray–sphere: pixels looking at the light itself show its radiance (away from its rim).
            let oc = o - c;
            let (b, cc) = (oc.dot(d), oc.length_squared() - r * r);
            let disc = b * b - cc;
            if disc > 0.0 {
                if disc > 0.25 * r * r {
                    emitter += 1;
                    let p = img.get(i, j);
                    assert!(
                        (p[0] - 20.0).abs() < 1e-3 && (p[2] - 5.0).abs() < 1e-3,
                        "emitter pixel ({i},{j}): {p:?}"
                    );
                }
                continue;
            }
            let Some(p) = hit_ground(&scene, i, j, 2.9) else {
                continue;
            };
            // Irradiance from a uniform sphere wholly above the horizon: π·L·(R/d)²·cos θ.
            let to = c - p;
            let d2 = to.length_squared();
            let expected = 0.7 * radiance.x * r * r / d2 * (to.y / d2.sqrt());
            let got = img.get(i, j)[0];
            assert!(
                (got - expected).abs() <= 1e-3 * expected,
                "pixel ({i},{j}): {got} vs {expected}"
            );
            ground += 1;
        }
    }
    assert!(
        emitter > 4 && ground > 1000,
        "{emitter} emitter pixels, {ground} ground pixels"
    );
}

#[test]
fn albedo_and_normal_maps_modulate_lambert() {
    // A four-colour albedo map (sRGB) and a normal map tilting the normal 45° about z.
    let dir = common::temp_path("maps");
    std::fs::create_dir_all(&dir).unwrap();
    let texels = [
        [255u8, 255, 255, 255],
        [128, 128, 128, 255],
        [64, 64, 64, 255],
        [255, 0, 0, 255],
    ];
    // 8×8 texels in four uniform 4×4 quadrants, so bilinear filtering well inside a quadrant
    // returns that quadrant's colour exactly.
    let albedo = image::RgbaImage::from_fn(8, 8, |x, y| image::Rgba(texels[((y / 4) * 2 + x / 4) as usize]));
    albedo.save(dir.join("albedo.png")).unwrap();
    // Tangent space (x, y, z) = (sin 45°, 0, cos 45°) encoded as (n + 1)/2.
    let t = std::f32::consts::FRAC_1_SQRT_2;
    let enc = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    let normal = image::RgbaImage::from_pixel(2, 2, image::Rgba([enc(t), enc(0.0), enc(t), 255]));
    normal.save(dir.join("normal.png")).unwrap();
    let toml = format!(
        r#"{CAMERA}
[[materials]]
name = "textured"
albedo = [1.0, 1.0, 1.0]
albedo_map = "albedo.png"

[[materials]]
name = "bumped"
albedo = [0.5, 0.5, 0.5]
normal_map = "normal.png"

[[objects]]
mesh = "plane"
size = [2, 2]
material = "textured"
translate = [-1.05, 0, 0]

[[objects]]
mesh = "plane"
size = [2, 2]
material = "bumped"
translate = [1.05, 0, 0]

[[lights]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = [3.0, 3.0, 3.0]
"#
    );
    let scene = Scene::from_str(&toml, "<test>", &dir).expect("test scene parses");
    let gpu = common::test_gpu();
    let mut r = Renderer::new(gpu, scene.clone(), None, (W, H), 1).unwrap();
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    let srgb = |c: u8| {
        let c = c as f32 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let (mut textured, mut bumped) = (0, 0);
    for j in 0..H {
        for i in 0..W {
            // Both planes span z ∈ [−1, 1]; stay clear of their edges.
            let Some(p) = hit_ground(&scene, i, j, 2.0).filter(|p| p.z.abs() < 0.95) else {
                continue;
            };
            let got = img.get(i, j);
            if p.x < -0.1 && p.x > -2.0 {
                // uv spans [0, 1] over the plane (u along +x, v along +z); ×2 gives quadrant units.
                let (u, v) = ((p.x + 1.05) / 2.0 + 0.5, p.z / 2.0 + 0.5);
                let (u, v) = (u * 2.0, v * 2.0);
                let (fu, fv) = (u.fract(), v.fract());
                if !(0.3..0.7).contains(&fu) || !(0.3..0.7).contains(&fv) || u < 0.0 || v < 0.0 || u >= 2.0 || v >= 2.0
                {
                    continue;
                }
                let texel = texels[(v as usize) * 2 + u as usize];
                for c in 0..3 {
                    let expected = srgb(texel[c]) / std::f32::consts::PI * 3.0;
                    // 8-bit sRGB decoding in the sampler is approximate (lavapipe: 0.4% at 128).
                    assert!(
                        (got[c] - expected).abs() <= 6e-3 * expected.max(0.05),
                        "textured ({i},{j}) ch {c}: {} vs {expected}",
                        got[c]
                    );
                }
                textured += 1;
            } else if p.x > 0.1 && p.x < 2.0 {
                // The mapped normal is tilted 45° from the light: cos θ = cos 45° (to 8-bit precision).
                let expected = 0.5 / std::f32::consts::PI * 3.0 * t;
                assert!(
                    (got[0] - expected).abs() <= 1e-2 * expected,
                    "bumped ({i},{j}): {} vs {expected}",
                    got[0]
                );
                bumped += 1;
            }
        }
    }
    assert!(
        textured > 20 && bumped > 100,
        "{textured} textured and {bumped} bumped pixels checked"
    );
}

#[test]
fn constant_sky_lights_an_open_plane_with_rho_l_and_is_seen_behind_it() {
    let toml = format!(
        r#"{CAMERA}
[[materials]]
name = "grey"
albedo = [0.6, 0.4, 0.2]

[[objects]]
mesh = "plane"
size = [4, 4]
material = "grey"

[environment]
type = "constant"
radiance = [2.0, 1.5, 1.0]
"#
    );
    let (img, scene) = render(&toml);
    let sky = [2.0f32, 1.5, 1.0];
    let (mut ground, mut background) = (0, 0);
    for j in 0..H {
        for i in 0..W {
            let p = img.get(i, j);
            match hit_ground(&scene, i, j, 2.5) {
                Some(q) if q.x.abs() < 1.9 && q.z.abs() < 1.9 => {
                    // An unoccluded Lambertian surface under a uniform sky reflects ρ·L.
                    for (c, rho) in [0.6f32, 0.4, 0.2].into_iter().enumerate() {
                        assert!(
                            (p[c] - rho * sky[c]).abs() <= 1e-3 * rho * sky[c],
                            "ground ({i},{j}) ch {c}: {}",
                            p[c]
                        );
                    }
                    ground += 1;
                }
                None => {
                    assert_eq!(&p[..3], &sky, "sky pixel ({i},{j})");
                    background += 1;
                }
                _ => {}
            }
        }
    }
    assert!(
        ground > 500 && background > 50,
        "{ground} ground and {background} sky pixels"
    );
}
