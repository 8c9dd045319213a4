//! The reference path tracer against closed forms, on lavapipe with validation. Checks are in
//! units of the renderer's own standard-error image (see [`Agreement`]), plus known biases
//! (bounce truncation) and float rounding; estimators with no noise are thus checked to
//! rounding.

use crate::support as common;
use crate::support::reference as reference_support;

use std::path::Path;

use glam::Vec3;
use penumbra::environment::EnvironmentMap;
use penumbra::gpu_scene::punctual_lights;
use penumbra::lighting::brdf::{shade, Surface};
use penumbra::reference::{
    Batching, LightPaths, LightSelection, ReferenceImage, ReferenceOptions, ReferenceRenderer, Sampler, Settings,
    DEFAULT_BOUNCES,
};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;
use reference_support::{
    ground_point, hemispherical_reflectance, off_light_outline, pixel_average, polygon_irradiance,
    reflected_environment, rmse, Agreement,
};

fn scene_file(name: &str) -> Scene {
    Scene::from_file(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).expect("scene parses")
}

fn parse(toml: &str) -> Scene {
    Scene::from_str(toml, "<test>", Path::new(".")).expect("test scene parses")
}

fn settings(spp: u32, bounces: u32, paths: LightPaths, seed: u32) -> Settings {
    Settings {
        spp,
        bounces,
        paths,
        seed,
        batching: Batching::Adaptive,
        ..Settings::default()
    }
}

/// Renders each settings in turn on one validated device.
fn render(scene: &Scene, size: (u32, u32), runs: &[Settings]) -> Vec<ReferenceImage> {
    let mut r = ReferenceRenderer::new(common::test_gpu(), scene, size).expect("reference renderer");
    let images = runs
        .iter()
        .map(|s| r.render(s, &mut |_, _| {}).expect("render"))
        .collect();
    common::assert_clean(&r.gpu);
    images
}

#[test]
fn furnace_converges_to_the_geometric_series() {
    let scene = scene_file("furnace.toml");
    let m = &scene.materials[0];
    let (albedo, emission) = (m.albedo, m.emission);
    let bounces = 14;
    assert!(albedo.max_element().powi(bounces as i32) < 1e-4);
    // Without Russian roulette every furnace path carries exactly the truncated series, so the
    // check is to rounding; roulette would add all of the noise (see
    // russian_roulette_leaves_the_mean_unchanged for the furnace with it).
    let no_roulette = |s: Settings| Settings {
        roulette_after: None,
        ..s
    };
    let img = &render(
        &scene,
        (32, 32),
        &[no_roulette(settings(32, bounces, LightPaths::All, 7))],
    )[0];
    let want = emission / (Vec3::ONE - albedo);
    // The estimate keeps the first K + 2 terms E ρ^k of the series.
    let truncation = emission * albedo.powf(bounces as f32 + 2.0) / (Vec3::ONE - albedo);
    let mut furnace = Agreement::new("furnace");
    for j in 0..32 {
        for i in 0..32 {
            furnace.check(img, i, j, want, truncation);
        }
    }
    furnace.assert();
    // With too few bounces the missing tail must show: the test can see truncation.
    let short = &render(&scene, (8, 8), &[no_roulette(settings(4, 1, LightPaths::All, 7))])[0];
    let three_terms = emission * (Vec3::ONE + albedo + albedo * albedo);
    let mut truncated = Agreement::new("furnace with 1 bounce");
    truncated.check(short, 3, 3, three_terms, Vec3::ZERO);
    truncated.assert();
}

const SKY_CAMERA: &str = r#"
[camera]
position = [0.0, 2.0, 0.0]
target = [0.5, 0.0, -0.5]
fov_y_deg = 60
"#;

#[test]
fn planes_under_a_constant_sky() {
    // A surface under a sky of radiance L reflects L ∫ f cos dω: ρ L when Lambertian. A thin
    // plane that also transmits sees the sky below too, adding τ L. The glossy case checks the
    // Blinn-Phong lobe's importance sampling against quadrature of the BRDF itself.
    let sky = Vec3::new(1.0, 2.0, 0.5);
    let lambert = |albedo, transmittance| Surface {
        albedo,
        specular: Vec3::ZERO,
        exponent: 1.0,
        emission: transmittance,
    };
    let cases = [
        lambert(Vec3::new(0.2, 0.5, 0.9), Vec3::ZERO),
        lambert(Vec3::new(0.3, 0.1, 0.5), Vec3::new(0.6, 0.2, 0.1)),
        Surface {
            albedo: Vec3::new(0.2, 0.3, 0.1),
            specular: Vec3::new(0.5, 0.4, 0.3),
            exponent: 20.0,
            emission: Vec3::new(0.15, 0.2, 0.25),
        },
    ];
    // Lobes are chosen by luminance; each must be chosen often enough in 64 samples for the
    // sample variance to see it (a lobe never drawn leaves the mean low with a tiny s.e.).
    for case in cases {
        // `emission` carries the transmittance here (Surface has no such field).
        let (albedo, specular, transmittance) = (case.albedo, case.specular, case.emission);
        let surface = Surface {
            emission: Vec3::ZERO,
            ..case
        };
        let scene = parse(&format!(
            r#"{SKY_CAMERA}
[[materials]]
name = "ground"
albedo = [{}, {}, {}]
specular = [{}, {}, {}]
exponent = {}
transmittance = [{}, {}, {}]

[[objects]]
mesh = "plane"
size = 400
material = "ground"

[environment]
type = "constant"
radiance = [{}, {}, {}]
"#,
            albedo.x,
            albedo.y,
            albedo.z,
            specular.x,
            specular.y,
            specular.z,
            case.exponent,
            transmittance.x,
            transmittance.y,
            transmittance.z,
            sky.x,
            sky.y,
            sky.z
        ));
        let img = &render(&scene, (32, 32), &[settings(64, 4, LightPaths::All, 1)])[0];
        let mut sky_check = Agreement::new("plane under the sky");
        for j in 0..32 {
            for i in 0..32 {
                assert!(
                    ground_point(&scene, i as f32, j as f32, (32, 32), 150.0).is_some(),
                    "the plane fills the image"
                );
                if specular == Vec3::ZERO {
                    sky_check.check(img, i, j, (albedo + transmittance) * sky, Vec3::ZERO);
                } else {
                    let v = -scene.camera.pixel_center_ray(i, j, 32, 32).1;
                    let want = (hemispherical_reflectance(v, &surface) + transmittance) * sky;
                    sky_check.check(img, i, j, want, want * 2e-3);
                }
            }
        }
        sky_check.assert();
        if transmittance != Vec3::ZERO {
            let noisy = img.standard_error.pixels.iter().any(|p| p[0] > 0.0);
            assert!(noisy, "choosing between lobes is random, so the s.e. is not 0");
        }
    }
}

