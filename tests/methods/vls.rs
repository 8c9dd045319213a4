//! Virtualised light sources drawn (Ridderhof 2002, digest §1.4): the shader's light models equal the
//! CPU's (`ManyLight::shade`) pixel by pixel, the physical one equals `forward` where every light
//! is kept, a segment with more than K lights shades with exactly its baked set, and static
//! intensities give bit-identical frames (item 23).

use crate::support as common;

use glam::{DVec3, Vec3};
use penumbra::lighting::lightmap::geometry::scene_geometry;
use penumbra::lighting::many_lights::{LightModel, ManyLight};
use penumbra::lighting::vls::{Config, Layout};
use penumbra::lighting::{registry, ReferenceKind};
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

const SIZE: (u32, u32) = (64, 48);

/// A 4 × 4 floor (ρ = 0.5, facing +y) seen from above, no environment, lit by LIGHTS.
const FLOOR: &str = r#"
methods = [METHOD]

[camera]
position = [0.0, 4.0, 2.5]
target = [0.0, 0.0, 0.0]
fov_y_deg = 60

[[materials]]
name = "grey"
albedo = 0.5

[[objects]]
name = "floor"
mesh = "quad"
corner = [-2, 0, -2]
edge_u = [0, 0, 4]
edge_v = [4, 0, 0]
material = "grey"
"#;

/// A light as the tests write it: position, spot (target, inner and outer degrees), intensity.
type TestLight = (Vec3, Option<(Vec3, f32, f32)>, Vec3);

fn lights_text(lights: &[TestLight]) -> String {
    let mut s = String::new();
    for (i, (p, spot, intensity)) in lights.iter().enumerate() {
        s += &format!(
            "\n[[lights]]\nname = \"l{i}\"\nposition = [{}, {}, {}]\nintensity = [{}, {}, {}]\n",
            p.x, p.y, p.z, intensity.x, intensity.y, intensity.z
        );
        match spot {
            None => s += "type = \"point\"\n",
            Some((target, inner, outer)) => {
                s += &format!(
                    "type = \"spot\"\ntarget = [{}, {}, {}]\ninner_deg = {inner}\nouter_deg = {outer}\n",
                    target.x, target.y, target.z
                )
            }
        }
    }
    s
}

fn three_lights() -> String {
    lights_text(&[
        (
            Vec3::new(0.3, 3.0, 0.2),
            Some((Vec3::new(0.0, 0.0, 0.0), 20.0, 35.0)),
            Vec3::new(6.0, 5.0, 4.0),
        ),
        (
            Vec3::new(-1.5, 2.0, 1.0),
            Some((Vec3::new(0.5, 0.0, -0.5), 25.0, 40.0)),
            Vec3::new(2.0, 3.0, 4.0),
        ),
        (Vec3::new(1.2, 1.5, -1.0), None, Vec3::new(1.0, 1.0, 1.0)),
    ])
}

/// Twelve spots and points scattered over the floor: more than K.
fn twelve_lights() -> String {
    let mut lights = Vec::new();
    for i in 0..12 {
        let a = i as f32 * 0.52;
        let p = Vec3::new(1.6 * a.cos(), 0.8 + 0.15 * i as f32, 1.6 * a.sin());
        let spot = (i % 3 != 0).then(|| (Vec3::new(0.6 * a.sin(), 0.0, -0.6 * a.cos()), 25.0, 45.0));
        lights.push((p, spot, Vec3::new(1.0 + 0.1 * i as f32, 1.0, 2.0 - 0.1 * i as f32)));
    }
    lights_text(&lights)
}

fn scene(methods: &str, lights: &str) -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    Scene::from_str(&(FLOOR.replace("METHOD", methods) + lights), "vls test", &dir).unwrap_or_else(|e| panic!("{e}"))
}

fn render(scene: Scene, method: &str) -> HdrImage {
    let mut r = Renderer::new(common::test_gpu(), scene, Some(method), SIZE, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

/// Pixel centres whose camera ray meets the floor well inside its edges, with the point hit.
fn floor_pixels(scene: &Scene) -> Vec<(usize, DVec3)> {
    let (w, h) = SIZE;
    let mut out = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (o, d) = scene.camera.pixel_center_ray(i, j, w, h);
            if d.y >= -1e-3 {
                continue;
            }
            let p = (o + d * (-o.y / d.y)).as_dvec3();
            if p.x.abs() < 1.95 && p.z.abs() < 1.95 {
                out.push(((j * w + i) as usize, DVec3::new(p.x, 0.0, p.z)));
            }
        }
    }
    out
}