/// Shading normals tilted away from the true surface: a large plane (y = 0) whose vertex normals
/// all lean 40° toward +x, under a constant sky, seen from a camera low on the -x side looking
/// along +x, so that every camera ray arrives between the two planes (above the surface, behind
/// the shading normal). Both normals must be turned to the side the ray came from together: the
/// plane then reflects the part of the cosine lobe about the shading normal that lies above the
/// surface, ρ L (1 + cos α) / 2 (the lobe's projected solid angle above a plane at angle α,
/// π (1 + cos α) / 2), wherever it is seen from. Turning each normal on its own toward the ray
/// flips the shading normal under the surface and leaves ρ L (1 − cos α) / 2.
#[test]
fn shading_normals_tilted_from_the_surface_are_turned_with_it() {
    let alpha = 40f32.to_radians();
    let (sx, sy) = (alpha.sin(), alpha.cos());
    let obj = common::temp_path("tilted-normals.obj");
    let half = 20.0;
    std::fs::write(&obj, format!("v -{half} 0 -{half}\nv {half} 0 -{half}\nv {half} 0 {half}\nv -{half} 0 {half}\nvn {sx} {sy} 0\nf 1//1 3//1 2//1\nf 1//1 4//1 3//1\n")).expect("write obj");
    let sky = Vec3::new(1.0, 0.8, 0.6);
    let albedo = 0.6;
    let scene = parse(&format!(
        r#"
[camera]
position = [-8.0, 1.5, 0.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 30

[[materials]]
name = "m"
albedo = {albedo}

[[objects]]
mesh = "obj"
path = "{}"
material = "m"

[environment]
type = "constant"
radiance = [{}, {}, {}]
"#,
        obj.display(),
        sky.x,
        sky.y,
        sky.z
    ));
    let size = (24, 24);
    let img = &render(&scene, size, &[settings(64, 0, LightPaths::Direct, 5)])[0];
    let want = sky * albedo * (1.0 + alpha.cos()) / 2.0;
    let mut plane = Agreement::new("plane with tilted shading normals");
    for j in 0..size.1 {
        for i in 0..size.0 {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
            let on_plane = corners
                .iter()
                .all(|&(a, b)| ground_point(&scene, i as f32 + a, j as f32 + b, size, half - 0.5).is_some());
            if !on_plane {
                continue;
            }
            let (_, d) = scene.camera.pixel_center_ray(i, j, size.0, size.1);
            assert!(
                d.y < 0.0 && d.dot(Vec3::new(sx, sy, 0.0)) > 0.0,
                "the ray arrives between the planes"
            );
            plane.check(img, i, j, want, Vec3::ZERO);
        }
    }
    assert!(plane.pixels > 150, "{} pixels", plane.pixels);
    plane.assert();
}

const LIT_PLANE: &str = r#"
[camera]
position = [0.3, 2.5, 2.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 50
"#;

/// Direct light from punctual lights is the forward method's closed form (plus `extra`, for
/// what it does not model), box-filtered over each pixel, with every light visited at each
/// vertex and with one drawn per vertex; the only noise of the first is the pixel jitter.
fn check_punctual(material: &str, surface: Surface, lights: &str, extra: impl Fn(Vec3) -> Vec3) {
    check_punctual_with(
        material,
        surface,
        lights,
        extra,
        (32, 32),
        &[LightSelection::Every, LightSelection::One],
    );
}

fn check_punctual_with(
    material: &str,
    surface: Surface,
    lights: &str,
    extra: impl Fn(Vec3) -> Vec3,
    size: (u32, u32),
    selections: &[LightSelection],
) -> Vec<ReferenceImage> {
    let toml = format!("{LIT_PLANE}\n[[materials]]\nname = \"m\"\n{material}\n\n[[objects]]\nmesh = \"plane\"\nsize = 6\nmaterial = \"m\"\n{lights}");
    let scene = parse(&toml);
    let runs: Vec<Settings> = selections
        .iter()
        .map(|&light_selection| Settings {
            light_selection,
            ..settings(64, 0, LightPaths::Direct, 3)
        })
        .collect();
    let imgs = render(&scene, size, &runs);
    let gpu_lights = punctual_lights(&scene);
    let want: Vec<Option<Vec3>> = (0..size.0 * size.1)
        .map(|k| {
            let (i, j) = (k % size.0, k / size.0);
            pixel_average(i, j, 8, |x, y| {
                let p = ground_point(&scene, x, y, size, 3.0)?;
                Some(shade(p, Vec3::Y, scene.camera.position, &surface, &gpu_lights, Vec3::ZERO) + extra(p))
            })
        })
        .collect();
    for (img, selection) in imgs.iter().zip(selections) {
        let mut agreement = Agreement::new(if *selection == LightSelection::One {
            "punctual lights, one drawn per vertex"
        } else {
            "punctual lights, every one"
        });
        for (k, want) in want.iter().enumerate() {
            let Some(want) = *want else { continue };
            agreement.check(img, k as u32 % size.0, k as u32 / size.0, want, want * 1e-3);
        }
        assert!(
            agreement.pixels > (size.0 * size.1 * 2 / 5) as usize,
            "most pixels see the plane ({})",
            agreement.pixels
        );
        agreement.assert();
    }
    imgs
}

/// Drawing one punctual light per vertex and colour channel in proportion to its unshadowed
/// contribution: with nothing in the way every draw gives the full sum, so the noise is the
/// pixel jitter's alone, as when every light is visited (a uniform draw, or any draw not in
/// proportion, would multiply it). And 1,024 lights, a shadow ray each beyond what llvmpipe lets
/// one invocation loop, render in one ray a vertex to their closed-form sum.
#[test]
fn one_punctual_light_drawn_per_vertex_is_unbiased_and_follows_the_contribution() {
    let surface = Surface {
        albedo: Vec3::splat(0.6),
        specular: Vec3::splat(0.3),
        exponent: 16.0,
        emission: Vec3::ZERO,
    };
    let material = "albedo = 0.6\nspecular = 0.3\nexponent = 16";
    let mut lights = String::new();
    for k in 0..20 {
        let (x, z) = ((k % 5) as f32 * 0.8 - 1.6, (k / 5) as f32 * 0.8 - 1.2);
        // Coloured, so that a light can matter to one channel and hardly to another.
        let intensity = [
            0.3 + 0.25 * (k % 7) as f32,
            0.2 + 0.3 * (k % 3) as f32,
            0.05 + 0.4 * (k % 5 == 0) as u32 as f32,
        ];
        lights += &format!(
            "\n[[lights]]\ntype = \"point\"\nposition = [{x}, {}, {z}]\nintensity = {intensity:?}\n",
            0.6 + 0.1 * (k % 3) as f32
        );
    }
    let imgs = check_punctual_with(
        material,
        surface,
        &lights,
        |_| Vec3::ZERO,
        (16, 16),
        &[LightSelection::Every, LightSelection::One],
    );
    let (every, one) = (sample_variance(&imgs[0]), sample_variance(&imgs[1]));
    eprintln!("variance per sample: every light {every:.3e}, one drawn {one:.3e}");
    assert!(
        one <= every * 1.02 + 1e-12,
        "one light drawn in proportion adds no noise on an unshadowed plane: {one:.3e} against {every:.3e}"
    );

    let grid = "\n[[light_arrays]]\nname = \"rig\"\ntype = \"point\"\ngrid = [32, 1, 32]\nmin = [-3, 1.5, -3]\nmax = [3, 1.5, 3]\nintensity = 0.004\n";
    check_punctual_with(
        material,
        surface,
        grid,
        |_| Vec3::ZERO,
        (16, 16),
        &[LightSelection::Auto],
    );
}

/// Under shadows and with indirect light (Ridderhof 2002's slanted polygon under 25 white lights, and
/// its polygon over a plane under three coloured ones, where each channel draws its own light),
/// the light drawn per vertex renders the mean of visiting every light, pixel by pixel and over
/// the image, within the renders' own standard errors; weighting the drawn light by anything
/// but the inverse of its probability, or drawing for all channels by one, moves the means by
/// many standard errors.
#[test]
fn one_punctual_light_drawn_per_vertex_matches_every_light_under_shadows() {
    let size = (16, 16);
    for (name, lights) in [("many_slanted.toml", 25), ("many_polygon3.toml", 3)] {
        let scene = scene_file(name);
        assert_eq!(punctual_lights(&scene).len(), lights);
        let with = |light_selection, seed| Settings {
            light_selection,
            ..settings(128, 2, LightPaths::All, seed)
        };
        let imgs = render(
            &scene,
            size,
            &[
                with(LightSelection::Every, 1),
                with(LightSelection::One, 2),
                with(LightSelection::Auto, 1),
            ],
        );
        assert_eq!(imgs[0].mean, imgs[2].mean, "up to 32 lights auto visits every one");
        let (beyond_3, worst, image_z) = two_render_z(&imgs[0], &imgs[1], &vec![true; 256]);
        let cost = sample_variance(&imgs[1]) / sample_variance(&imgs[0]);
        eprintln!("{name}: {beyond_3} of 256 pixels beyond 3 s.e., worst z {worst:.2}, image mean z {image_z:?}; variance per sample one / every {cost:.2}");
        assert!(
            beyond_3 <= 5 && worst <= 6.0,
            "{name}: {beyond_3} pixels beyond 3 s.e., worst z {worst}"
        );
        assert!(
            image_z.iter().all(|z| z.abs() <= 4.0),
            "{name}: image means differ: z {image_z:?}"
        );
    }
}

#[test]
fn point_light_and_shadow_over_a_plane_direct_only() {
    // ρ/π I cos θ / r², and exactly 0 in the umbra of a box.
    let (light, intensity, albedo) = (Vec3::new(0.2, 1.0, -0.3), 10.0, 0.9);
    let (box_center, half) = (Vec3::new(0.5, 0.4, -0.2), 0.15);
    let toml = format!(
        "{LIT_PLANE}\n[[materials]]\nname = \"m\"\nalbedo = {albedo}\n\n[[objects]]\nmesh = \"plane\"\nsize = 6\nmaterial = \"m\"\n\n\
         [[objects]]\nmesh = \"box\"\nsize = {}\ntranslate = [{}, {}, {}]\nmaterial = \"m\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = [{}, {}, {}]\nintensity = {intensity}\n",
        2.0 * half,
        box_center.x,
        box_center.y,
        box_center.z,
        light.x,
        light.y,
        light.z
    );
    let scene = parse(&toml);
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(64, 0, LightPaths::Direct, 3)])[0];
    // Segment or ray against the box grown (or shrunk) by `grow`, for margins at silhouettes.
    let hits_box = |o: Vec3, d: Vec3, t_max: f32, grow: f32| {
        let h = Vec3::splat(half + grow);
        penumbra::raytrace::bvh::box_entry(
            box_center - h,
            box_center + h,
            o,
            penumbra::raytrace::bvh::safe_inverse(d),
            t_max,
        )
        .is_some()
    };
    let (mut lit, mut umbra) = (
        Agreement::new("lit by a point light"),
        Agreement::new("point light umbra"),
    );
    for j in 0..size.1 {
        for i in 0..size.0 {
            let (mut shadowed, mut unsure) = (0, false);
            let want = pixel_average(i, j, 8, |x, y| {
                let (o, d) = scene.camera.ray(x, y, size.0, size.1);
                let p = ground_point(&scene, x, y, size, 2.9)?;
                if hits_box(o, d, f32::MAX, 0.01) {
                    return None;
                }
                let to_light = light - p;
                let (blocked, maybe) = (hits_box(p, to_light, 1.0, -0.01), hits_box(p, to_light, 1.0, 0.01));
                unsure |= blocked != maybe;
                shadowed += blocked as u32;
                let r2 = to_light.length_squared();
                Some(Vec3::splat(if blocked {
                    0.0
                } else {
                    albedo / std::f32::consts::PI * intensity * (to_light.y / r2.sqrt()) / r2
                }))
            });
            let Some(want) = want else { continue };
            match shadowed {
                _ if unsure => {}
                0 => lit.check(img, i, j, want, want * 1e-3),
                64 => umbra.check(img, i, j, Vec3::ZERO, Vec3::ZERO),
                _ => {}
            }
        }
    }
    assert!(
        lit.pixels > 400 && umbra.pixels >= 4,
        "{} lit pixels, {} in the umbra",
        lit.pixels,
        umbra.pixels
    );
    lit.assert();
    umbra.assert();
}

#[test]
fn spot_directional_transmission_and_blinn_phong_direct_only() {
    let surface = Surface {
        albedo: Vec3::new(0.3, 0.2, 0.1),
        specular: Vec3::splat(0.5),
        exponent: 32.0,
        emission: Vec3::ZERO,
    };
    let lights = r#"
[[lights]]
type = "spot"
position = [-0.5, 2.0, 0.5]
target = [0.2, 0.0, -0.2]
intensity = [20, 15, 10]
inner_deg = 15
outer_deg = 30

[[lights]]
type = "directional"
direction = [-1.0, -2.0, -0.5]
irradiance = [1.0, 2.0, 3.0]

[[lights]]
type = "point"
position = [0.3, -0.8, 0.1]
intensity = [3, 6, 9]
"#;
    // The light under the plane reaches the viewer's side through diffuse transmission τ/π.
    let (transmittance, below, intensity) = (
        Vec3::new(0.2, 0.3, 0.4),
        Vec3::new(0.3, -0.8, 0.1),
        Vec3::new(3.0, 6.0, 9.0),
    );
    let through = |p: Vec3| {
        let d = below - p;
        transmittance / std::f32::consts::PI * intensity * (-d.y / d.length()) / d.length_squared()
    };
    check_punctual(
        "albedo = [0.3, 0.2, 0.1]\nspecular = 0.5\nexponent = 32\ntransmittance = [0.2, 0.3, 0.4]",
        surface,
        lights,
        through,
    );
}

const QUAD_OVER_PLANE: &str = r#"
[camera]
position = [1.5, 0.9, 2.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 60

[[materials]]
name = "m"
albedo = 0.7

[[objects]]
mesh = "plane"
size = 20
material = "m"

[[lights]]
type = "quad"
corner = [-0.4, 1.2, -0.3]
edge_u = [0.8, 0.0, 0.0]
edge_v = [0.0, 0.0, 0.6]
radiance = [5.0, 4.0, 3.0]
"#;

/// The plane's closed form at pixel (i, j) under QUAD_OVER_PLANE, box-filtered; None where the
/// camera sees the light.
fn quad_over_plane_want(scene: &Scene, i: u32, j: u32, size: (u32, u32)) -> Option<Vec3> {
    let (corner, u, v, radiance) = (
        Vec3::new(-0.4, 1.2, -0.3),
        Vec3::new(0.8, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.6),
        Vec3::new(5.0, 4.0, 3.0),
    );
    let verts = [corner, corner + u, corner + u + v, corner + v];
    pixel_average(i, j, 8, |x, y| {
        // The camera is below the light and may see it; those pixels are left out.
        let (o, d) = scene.camera.ray(x, y, size.0, size.1);
        let t = (corner.y - o.y) / d.y;
        let q = o + d * t;
        if t > 0.0 && (-0.5..=0.5).contains(&q.x) && (-0.4..=0.4).contains(&q.z) {
            return None;
        }
        let p = ground_point(scene, x, y, size, 9.0)?;
        Some(0.7 / std::f32::consts::PI * radiance * polygon_irradiance(p, Vec3::Y, &verts))
    })
}

#[test]
fn quad_light_over_a_plane_direct_only() {
    let scene = parse(QUAD_OVER_PLANE);
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(128, 0, LightPaths::Direct, 11)])[0];
    let mut plane = Agreement::new("plane under a quad light");
    for j in 0..size.1 {
        for i in 0..size.0 {
            if let Some(want) = quad_over_plane_want(&scene, i, j, size) {
                plane.check(img, i, j, want, want * 1e-3);
            }
        }
    }
    assert!(plane.pixels > 600, "{} pixels", plane.pixels);
    plane.assert();
}

/// Per pixel and channel of `wants` (pixel, closed form), over renders `imgs` of independent
/// seeds: the mean squared relative error of one render against the closed form; the mean of
/// z² for the seeds' average, z being its distance from the closed form over the standard error
/// that the seeds' scatter gives it (about 1 + 2/(seeds - 3) when unbiased); and the mean of the
/// reported relative variance of one render.
fn error_over_seeds(imgs: &[ReferenceImage], wants: &[((u32, u32), Vec3)]) -> (f64, f64, f64) {
    let n = imgs.len() as f64;
    let (mut mse, mut z2, mut reported, mut count) = (0.0, 0.0, 0.0, 0.0);
    for &((i, j), want) in wants {
        for c in 0..3 {
            let w = want[c] as f64;
            let xs: Vec<f64> = imgs.iter().map(|img| img.mean.get(i, j)[c] as f64).collect();
            let m = xs.iter().sum::<f64>() / n;
            let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
            mse += xs.iter().map(|x| ((x - w) / w).powi(2)).sum::<f64>() / n;
            z2 += (m - w).powi(2) / (var / n + (1e-4 * w).powi(2));
            reported += imgs
                .iter()
                .map(|img| (img.standard_error.get(i, j)[c] as f64 / w).powi(2))
                .sum::<f64>()
                / n;
            count += 1.0;
        }
    }
    (mse / count, z2 / count, reported / count)
}

/// The Sobol sampler against Lambert's closed form for a quad light over a plane (direct light
/// only, so the pixel point and the light point are all there is to draw): over six seeds its
/// renders scatter about the closed form and not about some other value (no bias), with a
/// fraction of the error of independent samples at the same count, and for both samplers the
/// standard-error image states that error (for Sobol, from the scatter of its replicates).
#[test]
fn sobol_sampler_is_unbiased_and_has_less_error_than_independent_samples() {
    let scene = parse(QUAD_OVER_PLANE);
    let size = (24, 24);
    let (seeds, spp) = (6, 32);
    let run = |sampler, seed| Settings {
        sampler,
        ..settings(spp, 0, LightPaths::Direct, seed)
    };
    let runs: Vec<Settings> = [Sampler::Independent, Sampler::Sobol]
        .into_iter()
        .flat_map(|s| (1..=seeds).map(move |seed| run(s, seed)))
        .collect();
    let imgs = render(&scene, size, &runs);
    let (independent, sobol) = imgs.split_at(seeds as usize);
    let mut wants = Vec::new();
    for j in 0..size.1 {
        for i in 0..size.0 {
            if let Some(want) = quad_over_plane_want(&scene, i, j, size) {
                wants.push(((i, j), want));
            }
        }
    }
    assert!(wants.len() > 300, "{} pixels", wants.len());
    let (mse_i, z2_i, reported_i) = error_over_seeds(independent, &wants);
    let (mse_s, z2_s, reported_s) = error_over_seeds(sobol, &wants);
    eprintln!("independent: relative MSE {mse_i:.3e}, mean z² {z2_i:.2}, reported {reported_i:.3e}");
    eprintln!("sobol: relative MSE {mse_s:.3e}, mean z² {z2_s:.2}, reported {reported_s:.3e}");
    for (name, z2) in [("independent", z2_i), ("sobol", z2_s)] {
        assert!(
            z2 < 3.0,
            "{name}: the seeds' average is {z2:.2} of its error² from the closed form: biased"
        );
    }
    assert!(
        mse_s * 4.0 < mse_i,
        "sobol's error {mse_s:.3e} should be well below independent samples' {mse_i:.3e}"
    );
    for (name, reported, mse) in [("independent", reported_i, mse_i), ("sobol", reported_s, mse_s)] {
        assert!(
            reported > 0.7 * mse && reported < 1.4 * mse,
            "{name}: the standard-error image's {reported:.3e} is not the error {mse:.3e}"
        );
    }
}

/// The Sobol sampler's replicate sums take 128 bytes a pixel: at 1100×1000 that is more than
/// lavapipe's maxStorageBufferRange (128 MiB), which a storage buffer could not bind; they are
/// image layers, and the render is clean under validation (`render` asserts it) with a standard
/// error where the light reaches.
#[test]
fn sobol_sampler_renders_past_a_storage_buffer_range() {
    let scene = parse(QUAD_OVER_PLANE);
    let size = (1100, 1000);
    let img = &render(
        &scene,
        size,
        &[Settings {
            sampler: Sampler::Sobol,
            ..settings(2, 0, LightPaths::Direct, 1)
        }],
    )[0];
    let (mean, se) = img.average();
    assert!(
        (0..3).all(|c| mean[c] > 0.0 && se[c].is_finite() && se[c] > 0.0),
        "mean {mean:?}, standard error {se:?}"
    );
}

/// With bounces (BSDF draws at every depth, light draws at every vertex) the Sobol sampler's
/// renders of the Cornell box agree pixel by pixel with a long render of independent samples,
/// and scatter less than independent samples of the same count.
#[test]
fn sobol_sampler_with_bounces_agrees_with_independent_samples() {
    let scene = scene_file("cornell.toml");
    let size = (16, 16);
    let (seeds, spp, long) = (6, 128, 1024);
    let mut runs = vec![settings(long, 3, LightPaths::All, 100)];
    runs.extend((1..=seeds).map(|seed| Settings {
        sampler: Sampler::Sobol,
        ..settings(spp, 3, LightPaths::All, seed)
    }));
    let imgs = render(&scene, size, &runs);
    let (truth, sobol) = (&imgs[0], &imgs[1..]);
    let n = seeds as f64;
    let (mut z2, mut mse_s, mut mse_i, mut count) = (0.0, 0.0, 0.0, 0.0);
    for j in 0..size.1 {
        for i in 0..size.0 {
            for c in 0..3 {
                let (t, se) = (truth.mean.get(i, j)[c] as f64, truth.standard_error.get(i, j)[c] as f64);
                let xs: Vec<f64> = sobol.iter().map(|img| img.mean.get(i, j)[c] as f64).collect();
                let m = xs.iter().sum::<f64>() / n;
                let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
                let weight = 1.0 / (t * t + 0.01);
                z2 += (m - t).powi(2) / (var / n + se * se);
                mse_s += var * weight;
                // An independent render of `spp` samples: the long render's variance per sample over spp.
                mse_i += se * se * long as f64 / spp as f64 * weight;
                count += 1.0;
            }
        }
    }
    let (z2, ratio) = (z2 / count, mse_i / mse_s);
    eprintln!("mean z² {z2:.2}; independent over sobol variance at {spp} spp: {ratio:.2}");
    assert!(
        z2 < 3.0,
        "sobol renders stand {z2:.2} error² from the long independent render: biased"
    );
    assert!(
        ratio > 1.3,
        "sobol's variance should be below independent samples' ({ratio:.2})"
    );
}

/// A ceiling of 100 small coloured quad lights over a plane: every light visited and one drawn
/// per vertex and channel (each at one sampled point) both give the sum of Lambert's polygon
/// formula over the lights, within their standard errors.
#[test]
fn many_quad_lights_every_one_or_one_drawn_per_vertex_give_the_polygon_formula() {
    let mut toml = String::from(
        "[camera]\nposition = [0.2, 1.2, 1.6]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 60\n\n[[materials]]\nname = \"m\"\nalbedo = 0.7\n\n[[objects]]\nmesh = \"plane\"\nsize = 20\nmaterial = \"m\"\n",
    );
    let mut quads = Vec::new();
    for k in 0..100 {
        let corner = Vec3::new(-3.0 + 0.6 * (k % 10) as f32, 2.0, -3.0 + 0.6 * (k / 10) as f32);
        let radiance = [
            Vec3::new(6.0, 1.0, 1.0),
            Vec3::new(1.0, 6.0, 1.0),
            Vec3::new(1.0, 1.0, 6.0),
            Vec3::new(3.0, 3.0, 3.0),
        ][k % 4];
        toml += &format!(
            "\n[[lights]]\ntype = \"quad\"\ncorner = [{}, {}, {}]\nedge_u = [0.2, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.2]\nradiance = [{}, {}, {}]\n",
            corner.x, corner.y, corner.z, radiance.x, radiance.y, radiance.z
        );
        quads.push((
            [
                corner,
                corner + Vec3::new(0.2, 0.0, 0.0),
                corner + Vec3::new(0.2, 0.0, 0.2),
                corner + Vec3::new(0.0, 0.0, 0.2),
            ],
            radiance,
        ));
    }
    let scene = parse(&toml);
    let size = (16, 16);
    let with = |light_selection, seed| Settings {
        light_selection,
        ..settings(64, 0, LightPaths::Direct, seed)
    };
    let imgs = render(
        &scene,
        size,
        &[
            with(LightSelection::Every, 1),
            with(LightSelection::One, 2),
            with(LightSelection::Auto, 2),
        ],
    );
    assert_eq!(imgs[1].mean, imgs[2].mean, "100 lights are many: auto draws one");
    for (img, what) in imgs
        .iter()
        .zip(["plane under 100 quads, every one", "plane under 100 quads, one drawn"])
    {
        let mut plane = Agreement::new(what);
        for j in 0..size.1 {
            for i in 0..size.0 {
                let want = pixel_average(i, j, 4, |x, y| {
                    let p = ground_point(&scene, x, y, size, 9.0)?;
                    Some(quads.iter().fold(Vec3::ZERO, |sum, (verts, radiance)| {
                        sum + 0.7 / std::f32::consts::PI * *radiance * polygon_irradiance(p, Vec3::Y, verts)
                    }))
                });
                if let Some(want) = want {
                    plane.check(img, i, j, want, want * 2e-3);
                }
            }
        }
        assert!(plane.pixels > 200, "{what}: {} pixels", plane.pixels);
        plane.assert();
    }
}

#[test]
fn sphere_light_over_a_plane_direct_only() {
    // A sphere wholly above a Lambertian receiver's horizon gives the same irradiance as a point
    // light of intensity π R² L at its centre: E = π L R² cos θ / D². Directly below the centre
    // at distance d this is the cap formula E = π L (R/d)², radiance ρ L (R/d)².
    let (center, radius, radiance, albedo) = (Vec3::new(0.0, 1.5, 0.0), 0.5, Vec3::new(4.0, 3.0, 2.0), 0.8);
    let toml = r#"
[camera]
position = [2.5, 2.0, 2.5]
target = [0.0, 0.5, 0.0]
fov_y_deg = 55

[[materials]]
name = "m"
albedo = 0.8

[[objects]]
mesh = "plane"
size = 30
material = "m"

[[lights]]
type = "sphere"
center = [0.0, 1.5, 0.0]
radius = 0.5
radiance = [4.0, 3.0, 2.0]
"#;
    let scene = parse(toml);
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(128, 0, LightPaths::Direct, 5)])[0];
    // Grid points can miss a sliver of the silhouette: a pixel counts as wholly on the light if
    // a slightly smaller sphere covers its grid, and as off it if a slightly larger one misses.
    let hits_sphere = |x: f32, y: f32, r: f32| {
        let (o, d) = scene.camera.ray(x, y, size.0, size.1);
        let oc = o - center;
        let b = oc.dot(d);
        b * b - (oc.length_squared() - r * r) >= 0.0 && b < 0.0
    };
    let (mut on_light, mut on_plane, mut nearest_axis) = (
        Agreement::new("sphere light seen directly"),
        Agreement::new("plane under a sphere light"),
        (f32::MAX, 0, 0),
    );
    for j in 0..size.1 {
        for i in 0..size.0 {
            if pixel_average(i, j, 6, |x, y| hits_sphere(x, y, 0.97 * radius).then_some(Vec3::ONE)).is_some() {
                on_light.check(img, i, j, radiance, Vec3::ZERO);
                continue;
            }
            let want = pixel_average(i, j, 8, |x, y| {
                if hits_sphere(x, y, 1.03 * radius) {
                    return None;
                }
                let p = ground_point(&scene, x, y, size, 14.0)?;
                let to_c = center - p;
                let dist = to_c.length();
                Some(albedo * radiance * radius * radius * (to_c.y / dist) / (dist * dist))
            });
            let Some(want) = want else { continue };
            on_plane.check(img, i, j, want, want * 1e-3);
            let p = ground_point(&scene, i as f32 + 0.5, j as f32 + 0.5, size, 14.0).unwrap_or(Vec3::splat(99.0));
            if p.x.hypot(p.z) < nearest_axis.0 {
                nearest_axis = (p.x.hypot(p.z), i, j);
            }
        }
    }
    assert!(
        on_light.pixels > 10 && on_plane.pixels > 300,
        "{} pixels on the light, {} on the plane",
        on_light.pixels,
        on_plane.pixels
    );
    on_light.assert();
    on_plane.assert();
    let (r, i, j) = nearest_axis;
    assert!(
        r < 0.1,
        "a pixel looks almost straight below the light ({r} m off the axis)"
    );
    let d = center.y;
    let mut axis = Agreement::new("on the axis");
    axis.check(
        img,
        i,
        j,
        albedo * radiance * (radius / d).powi(2),
        albedo * radiance * 0.02,
    );
    axis.assert();
}