fn close(got: [f32; 4], want: DVec3, rel: f64) -> bool {
    (0..3).all(|c| (got[c] as f64 - want[c]).abs() <= rel * want[c].abs() + 1e-6)
}

/// The shader twin of the CPU models: each model's frame is Σ ManyLight::shade at every pixel's
/// floor point (all three lights kept: K = 8, `closest`, no `can_illuminate`).
#[test]
fn the_shader_models_equal_the_cpu_models() {
    for (decl, model) in [
        (
            r#"{ name = "vls", model = "physical", selection = "closest", can_illuminate = false }"#,
            LightModel::Physical,
        ),
        (
            r#"{ name = "vls", model = "seed", seed_k = 0.5, selection = "closest", can_illuminate = false }"#,
            LightModel::Seed { k: 0.5 },
        ),
        (
            r#"{ name = "vls", model = "opengl", kc = 1.0, kl = 0.3, kq = 0.2, ambient = 0, selection = "closest", can_illuminate = false }"#,
            LightModel::OpenGl {
                kc: 1.0,
                kl: 0.3,
                kq: 0.2,
            },
        ),
    ] {
        let s = scene(decl, &three_lights());
        let lights = ManyLight::from_scene(&s, "vls").unwrap();
        let pixels = floor_pixels(&s);
        let img = render(s, "vls");
        let (mut worst, mut lit) = (0.0f64, 0);
        for &(i, p) in &pixels {
            let want: DVec3 = lights
                .iter()
                .map(|l| l.shade(&model, p, DVec3::Y, DVec3::splat(0.5)))
                .sum();
            let got = img.pixels[i];
            lit += usize::from(want.x > 1e-4);
            worst = worst.max((got[0] as f64 - want.x).abs() / want.x.max(1e-6));
            assert!(close(got, want, 2e-3), "{decl}: pixel {i} at {p}: {got:?}, CPU {want}");
        }
        println!(
            "{decl}: {} floor pixels ({lit} lit), worst relative difference {worst:.2e}",
            pixels.len()
        );
        assert!(
            lit > pixels.len() / 3,
            "too few lit pixels for the test to mean anything: {lit}"
        );
    }
}

/// The thesis's fixed-function light model in full (§4.3.1): global ambient × albedo, plus per
/// light attenuation × spot × (light ambient + diffuse + specular), the specular term
/// Blinn-Phong from the eye with the material's colour and exponent, only where N·L > 0. Each
/// pixel of the faithful frame against that formula written out here, on a glossy floor.
#[test]
fn the_faithful_light_model_has_the_theses_ambient_and_specular_terms() {
    let (ambient, light_ambient, ks, shininess) = (0.15, 0.3, 0.4, 24.0);
    let decl = format!(
        r#"{{ name = "vls", mode = "faithful", kl = 0.3, kq = 0.2, ambient = {ambient}, light_ambient = {light_ambient}, selection = "closest", can_illuminate = false }}"#
    );
    let glossy = "albedo = 0.5\n";
    let s = scene(&decl, &three_lights());
    let text = FLOOR
        .replace("METHOD", &decl)
        .replace(glossy, &format!("{glossy}specular = {ks}\nexponent = {shininess}\n"))
        + &three_lights();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let glossy_scene = Scene::from_str(&text, "vls test", &dir).unwrap_or_else(|e| panic!("{e}"));
    assert_ne!(glossy_scene.materials[0].specular, Vec3::ZERO);
    let eye = s.camera.position.as_dvec3();
    let lights = ManyLight::from_scene(&s, "vls").unwrap();
    let pixels = floor_pixels(&s);
    let img = render(glossy_scene, "vls");
    let albedo = 0.5;
    let (mut worst, mut specular_share) = (0.0f64, 0.0f64);
    for &(i, p) in &pixels {
        let n = DVec3::Y;
        let mut want = DVec3::splat(ambient * albedo);
        let mut highlight = DVec3::ZERO;
        for l in &lights {
            let to = l.position - p;
            let d = to.length();
            let dir = to / d;
            let spot = match l.cone {
                None => 1.0,
                Some((full, null)) => {
                    let c = (-dir).dot(l.direction);
                    let e = (0.5f64.ln() / full.cos().ln()).clamp(0.0, 128.0);
                    if c < null.cos() {
                        0.0
                    } else {
                        c.max(0.0).powf(e)
                    }
                }
            };
            let reach = spot / (1.0 + 0.3 * d + 0.2 * d * d);
            let cos = n.dot(dir);
            let mut terms = light_ambient * albedo + albedo * cos.max(0.0);
            if cos > 0.0 {
                let h = (dir + (eye - p).normalize()).normalize();
                let s = ks * n.dot(h).max(0.0).powf(shininess);
                terms += s;
                highlight += l.intensity * reach * s;
            }
            want += l.intensity * reach * terms;
        }
        let got = img.pixels[i];
        worst = worst.max((got[0] as f64 - want.x).abs() / want.x);
        specular_share = specular_share.max(highlight.x / want.x);
        assert!(close(got, want, 2e-3), "pixel {i} at {p}: {got:?}, closed form {want}");
    }
    println!(
        "{} floor pixels: worst relative difference {worst:.2e}; the specular term up to {:.0} % of a pixel",
        pixels.len(),
        100.0 * specular_share
    );
    // The terms are there to be seen: the highlight is a sizeable part of the brightest pixels.
    assert!(specular_share > 0.2, "specular share {specular_share}");
}