#[test]
fn error_falls_as_one_over_sqrt_spp() {
    let scene = scene_file("cornell.toml");
    let size = (32, 32);
    // Independent seeds: renders sharing a seed share their first samples.
    let runs = [
        settings(8, 3, LightPaths::All, 1),
        settings(32, 3, LightPaths::All, 2),
        settings(512, 3, LightPaths::All, 3),
    ];
    let imgs = render(&scene, size, &runs);
    // The ~20 pixels straddling the light's outline hold nearly all the squared error at these
    // sample counts; with so few terms the RMSE ratio would scatter from 1.2 to 3.5 between seeds.
    let keep = off_light_outline(&scene, size);
    assert!(keep.iter().filter(|k| !**k).count() < 40);
    let (e8, e32) = (
        rmse(&imgs[0].mean, &imgs[2].mean, Some(&keep)),
        rmse(&imgs[1].mean, &imgs[2].mean, Some(&keep)),
    );
    // Expected sqrt((1/8 + 1/512) / (1/32 + 1/512)) ≈ 1.96, the reference's own noise included.
    let ratio = e8 / e32;
    assert!(
        (1.6..=2.5).contains(&ratio),
        "RMSE at 8 spp {e8}, at 32 spp {e32}: ratio {ratio}"
    );
}

/// Per channel, how two independent renders of the same estimand differ in units of their
/// combined standard error: pixels beyond 3 and the worst, and the z of the means over the pixels
/// `keep` marks.
fn two_render_z(a: &ReferenceImage, b: &ReferenceImage, keep: &[bool]) -> (usize, f64, [f64; 3]) {
    let (mut beyond_3, mut worst) = (0, 0.0f64);
    let (mut diff, mut var) = ([0.0f64; 3], [0.0f64; 3]);
    let pixels = a
        .mean
        .pixels
        .iter()
        .zip(&b.mean.pixels)
        .zip(a.standard_error.pixels.iter().zip(&b.standard_error.pixels));
    for (((ma, mb), (sa, sb)), &kept) in pixels.zip(keep) {
        let mut pixel_z = 0.0f64;
        for c in 0..3 {
            let s2 = (sa[c] as f64).powi(2) + (sb[c] as f64).powi(2);
            let d = ma[c] as f64 - mb[c] as f64;
            if kept {
                diff[c] += d;
                var[c] += s2;
            }
            pixel_z = pixel_z.max(if s2 > 0.0 {
                d.abs() / s2.sqrt()
            } else if d == 0.0 {
                0.0
            } else {
                f64::INFINITY
            });
        }
        beyond_3 += usize::from(pixel_z > 3.0);
        worst = worst.max(pixel_z);
    }
    (beyond_3, worst, [0, 1, 2].map(|c| diff[c] / var[c].sqrt()))
}

/// Mean per-pixel variance of one sample (s.e.² × spp), in luminance-weighted channels.
fn sample_variance(img: &ReferenceImage) -> f64 {
    let w = [0.2126, 0.7152, 0.0722];
    let n = img.standard_error.pixels.len() as f64;
    img.standard_error
        .pixels
        .iter()
        .map(|p| (0..3).map(|c| w[c] * (p[c] as f64).powi(2)).sum::<f64>())
        .sum::<f64>()
        / n
        * img.spp as f64
}

/// The relative variance of one sample that the reference prints (and its efficiency is built
/// on) predicts the relative MSE of a render against the truth: on the furnace with roulette from
/// the first bounce (noisy, and exact in expectation: the truncated series), the relative MSE
/// against that series equals the printed variance over the spp. Leaving the spp out of the
/// variance, or weighing the pixels otherwise than the relative MSE, misses by far more.
#[test]
fn relative_variance_per_sample_predicts_the_relative_mse_against_the_truth() {
    let furnace = scene_file("furnace.toml");
    let m = &furnace.materials[0];
    let (size, spp, bounces) = ((32u32, 32u32), 16, 14);
    let img = &render(
        &furnace,
        size,
        &[Settings {
            roulette_after: Some(1),
            ..settings(spp, bounces, LightPaths::All, 11)
        }],
    )[0];
    let truth = (0..bounces + 2).fold(Vec3::ZERO, |sum, k| sum + m.emission * m.albedo.powf(k as f32));
    let eps = penumbra::metrics::stats::REL_MSE_EPSILON;
    let rel_mse = img
        .mean
        .pixels
        .iter()
        .map(|p| {
            (0..3)
                .map(|c| (p[c] as f64 - truth[c] as f64).powi(2) / ((truth[c] as f64).powi(2) + eps))
                .sum::<f64>()
        })
        .sum::<f64>()
        / (3 * img.mean.pixels.len()) as f64;
    let predicted = img.relative_variance_per_sample() / spp as f64;
    eprintln!("relative MSE against the series {rel_mse:.4e}, predicted {predicted:.4e}");
    assert!(
        rel_mse > 0.0 && (0.75..1.33).contains(&(predicted / rel_mse)),
        "predicted {predicted:.4e} against {rel_mse:.4e}"
    );
}

/// Russian roulette is unbiased: with it the Cornell box (8 bounces) renders the same mean as
/// without, pixel by pixel and over the image, within the renders' own standard errors, and the
/// furnace (where every path without roulette carries exactly the truncated series) the
/// truncated series within the noise roulette adds. Roulette from the first bounce, the most
/// it can be used. Forgetting to divide the throughput by the survival probability moves the
/// Cornell box's image mean by tens of standard errors.
#[test]
fn russian_roulette_leaves_the_mean_unchanged() {
    let scene = scene_file("cornell.toml");
    let size = (16, 16);
    let with = |roulette_after, seed| Settings {
        roulette_after,
        ..settings(128, 8, LightPaths::All, seed)
    };
    // Independent seeds: renders sharing a seed share their first interactions.
    let imgs = render(&scene, size, &[with(None, 1), with(Some(1), 2), with(Some(1), 1)]);
    let (plain, roulette, same_seed) = (&imgs[0], &imgs[1], &imgs[2]);
    assert_ne!(
        plain.mean, same_seed.mean,
        "roulette reaches the tracer: the same seed renders differently"
    );
    // The mean over the pixels clear of the light's outline: the few that straddle it mix the
    // light's radiance with the room's and would hold nearly all of the image mean's variance.
    let (beyond_3, worst, image_z) = two_render_z(plain, roulette, &off_light_outline(&scene, size));
    let cost = sample_variance(roulette) / sample_variance(plain);
    eprintln!("Cornell box: {beyond_3} of 256 pixels beyond 3 s.e., worst z {worst:.2}, image mean z {image_z:?}; variance per sample with roulette / without {cost:.3}");
    assert!(
        beyond_3 <= 5 && worst <= 6.0,
        "{beyond_3} pixels beyond 3 s.e., worst z {worst}"
    );
    assert!(
        image_z.iter().all(|z| z.abs() <= 4.0),
        "image means differ: z {image_z:?}"
    );
    // Survival in proportion to the throughput costs little variance (0.98 measured: noise).
    assert!(cost < 1.3, "roulette multiplies the variance by {cost}");

    let furnace = scene_file("furnace.toml");
    let m = &furnace.materials[0];
    let bounces = 14;
    let img = &render(
        &furnace,
        size,
        &[Settings {
            roulette_after: Some(1),
            ..settings(64, bounces, LightPaths::All, 5)
        }],
    )[0];
    // The first K + 2 terms of E (1 + ρ + ρ² + …).
    let truncated = (0..bounces + 2).fold(Vec3::ZERO, |sum, k| sum + m.emission * m.albedo.powf(k as f32));
    let mut agreement = Agreement::new("furnace with roulette");
    for j in 0..size.1 {
        for i in 0..size.0 {
            agreement.check(img, i, j, truncated, Vec3::ZERO);
        }
    }
    assert!(
        img.standard_error.pixels.iter().all(|p| p[0] > 0.0),
        "roulette makes the furnace noisy: it was used"
    );
    agreement.assert();

    // With the Sobol sampler roulette's draws are stratified per depth: still the truncated
    // series (the image mean, within 4 of its standard error), with less variance.
    let sobol = |seed| Settings {
        roulette_after: Some(1),
        sampler: Sampler::Sobol,
        ..settings(256, bounces, LightPaths::All, seed)
    };
    let imgs = render(
        &furnace,
        size,
        &[
            Settings {
                sampler: Sampler::Independent,
                ..sobol(6)
            },
            sobol(6),
        ],
    );
    let ((_, independent), (mean, se)) = (imgs[0].average(), imgs[1].average());
    for c in 0..3 {
        let z = (mean[c] - truncated[c] as f64) / se[c];
        eprintln!("furnace, sobol: channel {c}: mean {:.6} against {:.6}, z {z:.2}; standard error {:.3e} against independent samples' {:.3e}", mean[c], truncated[c], se[c], independent[c]);
        assert!(
            z.abs() <= 4.0,
            "channel {c}: the Sobol furnace's mean {} is {z:.1} standard errors from {}",
            mean[c],
            truncated[c]
        );
        assert!(
            se[c] < 0.8 * independent[c],
            "channel {c}: stratified roulette should lower the error ({:.3e} against {:.3e})",
            se[c],
            independent[c]
        );
    }
}

/// The standard error a render reports is the spread of its mean across seeds, and a render
/// does not depend on its batches, even where a batch asks one shader invocation for more loop
/// iterations than llvmpipe allows it (65,535 in all, after which every loop stops early). At
/// 1×1 with all 1000 samples in one batch, an invocation used to stop after a couple of hundred
/// samples and report the standard error of 1000: the means scattered about five times their
/// reported standard error (a thousand times at 10⁶ samples). Per channel, the standard
/// deviation of 10 seeds' means over the root-mean-square reported standard error is about 1
/// (within 0.35–2.5 but for a chance of about 1 in 1000).
#[test]
fn reported_standard_error_matches_the_spread_across_seeds() {
    for sampler in [Sampler::Independent, Sampler::Sobol] {
        eprintln!("{sampler:?}");
        standard_error_against_spread(sampler);
    }
}

fn standard_error_against_spread(sampler: Sampler) {
    let scene = scene_file("cornell.toml");
    let spp = 1000;
    let one_batch = |seed| Settings {
        batching: Batching::Fixed(spp),
        sampler,
        ..settings(spp, 3, LightPaths::All, seed)
    };
    let mut runs: Vec<Settings> = (1..=10).map(one_batch).collect();
    runs.push(Settings {
        batching: Batching::Fixed(16),
        ..one_batch(1)
    });
    runs.push(Settings {
        sampler,
        ..settings(spp, 3, LightPaths::All, 1)
    });
    let mut imgs = render(&scene, (1, 1), &runs);
    let (adaptive, small_batches) = (imgs.pop().unwrap(), imgs.pop().unwrap());
    let n = imgs.len() as f64;
    for c in 0..3 {
        let means: Vec<f64> = imgs.iter().map(|i| i.mean.get(0, 0)[c] as f64).collect();
        let m = means.iter().sum::<f64>() / n;
        let spread = (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let reported = (imgs
            .iter()
            .map(|i| (i.standard_error.get(0, 0)[c] as f64).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        let ratio = spread / reported;
        eprintln!(
            "channel {c}: spread of means {spread:.3e}, reported standard error {reported:.3e}, ratio {ratio:.2}"
        );
        assert!((0.35..=2.5).contains(&ratio), "channel {c}: means {means:?} spread {spread:.3e}, reported standard error {reported:.3e} (ratio {ratio:.2})");
    }
    for other in [&small_batches, &adaptive] {
        assert_eq!(
            (&other.mean, &other.standard_error),
            (&imgs[0].mean, &imgs[0].standard_error),
            "batches of 16 or adaptive give the one-batch render"
        );
    }
}

#[test]
fn direct_plus_indirect_is_everything_and_batching_changes_nothing() {
    for sampler in [Sampler::Independent, Sampler::Sobol] {
        direct_plus_indirect_and_batching(sampler);
    }
}

#[test]
fn samples_traced_in_bands_of_rows_equal_the_whole_image_at_once() {
    // The demo's live reference traces a sample in bands of rows over several frames: samples
    // are keyed by pixel and index, so the bands give the image a whole-image render gives,
    // bit for bit, and a camera moved with `set_camera` gives that camera's render.
    let scene = scene_file("cornell.toml");
    let s = Settings {
        batching: Batching::Fixed(1),
        ..settings(3, 2, LightPaths::All, 5)
    };
    let whole = render(&scene, (12, 10), std::slice::from_ref(&s)).remove(0);
    let mut r = ReferenceRenderer::new(common::test_gpu(), &scene, (12, 10)).expect("reference renderer");
    let mut last = None;
    for done in 0..3 {
        for rows in [0..3, 3..4, 4..10] {
            let read = rows.end == 10;
            last = r.accumulate(&s, (done, 1), rows, read).expect("band");
            assert_eq!(last.is_some(), read);
        }
    }
    let banded = last.expect("read back");
    assert_eq!(banded.spp, 3);
    assert_eq!(banded.mean, whole.mean, "bands change nothing");
    assert_eq!(banded.standard_error, whole.standard_error);
    assert!(r.accumulate(&s, (3, 1), 4..11, false).is_err(), "rows past the image");

    let mut moved = scene.clone();
    moved.camera.position.x += 0.3;
    moved.camera.target.x += 0.3;
    let want = render(&moved, (12, 10), std::slice::from_ref(&s)).remove(0);
    r.set_camera(&moved.camera);
    let got = r
        .accumulate(&s, (0, 3), 0..10, true)
        .expect("moved")
        .expect("read back");
    assert_eq!(
        got.mean, want.mean,
        "set_camera traces the new view, afresh from sample 0"
    );
    common::assert_clean(&r.gpu);
}

fn direct_plus_indirect_and_batching(sampler: Sampler) {
    let scene = scene_file("cornell.toml");
    let with = |paths| Settings {
        sampler,
        ..settings(6, 3, paths, 9)
    };
    let batched = |batching| Settings {
        batching,
        ..with(LightPaths::All)
    };
    let runs = [
        batched(Batching::Fixed(1)),
        batched(Batching::Fixed(4)),
        with(LightPaths::Direct),
        with(LightPaths::Indirect),
    ];
    let imgs = render(&scene, (16, 16), &runs);
    assert_eq!(
        imgs[0].mean, imgs[1].mean,
        "samples do not depend on how they are batched"
    );
    assert_eq!(imgs[0].standard_error, imgs[1].standard_error);
    let (all, direct, indirect) = (&imgs[0].mean, &imgs[2].mean, &imgs[3].mean);
    let (mut some_direct, mut some_indirect) = (false, false);
    for ((a, d), n) in all.pixels.iter().zip(&direct.pixels).zip(&indirect.pixels) {
        for c in 0..3 {
            // The same seed draws the same first interaction in all three estimators.
            assert!(
                (a[c] - d[c] - n[c]).abs() <= 1e-4 * a[c].abs() + 1e-6,
                "{a:?} != {d:?} + {n:?}"
            );
            some_direct |= d[c] > 0.0;
            some_indirect |= n[c] > 0.0;
        }
    }
    assert!(some_direct && some_indirect);
    let mut r = ReferenceRenderer::new(common::test_gpu(), &scene, (4, 4)).expect("reference renderer");
    let e = r
        .render(&settings(1, 0, LightPaths::Indirect, 0), &mut |_, _| {})
        .expect_err("--indirect-only with 0 bounces is an error")
        .to_string();
    assert!(e.contains("--indirect-only") && e.contains("--bounces"), "{e}");
    common::assert_clean(&r.gpu);
}

fn cli_options(scene: &str, output: &Path, seed: u32) -> ReferenceOptions {
    ReferenceOptions {
        scene: Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(scene),
        output: output.to_path_buf(),
        size: (16, 16),
        settings: settings(4, 2, LightPaths::All, seed),
        frame: 0,
        target: None,
        camera: None,
        gpu: common::test_gpu_desc(),
    }
}

#[test]
fn same_seed_gives_identical_files_and_another_seed_differs() {
    let paths = ["same-a.exr", "same-b.exr", "other.exr"].map(common::temp_path);
    // `run` fails when the validation layer reported anything.
    for (path, seed) in paths.iter().zip([3, 3, 4]) {
        let report = penumbra::reference::run(&cli_options("cornell.toml", path, seed)).expect("reference run");
        assert_eq!(
            report.written,
            vec![path.clone(), penumbra::reference::stderr_path(path)]
        );
    }
    let bytes = |p: &Path| std::fs::read(p).expect("written");
    let stderr = |p: &Path| bytes(&penumbra::reference::stderr_path(p));
    assert_eq!(bytes(&paths[0]), bytes(&paths[1]), "same seed, same mean");
    assert_eq!(stderr(&paths[0]), stderr(&paths[1]), "same seed, same standard error");
    assert_ne!(bytes(&paths[0]), bytes(&paths[2]), "another seed, other noise");
}

#[test]
fn command_line_renders_the_furnace_and_rejects_bad_input() {
    let out = common::temp_path("cli-furnace.exr");
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let furnace = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/furnace.toml");
    let penumbra = |args: &[&str]| {
        let mut all = vec![
            "reference",
            furnace.to_str().expect("utf-8 path"),
            "--device",
            &device,
            "--validation",
        ];
        all.extend_from_slice(args);
        std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args(&all)
            .output()
            .expect("run penumbra")
    };
    // No roulette: the furnace is then noise-free (every path carries the truncated series).
    let o = penumbra(&[
        "--size",
        "8x8",
        "--spp",
        "3",
        "--bounces",
        "14",
        "--roulette-after",
        "off",
        "--light-selection",
        "one",
        "--sampler",
        "sobol",
        "-o",
        out.to_str().expect("utf-8 path"),
    ]);
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{stdout}\n{stderr}");
    // The summary goes to stdout; progress lines only to a terminal, so a pipe gets none.
    assert!(
        stdout.contains("samples/s") && !stderr.contains("spp"),
        "{stdout}\n{stderr}"
    );
    let mean = HdrImage::read_exr(&out).expect("mean EXR");
    let se = HdrImage::read_exr(&penumbra::reference::stderr_path(&out)).expect("standard-error EXR");
    assert_eq!((mean.width, mean.height, se.width), (8, 8, 8));
    assert!(
        mean.pixels.iter().all(|p| (p[0] - 1.0).abs() < 1e-3),
        "{:?}",
        mean.pixels[0]
    );

    for (args, expect) in [
        (&["-o", "x.png"][..], "OpenEXR"),
        (&["--direct-only", "--bounces", "3"][..], "cannot be used with"),
        (&["--indirect-only", "--bounces", "0"][..], "--indirect-only"),
        (&["--spp", "0"][..], "--spp"),
        (&["--size", "0x4"][..], "--size"),
        (&["--roulette-after", "0"][..], "--roulette-after"),
        (&["--roulette-after", "never"][..], "--roulette-after"),
        (&["--light-selection", "some"][..], "--light-selection"),
        (&["--sampler", "halton"][..], "--sampler"),
    ] {
        let o = penumbra(args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && stderr.contains(expect), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

/// An 8 × 8 map of four 4 × 4 quadrants (top-left, top-right, bottom-left, bottom-right), saved
/// as a PNG; distinct quadrants show a flipped or transposed lookup.
fn quadrant_png(name: &str, quadrants: [[u8; 3]; 4]) -> std::path::PathBuf {
    let path = common::temp_path(name);
    image::RgbaImage::from_fn(8, 8, |x, y| {
        let [r, g, b] = quadrants[(y / 4 * 2 + x / 4) as usize];
        image::Rgba([r, g, b, 255])
    })
    .save(&path)
    .expect("write map");
    path
}

/// The quadrant (0–3, as in [`quadrant_png`]) whose texels alone the bilinear, repeat-wrapped
/// lookup at uv blends, or None where it blends two quadrants (within half a texel of a
/// quadrant's edge, the map's border included, where repeat wrapping blends in the far side).
fn pure_quadrant(u: f32, v: f32) -> Option<usize> {
    let block = |c: f32| {
        let i = (c * 8.0 - 0.5).floor() as i64;
        let (a, b) = (i.rem_euclid(8) / 4, (i + 1).rem_euclid(8) / 4);
        (a == b).then_some(a as usize)
    };
    Some(block(v)? * 2 + block(u)?)
}

#[test]
fn albedo_and_specular_maps_give_each_texel_region_its_closed_form() {
    // Albedo bytes are sRGB, specular bytes linear: each quadrant a different known surface.
    let albedo_bytes = [[200, 64, 16], [32, 128, 240], [250, 250, 250], [10, 90, 160]];
    let specular_bytes = [[51, 51, 51], [255, 255, 255], [102, 102, 102], [0, 0, 0]];
    let (albedo_png, specular_png) = (
        quadrant_png("quad-albedo.png", albedo_bytes),
        quadrant_png("quad-specular.png", specular_bytes),
    );
    let (base_albedo, base_specular, exponent) = (Vec3::new(0.9, 0.8, 0.7), 0.5, 16.0);
    // The highlight's mirror point lies in the top-right quadrant (u ≈ 0.66, v ≈ 0.30).
    let toml = format!(
        "{LIT_PLANE}\n[[materials]]\nname = \"m\"\nalbedo = [0.9, 0.8, 0.7]\nspecular = {base_specular}\nexponent = {exponent}\n\
         albedo_map = {:?}\nspecular_map = {:?}\n\n[[objects]]\nmesh = \"plane\"\nsize = 6\nmaterial = \"m\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = [1.2, 1.0, -2.5]\nintensity = 10\n",
        albedo_png.display().to_string(),
        specular_png.display().to_string()
    );
    let scene = parse(&toml);
    // The plane's uvs as the tracer reads them: u = (x + 3)/6, v = (z + 3)/6.
    let mesh = scene.objects[0].load_mesh(Path::new(".")).unwrap();
    for (p, uv) in mesh.positions.iter().zip(&mesh.uvs) {
        assert!(
            (uv.x - (p.x + 3.0) / 6.0).abs() < 1e-6 && (uv.y - (p.z + 3.0) / 6.0).abs() < 1e-6,
            "{p} has uv {uv}"
        );
    }
    let surface_of = |q: usize| Surface {
        albedo: base_albedo * Vec3::from(albedo_bytes[q].map(penumbra::util::image_io::srgb_decode)),
        specular: Vec3::from(specular_bytes[q].map(|b| b as f32 / 255.0)) * base_specular,
        exponent,
        emission: Vec3::ZERO,
    };
    let size = (48, 48);
    let img = &render(&scene, size, &[settings(64, 0, LightPaths::Direct, 5)])[0];
    let lights = punctual_lights(&scene);
    let mut agreement = Agreement::new("albedo and specular maps");
    let (mut per_quadrant, mut specular_share) = ([0; 4], 0.0f32);
    for j in 0..size.1 {
        for i in 0..size.0 {
            // The plane's image of a pixel is convex, so its four corners in one pure quadrant
            // put the whole pixel there.
            let corner_quadrant = |x: u32, y: u32| {
                ground_point(&scene, x as f32, y as f32, size, 3.0)
                    .and_then(|p| pure_quadrant((p.x + 3.0) / 6.0, (p.z + 3.0) / 6.0))
            };
            let Some(q) = corner_quadrant(i, j) else { continue };
            if [(i + 1, j), (i, j + 1), (i + 1, j + 1)]
                .into_iter()
                .any(|(x, y)| corner_quadrant(x, y) != Some(q))
            {
                continue;
            }
            let s = surface_of(q);
            let Some(want) = pixel_average(i, j, 8, |x, y| {
                Some(shade(
                    ground_point(&scene, x, y, size, 3.0)?,
                    Vec3::Y,
                    scene.camera.position,
                    &s,
                    &lights,
                    Vec3::ZERO,
                ))
            }) else {
                continue;
            };
            let diffuse_only = Surface {
                specular: Vec3::ZERO,
                ..s
            };
            let diffuse = pixel_average(i, j, 4, |x, y| {
                Some(shade(
                    ground_point(&scene, x, y, size, 3.0)?,
                    Vec3::Y,
                    scene.camera.position,
                    &diffuse_only,
                    &lights,
                    Vec3::ZERO,
                ))
            })
            .unwrap();
            specular_share = specular_share.max(1.0 - diffuse.x / want.x.max(1e-9));
            agreement.check(img, i, j, want, want * 1e-3);
            per_quadrant[q] += 1;
        }
    }
    println!("pixels per quadrant {per_quadrant:?}, largest specular share {specular_share}");
    assert!(
        per_quadrant.iter().all(|&n| n >= 40),
        "every quadrant is checked: {per_quadrant:?}"
    );
    assert!(
        specular_share > 0.3,
        "the specular lobe matters somewhere checked ({specular_share})"
    );
    agreement.assert();
}

/// Between texel centres the map is filtered as the raster sampler filters it: sRGB decoded per
/// texel, then bilinear with texel centres at half-integers, wrapping around the map's edges.
#[test]
fn albedo_map_is_filtered_bilinearly_with_repeat_wrapping() {
    let png = common::temp_path("gradient-albedo.png");
    let texels = [
        [250, 20, 90],
        [30, 200, 60],
        [120, 120, 250],
        [10, 60, 10],
        [220, 220, 40],
        [60, 10, 200],
        [250, 250, 250],
        [0, 90, 30],
    ];
    image::RgbaImage::from_fn(4, 2, |x, y| {
        let [r, g, b] = texels[(y * 4 + x) as usize];
        image::Rgba([r, g, b, 255])
    })
    .save(&png)
    .expect("write map");
    let toml = format!(
        "{LIT_PLANE}\n[[materials]]\nname = \"m\"\nalbedo = 1\nalbedo_map = {:?}\n\n[[objects]]\nmesh = \"plane\"\nsize = 6\nmaterial = \"m\"\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 2\n",
        png.display().to_string()
    );
    let scene = parse(&toml);
    let traced = penumbra::reference::TracedScene::build(&scene).unwrap();
    let map = &traced.textures[0];
    // The lookup itself: at a texel centre the texel; on the left edge half the far right texel.
    let decoded = |k: usize| Vec3::from(texels[k].map(penumbra::util::image_io::srgb_decode));
    assert!(
        (map.sample(glam::Vec2::new(0.625, 0.25)).truncate() - decoded(2))
            .abs()
            .max_element()
            < 1e-6
    );
    let edge = map.sample(glam::Vec2::new(0.0, 0.25)).truncate();
    assert!(
        (edge - 0.5 * (decoded(0) + decoded(3))).abs().max_element() < 1e-6,
        "{edge}"
    );
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(64, 0, LightPaths::Direct, 11)])[0];
    let mut agreement = Agreement::new("bilinear albedo map");
    for j in 0..size.1 {
        for i in 0..size.0 {
            let Some(want) = pixel_average(i, j, 8, |x, y| {
                let p = ground_point(&scene, x, y, size, 3.0)?;
                Some(
                    map.sample(glam::Vec2::new((p.x + 3.0) / 6.0, (p.z + 3.0) / 6.0))
                        .truncate()
                        * (2.0 / std::f32::consts::PI),
                )
            }) else {
                continue;
            };
            // The 8 × 8 point average misses the kinks at texel centres by a little.
            agreement.check(img, i, j, want, want * 5e-3);
        }
    }
    assert!(agreement.pixels > 400, "{} pixels", agreement.pixels);
    agreement.assert();
}

#[test]
fn normal_map_tilts_the_normal_in_the_meshs_tangent_frame() {
    // A uniform map of the tangent-space normal (0.3, 0.4, 0.866) on a plane turned 90° about y,
    // so that the world frame comes from the mesh's transformed tangents: T = (0, 0, −1),
    // B = N × T = (−1, 0, 0) (toward −v, green up), N = +y.
    let encode = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
    let bytes = [encode(0.3), encode(0.4), encode(0.866)];
    let png = quadrant_png("normal-map.png", [bytes; 4]);
    let toml = format!(
        "{LIT_PLANE}\n[[materials]]\nname = \"m\"\nalbedo = 0.7\nnormal_map = {:?}\n\n\
         [[objects]]\nmesh = \"plane\"\nsize = 6\nrotate_deg = [0, 90, 0]\nmaterial = \"m\"\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [1.0, -1.0, 0.5]\nirradiance = 3\n",
        png.display().to_string()
    );
    let scene = parse(&toml);
    let mesh = scene.objects[0]
        .load_mesh(Path::new("."))
        .unwrap()
        .transformed(&scene.objects[0].transform);
    for t in &mesh.tangents {
        assert!(
            (t.truncate() - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5 && t.w == 1.0,
            "tangent {t}"
        );
    }
    let tn = Vec3::from(bytes.map(|b| b as f32 / 255.0 * 2.0 - 1.0)).normalize();
    let (t, b, n) = (Vec3::new(0.0, 0.0, -1.0), Vec3::new(-1.0, 0.0, 0.0), Vec3::Y);
    let tilted = (t * tn.x + b * tn.y + n * tn.z).normalize();
    let l = -Vec3::new(1.0, -1.0, 0.5).normalize();
    let (cos_tilted, cos_flat, cos_mirrored_b) = (
        tilted.dot(l),
        n.dot(l),
        (t * tn.x - b * tn.y + n * tn.z).normalize().dot(l),
    );
    // The test can tell the tilt, and the bitangent's sign, apart.
    assert!(
        cos_tilted > 1.3 * cos_flat && cos_tilted > 1.5 * cos_mirrored_b,
        "{cos_tilted} {cos_flat} {cos_mirrored_b}"
    );
    let want = Vec3::splat(0.7 / std::f32::consts::PI * 3.0 * cos_tilted);
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(16, 0, LightPaths::Direct, 9)])[0];
    let mut agreement = Agreement::new("normal-mapped plane under a directional light");
    for j in 0..size.1 {
        for i in 0..size.0 {
            if [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                .into_iter()
                .all(|(x, y)| ground_point(&scene, x as f32, y as f32, size, 3.0).is_some())
            {
                agreement.check(img, i, j, want, want * 1e-4);
            }
        }
    }
    assert!(agreement.pixels > 400, "{} pixels", agreement.pixels);
    agreement.assert();
}

#[test]
fn an_unreadable_texture_map_is_an_error_naming_the_field() {
    let bad = common::temp_path("not-an-image.png");
    std::fs::write(&bad, "not a PNG").expect("write");
    let texture = |path: &Path| {
        format!(
            "{SKY_CAMERA}\n[[materials]]\nname = \"wood\"\nspecular_map = {:?}\n",
            path.display().to_string()
        )
    };
    // Not an image at all: refused when the scene is read, with the field's line.
    let e = Scene::from_str(&texture(&bad), "<test>", Path::new("."))
        .expect_err("an error")
        .to_string();
    assert!(
        e.contains("<test>:") && e.contains("materials[0].specular_map") && e.contains("not-an-image.png"),
        "{e}"
    );
    // A valid header over corrupt image data: refused when the tracer decodes it.
    let scrambled = common::temp_path("scrambled.png");
    image::RgbaImage::from_fn(16, 16, |x, y| image::Rgba([(x * 16) as u8, (y * 16) as u8, 7, 255]))
        .save(&scrambled)
        .unwrap();
    let mut bytes = std::fs::read(&scrambled).unwrap();
    let n = bytes.len();
    for b in &mut bytes[41..n - 12] {
        *b ^= 0x5a;
    }
    std::fs::write(&scrambled, bytes).unwrap();
    let e = penumbra::reference::TracedScene::build(&parse(&texture(&scrambled)))
        .err()
        .expect("an error")
        .to_string();
    assert!(
        e.contains("<test>")
            && e.contains("specular_map")
            && e.contains("\"wood\"")
            && e.contains("scrambled.png")
            && e.contains("corrupt"),
        "{e}"
    );
    assert!(e.lines().count() == 1 && !e.contains('{'), "{e}");
}

/// A 16 × 8 sky: a bright sun texel, a bluish gradient above the horizon, a dim ground below,
/// with left-right asymmetry so that a mirrored or rotated lookup would show.
fn sky_texels() -> (u32, u32, Vec<[f32; 4]>) {
    let (w, h) = (16u32, 8u32);
    let texels = (0..w * h)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            if (i, j) == (11, 2) {
                [40.0, 36.0, 30.0, 1.0]
            } else if j < h / 2 {
                [0.2 + 0.05 * i as f32, 0.4 + 0.02 * j as f32, 0.9, 1.0]
            } else {
                [0.15, 0.1 + 0.01 * i as f32, 0.05, 1.0]
            }
        })
        .collect();
    (w, h, texels)
}

#[test]
fn image_environment_seen_directly_and_lighting_planes() {
    let (w, h, texels) = sky_texels();
    let exr = common::temp_path("sky.exr");
    HdrImage {
        width: w,
        height: h,
        pixels: texels.clone(),
    }
    .write_exr(&exr)
    .expect("write sky");
    let scale = 1.5;
    let sky = EnvironmentMap::from_texels(
        w,
        h,
        texels
            .iter()
            .map(|t| [t[0] * scale, t[1] * scale, t[2] * scale, 0.0])
            .collect(),
    );
    let environment = format!(
        "\n[environment]\ntype = \"image\"\npath = {:?}\nscale = {scale}\n",
        exr.display().to_string()
    );

    // Seen directly: every pixel whose footprint lies in one texel shows exactly that texel.
    let scene = parse(&format!(
        "[camera]\nposition = [0, 0, 0]\ntarget = [0.6, 0.5, -1]\nfov_y_deg = 100\n{environment}"
    ));
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(4, 2, LightPaths::All, 1)])[0];
    let mut direct = Agreement::new("environment seen directly");
    for j in 0..size.1 {
        for i in 0..size.0 {
            let mut texel = None;
            let want = pixel_average(i, j, 4, |x, y| {
                let d = scene.camera.ray(x, y, size.0, size.1).1;
                let uv = penumbra::scene::Environment::equirect_uv(d);
                let t = ((uv.x * w as f32) as u32, (uv.y * h as f32) as u32);
                (*texel.get_or_insert(t) == t).then(|| sky.radiance(d))
            });
            if let Some(want) = want {
                direct.check(img, i, j, want, Vec3::ZERO);
            }
        }
    }
    assert!(direct.pixels > 500, "{} pixels", direct.pixels);
    direct.assert();

    // A Lambertian plane facing +y: for a map constant over texels, each texel row between θ0 and
    // θ1 adds L (2π/W) (sin²θ1 − sin²θ0)/2 of irradiance; the rows above the horizon light the
    // front, those below reach the viewer through transmission.
    let irradiance = |rows: std::ops::Range<u32>| {
        let mut e = Vec3::ZERO;
        for j in rows {
            let (t0, t1) = (
                j as f32 / h as f32 * std::f32::consts::PI,
                (j + 1) as f32 / h as f32 * std::f32::consts::PI,
            );
            let band = std::f32::consts::TAU / w as f32 * (t1.sin().powi(2) - t0.sin().powi(2)).abs() / 2.0;
            for i in 0..w {
                let t = sky.texels[(j * w + i) as usize];
                e += Vec3::new(t[0], t[1], t[2]) * band;
            }
        }
        e
    };
    let (above, below) = (irradiance(0..h / 2), irradiance(h / 2..h));
    let size = (16, 16);
    for (material, glossy) in [
        ("albedo = [0.6, 0.5, 0.4]", false),
        (
            "albedo = [0.2, 0.3, 0.1]\nspecular = [0.5, 0.4, 0.3]\nexponent = 20\ntransmittance = [0.3, 0.3, 0.3]",
            true,
        ),
    ] {
        let scene = parse(&format!("{SKY_CAMERA}\n[[materials]]\nname = \"m\"\n{material}\n\n[[objects]]\nmesh = \"plane\"\nsize = 400\nmaterial = \"m\"\n{environment}"));
        let m = &scene.materials[0];
        let surface = Surface {
            albedo: m.albedo,
            specular: m.specular,
            exponent: m.exponent,
            emission: Vec3::ZERO,
        };
        let img = &render(&scene, size, &[settings(64, 0, LightPaths::Direct, 2)])[0];
        let mut lit = Agreement::new(if glossy {
            "glossy plane under an image sky"
        } else {
            "plane under an image sky"
        });
        for j in 0..size.1 {
            for i in 0..size.0 {
                let v = -scene.camera.pixel_center_ray(i, j, size.0, size.1).1;
                let (want, slack) = if glossy {
                    let want =
                        reflected_environment(&sky, v, &surface) + m.transmittance / std::f32::consts::PI * below;
                    (want, want * 2e-3)
                } else {
                    (m.albedo / std::f32::consts::PI * above, Vec3::ZERO)
                };
                lit.check(img, i, j, want, slack);
            }
        }
        lit.assert();
    }
}