/// Where every light is kept and none is blocked, the physical model is `forward`'s diffuse
/// term and the frames agree to fp32.
#[test]
fn physical_vls_equals_forward_without_dropped_lights() {
    let methods = r#"{ name = "vls", mode = "corrected", selection = "closest", can_illuminate = false }, "forward""#;
    physical_vls_equals_forward(&scene(methods, &three_lights()));
    // A glossy floor: the physical model has forward's Blinn-Phong lobe too (without it the
    // floor reads darker wherever the lobe reaches the camera).
    let glossy = FLOOR.replace("albedo = 0.5", "albedo = 0.5\nspecular = 0.3\nexponent = 20");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = glossy.replace("METHOD", methods) + &three_lights();
    physical_vls_equals_forward(&Scene::from_str(&text, "vls test", &dir).unwrap_or_else(|e| panic!("{e}")));
}

fn physical_vls_equals_forward(s: &Scene) {
    let s = s.clone();
    let pixels = floor_pixels(&s);
    let vls = render(s.clone(), "vls");
    let forward = render(s, "forward");
    let mut worst = 0.0f64;
    for &(i, _) in &pixels {
        let (a, b) = (vls.pixels[i], forward.pixels[i]);
        for c in 0..3 {
            let d = (a[c] - b[c]).abs() as f64 / (b[c].abs() as f64).max(1e-4);
            worst = worst.max(d);
            assert!(d < 1e-4, "pixel {i}: vls {a:?}, forward {b:?}");
        }
    }
    println!(
        "vls against forward over {} floor pixels: worst relative difference {worst:.2e}",
        pixels.len()
    );
}