/// Stochastic transparency: a pane of opacity α over a lit plane. A pixel through the pane is
/// `α·pane + (1 − α)·floor`, and the floor in the pane's shadow receives `1 − α` of the light
/// (the physical truth the shadow_volumes method's "light shines through glass" departs from).
#[test]
fn a_translucent_pane_is_seen_and_lets_light_through_in_proportion_to_its_opacity() {
    let (light, intensity, albedo) = (Vec3::new(0.2, 1.5, -0.3), 10.0, 0.9);
    // No emission on the pane: an emissive pane would also light the floor below it (the tracer
    // counts emission wherever a path meets it), which this closed form leaves out.
    let (pane_y, half, alpha, pane_albedo, pane_emission) = (0.6, 0.5, 0.4, 0.5, 0.0);
    let toml = format!(
        "{LIT_PLANE}\n[[materials]]\nname = \"m\"\nalbedo = {albedo}\n\n[[materials]]\nname = \"glass\"\nalbedo = {pane_albedo}\nemission = {pane_emission}\nopacity = {alpha}\n\n\
         [[objects]]\nmesh = \"plane\"\nsize = 6\nmaterial = \"m\"\n\n\
         [[objects]]\nmesh = \"quad\"\ncorner = [{}, {pane_y}, {}]\nedge_u = [0, 0, {}]\nedge_v = [{}, 0, 0]\nmaterial = \"glass\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = [{}, {}, {}]\nintensity = {intensity}\n",
        -half,
        -half,
        2.0 * half,
        2.0 * half,
        light.x,
        light.y,
        light.z
    );
    let scene = parse(&toml);
    let size = (32, 32);
    let img = &render(&scene, size, &[settings(256, 0, LightPaths::Direct, 5)])[0];
    let in_pane = |o: Vec3, d: Vec3, t_max: f32| {
        let t = (pane_y - o.y) / d.y;
        let p = o + d * t;
        (t > 0.0 && t < t_max && p.x.abs() <= half && p.z.abs() <= half).then_some(p)
    };
    let lambert = |p: Vec3, rho: f32| {
        let to_light = light - p;
        let r2 = to_light.length_squared();
        rho / std::f32::consts::PI * intensity * (to_light.y / r2.sqrt()) / r2
    };
    let mut transmitted = glam::DVec2::ZERO;
    let (mut through, mut under_shadow, mut open) = (
        Agreement::new("seen through the pane"),
        Agreement::new("floor in the pane's shadow"),
        Agreement::new("floor in the open"),
    );
    for j in 0..size.1 {
        for i in 0..size.0 {
            // (through the pane, floor point behind the pane's shadow), uniform over the pixel.
            let mut class = None;
            let mut uniform = true;
            let want = pixel_average(i, j, 8, |x, y| {
                let (o, d) = scene.camera.ray(x, y, size.0, size.1);
                let p = ground_point(&scene, x, y, size, 2.9)?;
                let pane = in_pane(o, d, f32::MAX);
                let shaded = in_pane(p, light - p, 1.0).is_some();
                let c = (pane.is_some(), shaded);
                uniform &= class.is_none_or(|k| k == c);
                class = Some(c);
                let floor = lambert(p, albedo) * if shaded { 1.0 - alpha } else { 1.0 };
                Some(Vec3::splat(match pane {
                    Some(q) => alpha * (pane_emission + lambert(q, pane_albedo)) + (1.0 - alpha) * floor,
                    None => floor,
                }))
            });
            let (Some(want), Some(c), true) = (want, class, uniform) else {
                continue;
            };
            if c == (false, true) {
                // What the floor there would be without the pane (the raster compromise).
                transmitted += glam::DVec2::new(img.mean.get(i, j)[0] as f64, (want.x / (1.0 - alpha)) as f64);
            }
            let a = match c {
                (true, _) => &mut through,
                (false, true) => &mut under_shadow,
                (false, false) => &mut open,
            };
            a.check(img, i, j, want, want * 1e-3);
        }
    }
    println!(
        "{} pixels through the pane, {} of floor in its shadow, {} in the open; worst z: {:.2}, {:.2}, {:.2}; the pane's shadow gets {:.3} of the unshadowed light (1 − α = {})",
        through.pixels,
        under_shadow.pixels,
        open.pixels,
        through.worst.0,
        under_shadow.worst.0,
        open.worst.0,
        transmitted.x / transmitted.y,
        1.0 - alpha
    );
    assert!(
        (transmitted.x / transmitted.y - (1.0 - alpha) as f64).abs() < 0.02,
        "{transmitted}"
    );
    assert!(
        through.pixels > 40 && under_shadow.pixels > 20 && open.pixels > 300,
        "{} / {} / {}",
        through.pixels,
        under_shadow.pixels,
        open.pixels
    );
    through.assert();
    under_shadow.assert();
    open.assert();
}

/// `--export-scene` writes every traced triangle once, under its material, with the camera and
/// lights of the scene file (what tools/reference_vs_mitsuba.py rebuilds for Mitsuba).
#[test]
fn export_scene_writes_every_triangle_with_its_material() {
    let dir = common::temp_path("export-cornell");
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml");
    let written = penumbra::reference::export::export_file(&scene_path, &dir).expect("export");
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("scene.json")).expect("scene.json")).expect("valid JSON");
    let traced = penumbra::reference::TracedScene::build(&scene_file("cornell.toml")).unwrap();
    let mut total = 0;
    for m in doc["materials"].as_array().expect("materials") {
        let n = m["triangles"].as_u64().unwrap() as usize;
        total += n;
        if n > 0 {
            let ply = std::fs::read(dir.join(m["mesh"].as_str().unwrap())).expect("ply");
            let header =
                String::from_utf8_lossy(&ply[..ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11])
                    .to_string();
            assert!(
                header.contains(&format!("element face {n}\n"))
                    && header.contains(&format!("element vertex {}\n", 3 * n)),
                "{header}"
            );
            assert_eq!(
                ply.len(),
                header.len() + n * 3 * 24 + n * 13,
                "positions and normals per vertex, a list of three indices per face"
            );
        }
    }
    assert_eq!(total, traced.triangles.len());
    assert_eq!(doc["lights"][0]["type"], "quad");
    assert_eq!(doc["camera"]["fov_y_deg"].as_f64().unwrap() as f32, 39.3);
    assert!(written.len() >= 2);
}

/// `--max-stderr`: a render with a target error stops once the error, as
/// `reference::relative_error` measures it, is at most the target (never before 32 spp), a
/// tighter target takes more samples, and a render stopped at n samples is bit for bit the
/// fixed render of n samples (samples are keyed by their index, whatever the batching).
#[test]
fn a_target_error_stops_the_render_where_it_holds() {
    use penumbra::reference::{relative_error, ErrorScope, Stop, MIN_ADAPTIVE_SPP};
    let scene = scene_file("cornell.toml");
    let mut r = ReferenceRenderer::new(common::test_gpu(), &scene, (16, 16)).expect("reference renderer");
    let cap = settings(4096, 3, LightPaths::All, 5);
    let mut adaptive = |scope: ErrorScope, max: f64| {
        let mut checks = 0;
        let mut check = |img: &ReferenceImage| {
            checks += 1;
            relative_error(img, scope) / max
        };
        let img = r
            .render_until(
                &cap,
                Some(Stop {
                    min_spp: MIN_ADAPTIVE_SPP,
                    check: &mut check,
                }),
                &mut |_, _| {},
            )
            .expect("adaptive render");
        (img, checks)
    };
    let mut stopped = Vec::new();
    for (scope, loose, tight) in [(ErrorScope::Image, 0.05, 0.025), (ErrorScope::Pixel, 0.5, 0.35)] {
        let ((a, checks_a), (b, checks_b)) = (adaptive(scope, loose), adaptive(scope, tight));
        let (ea, eb) = (relative_error(&a, scope), relative_error(&b, scope));
        eprintln!("{scope:?}: target {loose} reached {ea:.4} at {} spp ({checks_a} checks), target {tight} reached {eb:.4} at {} spp ({checks_b} checks)", a.spp, b.spp);
        assert!(
            ea <= loose && eb <= tight,
            "{scope:?}: {ea} > {loose} or {eb} > {tight}"
        );
        assert!(
            a.spp >= MIN_ADAPTIVE_SPP && b.spp > a.spp && b.spp < cap.spp,
            "{scope:?}: {} then {} spp",
            a.spp,
            b.spp
        );
        stopped.push(a);
        stopped.push(b);
    }
    // Two of the stopped renders against fixed ones of the same spp, bit for bit.
    let fixed = render(
        &scene,
        (16, 16),
        &[
            settings(stopped[0].spp, 3, LightPaths::All, 5),
            settings(stopped[3].spp, 3, LightPaths::All, 5),
        ],
    );
    for (stopped, fixed) in [(&stopped[0], &fixed[0]), (&stopped[3], &fixed[1])] {
        assert_eq!(stopped.spp, fixed.spp);
        assert_eq!(
            (&stopped.mean, &stopped.standard_error),
            (&fixed.mean, &fixed.standard_error),
            "stopped at {} spp",
            fixed.spp
        );
    }
    // A target out of reach ends at the cap.
    let small_cap = settings(40, 3, LightPaths::All, 5);
    let img = r
        .render_until(
            &small_cap,
            Some(Stop {
                min_spp: MIN_ADAPTIVE_SPP,
                check: &mut |_| 2.0,
            }),
            &mut |_, _| {},
        )
        .expect("capped render");
    assert_eq!(img.spp, 40);
    common::assert_clean(&r.gpu);
}