/// Twelve lights over the floor and K = 4: the light sets keep the four strongest at every
/// point and the renderer's warnings say how many points lost light; with K = 16 every light is
/// kept and nothing is said.
#[test]
fn light_dropped_past_k_is_warned_about() {
    let warnings = |k: u32| {
        let methods = format!(r#"{{ name = "vls", k = {k} }}"#);
        let mut r = Renderer::new(
            common::test_gpu(),
            scene(&methods, &twelve_lights()),
            Some("vls"),
            SIZE,
            1,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let cam = r.scene.camera.clone();
        r.render(&cam, FrameOutput::None).unwrap();
        let w = r.method_warnings().unwrap();
        common::assert_clean(&r.gpu);
        w
    };
    let few = warnings(4);
    println!("{few:?}");
    assert!(
        few.len() == 1 && few[0].starts_with("vls: at ") && few[0].contains("more than k = 4 lights reach"),
        "{few:?}"
    );
    assert!(warnings(16).is_empty(), "16 slots hold all 12 lights");
}

/// The corrected default keeps every light that reaches a point, up to 32, in sets no wider
/// than the fullest: twelve lights over the floor fill each segment's set with exactly the lights
/// whose light reaches its centroid, and nothing is dropped; twelve narrow spots, each on its own
/// part of the floor, leave sets only as wide as the most that overlap. The plan says what it
/// chose.
#[test]
fn the_default_keeps_every_light_in_reach_and_no_more_slots() {
    let check = |lights: &str| -> (usize, usize) {
        let s = scene(r#""vls""#, lights);
        let config = Config::from_decl_in(&s.methods[0], Some(&s)).unwrap();
        assert_eq!(config.setup.k, 32, "the corrected default's cap");
        let geometry = scene_geometry(&s, "vls").unwrap();
        let layout = Layout::new(&s, &geometry, &s.methods[0], &config).unwrap();
        let sets = layout.select(&config.setup, &mut penumbra::util::progress::Progress::new("test"));
        let segments = &layout.segments;
        let mut fullest = 0;
        for t in 0..segments.triangles.len() {
            let p = segments.centroid(t);
            let reach = (layout.lights.iter())
                .filter(|l| l.shade(&LightModel::Physical, p, DVec3::Y, DVec3::ONE).max_element() > 0.0)
                .count();
            assert_eq!(sets.of(t).count(), reach, "segment {t} at {p}");
            fullest = fullest.max(reach);
        }
        assert_eq!(sets.crowded, 0);
        assert_eq!(sets.k, fullest, "the sets' width");
        let config = registry::configuration(&s, Some("vls")).unwrap();
        let (_, notes) = registry::plan(&config, &s).unwrap();
        assert!(
            notes
                .iter()
                .any(|n| n.starts_with("vls: k = 12 (every one of the scene's 12 lights")),
            "{notes:?}"
        );
        (sets.k, layout.lights.len())
    };
    let (wide, lights) = check(&twelve_lights());
    println!("twelve lights: sets {wide} wide");
    assert!(wide > 8, "more than the thesis's 8 reach some point: {wide}");
    let mut narrow = Vec::new();
    for i in 0..12 {
        let a = i as f32 * std::f32::consts::TAU / 12.0;
        let target = Vec3::new(1.5 * a.cos(), 0.0, 1.5 * a.sin());
        narrow.push((target + Vec3::Y * 2.0, Some((target, 8.0, 12.0)), Vec3::splat(1.0)));
    }
    let (narrowed, _) = check(&lights_text(&narrow));
    println!("twelve narrow spots: sets {narrowed} wide");
    assert!(narrowed < lights / 2, "{narrowed} slots for spots that barely overlap");
}

/// As a direct term over another method's base (`forward`'s, under a constant sky), VLS adds
/// its light to every floor pixel despite drawing other triangles than the base (its depth bias
/// lets it pass the base's depth): the frame equals VLS drawing both terms itself, and without
/// any base (the renderer's own depth pass) it is that frame less the sky's light.
#[test]
fn as_a_direct_term_it_adds_over_another_base() {
    let methods = r#"{ name = "vls", selection = "closest", can_illuminate = false }, "forward""#;
    let extra = "\n[environment]\ntype = \"constant\"\nradiance = 0.3\n\n[[combinations]]\nname = \"over_forward\"\nbase = \"forward\"\ndirect = \"vls\"\n\n[[combinations]]\nname = \"direct_alone\"\ndirect = \"vls\"\n";
    let s = scene(methods, &(three_lights() + extra));
    let pixels = floor_pixels(&s);
    let alone = render(s.clone(), "vls");
    let over = render(s.clone(), "over_forward");
    let direct = render(s, "direct_alone");
    // The floor's sky light: rho/pi * E with E = pi * 0.3 for a constant sky over a plane.
    let sky = 0.5 * 0.3;
    for &(i, p) in &pixels {
        let (a, b, d) = (alone.pixels[i], over.pixels[i], direct.pixels[i]);
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() <= 1e-4 * a[c].abs() + 1e-6,
                "pixel {i} at {p}: vls {a:?}, vls over forward {b:?}"
            );
            assert!(
                (d[c] + sky - a[c]).abs() <= 2e-3 * a[c].abs() + 1e-4,
                "pixel {i} at {p}: direct alone {d:?} + sky {sky} vs {a:?}"
            );
        }
    }
}

/// With 12 lights and K = 3, each pixel shows exactly the sum over its segment's baked set (the
/// CPU recomputes the same sets) at the frame's intensities, changed every frame, so the index
/// buffer, the unshared vertices' segment ids and the shader agree; some neighbouring segments
/// differ (the seams are drawn).
#[test]
fn a_segment_shades_with_exactly_its_light_set() {
    let decl = r#"{ name = "vls", mode = "faithful", k = 3, feeler = "bvh", max_segment_area = 0.1, ambient = 0 }"#;
    let s = scene(decl, &twelve_lights());
    let config = Config::from_decl_in(&s.methods[0], Some(&s)).unwrap();
    let geometry = scene_geometry(&s, "vls").unwrap();
    let layout = Layout::new(&s, &geometry, &s.methods[0], &config).unwrap();
    let sets = layout.select(&config.setup, &mut penumbra::util::progress::Progress::new("test"));
    let (segments, lights) = (&layout.segments, &layout.lights);
    let pixels = floor_pixels(&s);
    let model = LightModel::OpenGl {
        kc: 1.0,
        kl: 0.0,
        kq: 1.0,
    };
    // The segment holding each pixel's point, away from its edges (a pixel on an edge may go to
    // either side).
    let owners: Vec<Option<usize>> = pixels
        .iter()
        .map(|&(_, p)| {
            (0..segments.triangles.len()).find(|&t| {
                let [a, b, c] = segments.triangles[t].map(|k| segments.positions[k as usize]);
                let n = (b - a).cross(c - a);
                let w = [
                    (c - b).cross(p - b).dot(n),
                    (a - c).cross(p - c).dot(n),
                    (b - a).cross(p - a).dot(n),
                ]
                .map(|x| x / n.length_squared());
                w.iter().all(|&x| x > 0.02)
            })
        })
        .collect();
    let mut r = Renderer::new(common::test_gpu(), s, Some("vls"), SIZE, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let full: Vec<[f32; 4]> = r.scene_gpu.lights.iter().map(|l| l.intensity).collect();
    // On the GPU: new intensities every frame (as a light board sets them), the same
    // sets, and every pixel the sum over its set at this frame's intensities.
    let mut rng = crate::support::rng::Lcg(12345);
    for frame in 0..3 {
        let scale: Vec<f64> = (0..full.len())
            .map(|_| {
                let u = rng.next_f32() as f64;
                if frame == 0 {
                    1.0
                } else {
                    u
                }
            })
            .collect();
        for ((l, f), &k) in r.scene_gpu.lights.iter_mut().zip(&full).zip(&scale) {
            let k = k as f32;
            l.intensity = [f[0] * k, f[1] * k, f[2] * k, f[3]];
        }
        let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
        let (mut checked, mut distinct) = (0, std::collections::BTreeSet::new());
        for (&(i, p), owner) in pixels.iter().zip(&owners) {
            let Some(t) = *owner else { continue };
            let set: Vec<usize> = sets.of(t).collect();
            distinct.insert(set.clone());
            let want: DVec3 = set
                .iter()
                .map(|&l| lights[l].shade(&model, p, DVec3::Y, DVec3::splat(0.5)) * (scale[l] as f32) as f64)
                .sum();
            assert!(
                close(img.pixels[i], want, 2e-3),
                "frame {frame}: pixel {i} in segment {t} (lights {set:?}): {:?}, CPU {want}",
                img.pixels[i]
            );
            checked += 1;
        }
        println!(
            "frame {frame}: {checked} pixels checked against their segment's set; {} distinct sets",
            distinct.len()
        );
        assert!(
            checked > pixels.len() / 2 && distinct.len() > 3,
            "{checked} pixels, {} sets",
            distinct.len()
        );
    }
    common::assert_clean(&r.gpu);
}

/// `point = "vertex"`: light sets at the segment vertices, shaded per vertex and interpolated
/// (fixed-function OpenGL's Gouraud): with every light kept each pixel is the barycentric blend
/// of Σ `ManyLight::shade` at its segment's corners.
#[test]
fn per_vertex_sets_shade_at_the_vertices() {
    let decl =
        r#"{ name = "vls", point = "vertex", selection = "closest", can_illuminate = false, max_segment_area = 0.1 }"#;
    let s = scene(decl, &three_lights());
    let config = Config::from_decl_in(&s.methods[0], Some(&s)).unwrap();
    let geometry = scene_geometry(&s, "vls").unwrap();
    let layout = Layout::new(&s, &geometry, &s.methods[0], &config).unwrap();
    let (segments, lights) = (&layout.segments, &layout.lights);
    let pixels = floor_pixels(&s);
    let img = render(s, "vls");
    let at = |q: DVec3| -> DVec3 {
        lights
            .iter()
            .map(|l| l.shade(&LightModel::Physical, q, DVec3::Y, DVec3::splat(0.5)))
            .sum()
    };
    let (mut checked, mut off_per_pixel) = (0, 0.0f64);
    for &(i, p) in &pixels {
        let found = (0..segments.triangles.len()).find_map(|t| {
            let [a, b, c] = segments.triangles[t].map(|k| segments.positions[k as usize]);
            let n = (b - a).cross(c - a);
            let w = [
                (c - b).cross(p - b).dot(n),
                (a - c).cross(p - c).dot(n),
                (b - a).cross(p - a).dot(n),
            ]
            .map(|x| x / n.length_squared());
            w.iter().all(|&x| x >= 0.0).then_some(([a, b, c], w))
        });
        let Some((corners, w)) = found else { continue };
        let want = at(corners[0]) * w[0] + at(corners[1]) * w[1] + at(corners[2]) * w[2];
        assert!(
            close(img.pixels[i], want, 2e-3),
            "pixel {i} at {p}: {:?}, interpolated CPU {want}",
            img.pixels[i]
        );
        off_per_pixel = off_per_pixel.max((want.x - at(p).x).abs() / at(p).x.max(1e-6));
        checked += 1;
    }
    println!(
        "{checked} pixels equal the interpolated vertex sums; per-pixel shading differs by up to {:.1} %",
        100.0 * off_per_pixel
    );
    assert!(
        checked > pixels.len() / 2 && off_per_pixel > 1e-3,
        "{checked} pixels, {off_per_pixel}"
    );
}

/// Static intensities give the same bytes every frame, for 100 frames.
#[test]
fn frames_are_bit_identical_with_static_intensities() {
    let s = scene(r#"{ name = "vls", k = 3 }"#, &twelve_lights());
    let mut r = Renderer::new(common::test_gpu(), s, Some("vls"), SIZE, 2).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let first = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    assert!(first.pixels.iter().any(|p| p[0] > 0.0));
    for frame in 1..100 {
        let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
        assert!(img.pixels == first.pixels, "frame {frame} differs from frame 0");
    }
    common::assert_clean(&r.gpu);
}

/// The registry entry: direct light both terms, separable, no translucency.
#[test]
fn the_registry_entry() {
    let info = registry::info("vls").unwrap();
    assert!(info.separable && !info.translucency);
    assert_eq!(info.terms, penumbra::lighting::Terms::BASE_DIRECT);
    let s = scene(r#""vls""#, &three_lights());
    assert_eq!((info.reference)(&s.methods[0]), ReferenceKind::Direct);
}

/// Frame time against the number of lights, VLS (K = 8) beside forward's loop over every light
/// (`cargo test --release --test methods vls::frame_time -- --ignored --nocapture`): VLS should level off
/// once every segment's 8 slots are full.
#[test]
#[ignore]
fn frame_time_against_lights() {
    println!("{:>6} {:>10} {:>12}", "lights", "vls ms", "forward ms");
    for n in [1usize, 2, 4, 8, 16, 32, 64, 128, 256] {
        let mut lights = Vec::new();
        for i in 0..n {
            let a = i as f32 * 2.399;
            let r = 1.9 * ((i as f32 + 0.5) / n as f32).sqrt();
            let p = Vec3::new(r * a.cos(), 2.5, r * a.sin());
            lights.push((p, Some((p - Vec3::new(0.0, 2.5, 0.0), 25.0, 45.0)), Vec3::splat(1.0)));
        }
        let methods = r#"{ name = "vls", max_segment_area = 0.02, k = 8 }, "forward""#;
        let s = scene(methods, &lights_text(&lights));
        let mut times = Vec::new();
        for method in ["vls", "forward"] {
            let mut r = Renderer::new(common::test_gpu(), s.clone(), Some(method), (640, 480), 1)
                .unwrap_or_else(|e| panic!("{e}"));
            let cam = r.scene.camera.clone();
            for _ in 0..3 {
                r.render(&cam, FrameOutput::Readback).unwrap();
            }
            let start = std::time::Instant::now();
            for _ in 0..10 {
                r.render(&cam, FrameOutput::Readback).unwrap();
            }
            times.push(start.elapsed().as_secs_f64() * 1e3 / 10.0);
        }
        println!("{n:>6} {:>10.2} {:>12.2}", times[0], times[1]);
    }
}