/// The relative standard errors by hand on a 2-pixel image: the image's is the s.e. of the
/// image mean over that mean (worst channel), the pixel one s.e./sqrt(mean² + 0.01) at the
/// 99th percentile (here the larger pixel, worst channel); a black channel counts as 0.
#[test]
fn relative_error_follows_its_definition() {
    use penumbra::reference::{relative_error, ErrorScope};
    let mut mean = HdrImage::new(2, 1);
    let mut se = HdrImage::new(2, 1);
    mean.pixels = vec![[1.0, 0.0, 0.2, 1.0], [3.0, 0.0, 0.0, 1.0]];
    se.pixels = vec![[0.1, 0.0, 0.05, 1.0], [0.2, 0.0, 0.01, 1.0]];
    let img = ReferenceImage {
        mean,
        standard_error: se,
        spp: 100,
        seconds: 1.0,
    };
    // R: sqrt(0.01 + 0.04) / 2 over 2; B: sqrt(0.0025 + 0.0001) / 2 over 0.1.
    let image = (0.05f64.sqrt() / 2.0 / 2.0).max(0.0026f64.sqrt() / 2.0 / 0.1);
    assert!(
        (relative_error(&img, ErrorScope::Image) - image).abs() < 1e-6,
        "{} vs {image}",
        relative_error(&img, ErrorScope::Image)
    );
    // Pixel 0: R 0.1/sqrt(1.01), B 0.05/sqrt(0.05); pixel 1: R 0.2/sqrt(9.01), B 0.01/sqrt(0.01).
    let pixel = (0.1 / 1.01f64.sqrt())
        .max(0.05 / 0.05f64.sqrt())
        .max(0.2 / 9.01f64.sqrt())
        .max(0.01 / 0.01f64.sqrt());
    assert!(
        (relative_error(&img, ErrorScope::Pixel) - pixel).abs() < 1e-6,
        "{} vs {pixel}",
        relative_error(&img, ErrorScope::Pixel)
    );
}

/// `penumbra reference --max-stderr` prints the spp it used and the error it reached.
#[test]
fn command_line_max_stderr_reports_spp_and_error() {
    let out = common::temp_path("cli-max-stderr.exr");
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "reference",
            cornell.to_str().unwrap(),
            "--device",
            &device,
            "--validation",
            "--size",
            "8x8",
            "--bounces",
            "2",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args(&args)
            .output()
            .expect("run penumbra")
    };
    let o = run(&["--max-stderr", "0.03", "--stderr-over", "image"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    let line = stdout
        .lines()
        .find(|l| l.starts_with("relative standard error (image)"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(line.contains("reached") && !line.contains("NOT"), "{line}");
    let achieved: f64 = line
        .split_whitespace()
        .nth(4)
        .and_then(|v| v.trim_end_matches(':').parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!(achieved <= 0.03, "{line}");
    // The cap first: said so.
    let o = run(&["--max-stderr", "1e-6", "--spp", "40"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && stdout.contains("at 40 spp") && stdout.contains("NOT reached"),
        "{stdout}"
    );
    let o = run(&["--max-stderr", "0"]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--max-stderr"));
}

/// A batch the device cuts short for some pixels only (llvmpipe ends an invocation after
/// 65,535 loop iterations: pixels inside the box run out, pixels that see past it do not) is
/// run again with fewer samples, and the pixels that had finished it count none of its samples
/// twice: the image is bit for bit the one batches that are never cut short give.
#[test]
fn a_batch_cut_short_for_some_pixels_counts_no_sample_twice() {
    let mut scene = scene_file("cornell.toml");
    // Far back and wide: the box fills the middle, the rest of the image sees the black beyond.
    scene.camera.position.z = 7.0;
    scene.camera.fov_y_deg = 60.0;
    let mut r = ReferenceRenderer::new(common::test_gpu(), &scene, (12, 12)).expect("reference renderer");
    let plain = |spp| Settings {
        roulette_after: None,
        ..settings(spp, 32, LightPaths::All, 4)
    };
    let mut cut = None;
    // Growing batches (1, 2, 4, ...): the first one the device cuts short starts past sample 0,
    // where the pixels that finished it hold samples the rerun would add again.
    for spp in [1024, 2048, 4096] {
        let image = r.render(&plain(spp), &mut |_, _| {}).expect("render");
        println!(
            "{spp} spp in growing batches: pixels cut short per rerun {:?}",
            r.pixels_cut_short
        );
        if r.pixels_cut_short.first().is_some_and(|&n| n > 0 && n < 144) {
            cut = Some((spp, image));
            break;
        }
    }
    let (spp, image) =
        cut.expect("no batch was cut short for some pixels only: the test does not reach the case it is for");
    let small = r
        .render(
            &Settings {
                batching: Batching::Fixed(16),
                ..plain(spp)
            },
            &mut |_, _| {},
        )
        .expect("render");
    assert!(
        r.pixels_cut_short.is_empty(),
        "batches of 16 were cut short: {:?}",
        r.pixels_cut_short
    );
    assert_eq!(
        image.mean.pixels, small.mean.pixels,
        "{spp} spp in batches cut short against batches of 16"
    );
    assert_eq!(image.standard_error.pixels, small.standard_error.pixels);
    common::assert_clean(&r.gpu);
}

/// Measurement behind `ONE_LIGHT_ABOVE` (docs/reference.md, light selection): per
/// scene, samples per second and variance per sample with every light visited and with one
/// drawn, and their efficiency ratio (samples/s ÷ variance). `cargo test --release --test
/// reference light_selection_efficiency -- --ignored --nocapture`.
#[test]
#[ignore]
fn light_selection_efficiency() {
    let size = (64, 36);
    for name in [
        "many_polygon3.toml",
        "many_intersecting.toml",
        "many_slanted.toml",
        "theatre_50.toml",
        "theatre_100.toml",
    ] {
        let scene = scene_file(name);
        let lights = punctual_lights(&scene).len();
        let with = |light_selection| Settings {
            light_selection,
            batching: Batching::Fixed(16),
            ..settings(128, DEFAULT_BOUNCES, LightPaths::All, 1)
        };
        // The first render of a device also pays for its warm-up: measured again after it.
        let mut imgs = render(
            &scene,
            size,
            &[
                with(LightSelection::One),
                with(LightSelection::Every),
                with(LightSelection::One),
            ],
        );
        imgs.remove(0);
        let rate = |i: &ReferenceImage| i.samples_per_second();
        let efficiency = |i: &ReferenceImage| rate(i) / sample_variance(i);
        eprintln!(
            "{name}: {lights} lights; every {:.0} samples/s, variance {:.3e}; one {:.0} samples/s, variance {:.3e}; efficiency one / every {:.2}",
            rate(&imgs[0]),
            sample_variance(&imgs[0]),
            rate(&imgs[1]),
            sample_variance(&imgs[1]),
            efficiency(&imgs[1]) / efficiency(&imgs[0])
        );
    }
}

/// The tracer compiled for what a scene holds (glsl/reference/features.glsl: code for absent
/// kinds of light and material dropped) gives the general shader's image bit for bit. Together
/// the scenes have every feature and lack every one, and one draws one light per vertex, so a
/// feature detected wrongly, or a gate that drops code a scene runs, changes some image here.
/// Two renders of the same samples by two compilations of the tracer (specialised or general,
/// one BVH walk or the other). On a CPU device (lavapipe, where CI runs) they agree bit for bit.
/// A GPU's compiler may fuse a multiply and an add in one compilation and not in the other, and
/// a path whose random decisions then differ goes another way: there the image means must agree
/// within four standard errors (on the H200, 78 of 640 values of `terrain_cones` at 3 spp
/// differed between the specialised and the general tracer).
fn assert_same_image(gpu: &penumbra::backend::Gpu, what: &str, a: &ReferenceImage, b: &ReferenceImage) {
    assert!(
        a.mean.pixels.iter().any(|p| p[0] + p[1] + p[2] > 0.0),
        "{what}: a black image shows nothing"
    );
    if gpu.caps().device_type == ash::vk::PhysicalDeviceType::CPU {
        let bits = |img: &ReferenceImage| {
            img.mean
                .pixels
                .iter()
                .chain(&img.standard_error.pixels)
                .flat_map(|p| p.map(f32::to_bits))
                .collect::<Vec<u32>>()
        };
        let (x, y) = (bits(a), bits(b));
        let differ = x.iter().zip(&y).filter(|(p, q)| p != q).count();
        assert_eq!(differ, 0, "{what}: {differ} of {} values differ", x.len());
        return;
    }
    let ((ma, ea), (mb, eb)) = (a.average(), b.average());
    for c in 0..3 {
        let sigma = (ea[c] * ea[c] + eb[c] * eb[c]).sqrt();
        assert!(
            (ma[c] - mb[c]).abs() <= 4.0 * sigma + 1e-6 * ma[c].abs(),
            "{what}: channel {c} mean {} against {} (standard errors {} and {})",
            ma[c],
            mb[c],
            ea[c],
            eb[c]
        );
    }
}

#[test]
fn specialised_tracer_matches_the_general_one() {
    use penumbra::reference::features::SceneFeatures;
    let names = [
        "cornell.toml",
        "terrain_cones.toml",
        "sh_courtyard_sky.toml",
        "sv_glass.toml",
        "lpv_bush.toml",
        "default.toml",
        "theatre_50.toml",
    ];
    let mut seen_on = SceneFeatures {
        maps: false,
        translucency: false,
        specular: false,
        transmission: false,
        punctual_lights: false,
        sphere_lights: false,
        quad_lights: false,
        environment_map: false,
        sampled_environment: false,
    };
    let mut seen_off = seen_on;
    let run = settings(3, 3, LightPaths::All, 7);
    for name in names {
        let scene = scene_file(name);
        let mut r = ReferenceRenderer::new(common::test_gpu(), &scene, (10, 8)).expect("reference renderer");
        let f = r.features;
        assert_eq!(f, SceneFeatures::of(&r.scene));
        assert_ne!(f, SceneFeatures::ALL, "{name}: nothing to specialise");
        for (on, off, have) in [
            (&mut seen_on.maps, &mut seen_off.maps, f.maps),
            (&mut seen_on.translucency, &mut seen_off.translucency, f.translucency),
            (&mut seen_on.specular, &mut seen_off.specular, f.specular),
            (&mut seen_on.transmission, &mut seen_off.transmission, f.transmission),
            (
                &mut seen_on.punctual_lights,
                &mut seen_off.punctual_lights,
                f.punctual_lights,
            ),
            (&mut seen_on.sphere_lights, &mut seen_off.sphere_lights, f.sphere_lights),
            (&mut seen_on.quad_lights, &mut seen_off.quad_lights, f.quad_lights),
            (
                &mut seen_on.environment_map,
                &mut seen_off.environment_map,
                f.environment_map,
            ),
            (
                &mut seen_on.sampled_environment,
                &mut seen_off.sampled_environment,
                f.sampled_environment,
            ),
        ] {
            *on |= have;
            *off |= !have;
        }
        let specialised = r.render(&run, &mut |_, _| {}).expect("render");
        r.features = SceneFeatures::ALL;
        let general = r.render(&run, &mut |_, _| {}).expect("render");
        common::assert_clean(&r.gpu);
        assert_same_image(
            &r.gpu,
            &format!("{name}, specialised against general"),
            &specialised,
            &general,
        );
    }
    assert_eq!(seen_on, SceneFeatures::ALL, "some feature is in none of the scenes");
    assert_eq!(seen_off, SceneFeatures::ALL, "some feature is in every scene");
}

/// The stack walk and the stackless walk ordered per ray octant find the same closest hits, so
/// the same image (assert_same_image), on scenes with walls seen from inside (Cornell box), a dense
/// closed mesh (furnace), a height field, leaves with translucency and textures.
#[test]
fn both_bvh_walks_give_the_same_image() {
    use penumbra::reference::features::BvhWalk;
    let run = settings(3, 4, LightPaths::All, 11);
    for name in [
        "cornell.toml",
        "furnace.toml",
        "terrain_cones.toml",
        "lpv_bush.toml",
        "sh_courtyard_sky.toml",
    ] {
        let scene = scene_file(name);
        // Made for the stack walk, whose table of octant links is one zeroed texel: the ordered
        // walk uploads its links when it is first used.
        let mut r = ReferenceRenderer::with_walk(common::test_gpu(), &scene, (12, 10), BvhWalk::Stack)
            .expect("reference renderer");
        let mut images = Vec::new();
        for walk in [BvhWalk::Stack, BvhWalk::Ordered] {
            r.walk = walk;
            images.push(r.render(&run, &mut |_, _| {}).expect("render"));
        }
        common::assert_clean(&r.gpu);
        assert_same_image(
            &r.gpu,
            &format!("{name}, stack walk against ordered walk"),
            &images[0],
            &images[1],
        );
    }
}
