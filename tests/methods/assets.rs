//! Assets rendered: an OBJ + MTL and a glTF file written by the test, drawn by `forward` and traced
//! by the reference, each pixel compared with the closed form at the point its centre ray hits;
//! and a cut-out leaf (`map_d`) traced with the light through its holes.

use crate::support as common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use penumbra::gpu_scene::punctual_lights;
use penumbra::lighting::brdf::{shade, Surface};
use penumbra::reference::{Batching, LightPaths, ReferenceRenderer, Settings};
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

const W: u32 = 48;
const H: u32 = 36;

fn temp_dir(name: &str) -> common::test_files::TestDir {
    common::test_files::TestDir::new(&format!("assets-{name}"))
}

fn write_png(path: &Path, rgba: [u8; 4]) {
    image::RgbaImage::from_pixel(1, 1, image::Rgba(rgba))
        .save(path)
        .unwrap();
}

/// The sRGB decoding curve (IEC 61966-2-1), independent of the renderer's tables.
fn srgb(byte: u8) -> f32 {
    let c = f32::from(byte) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn forward(scene: &Scene) -> HdrImage {
    let mut r = Renderer::new(common::test_gpu(), scene.clone(), None, (W, H), 1).unwrap();
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

/// Where the ray through continuous pixel coordinates (x, y) meets the plane y = 0.
fn ground(scene: &Scene, x: f32, y: f32) -> Option<Vec3> {
    let (o, d) = scene.camera.ray(x, y, W, H);
    (d.y < 0.0).then(|| o + d * (-o.y / d.y))
}

/// Two textured quads side by side (x in [-1, 0] and [0, 1], z in [-1, 1], facing +y), one
/// material each, placed by the scene at `x' = 2 x + 0.5`.
const OBJ: &str = "mtllib quads.mtl
v -1 0 -1\nv -1 0 1\nv 0 0 1\nv 0 0 -1\nv 1 0 1\nv 1 0 -1
vt 0 0\nvt 0 1\nvt 1 1\nvt 1 0
vn 0 1 0
usemtl a
f 1/1/1 2/2/1 3/3/1 4/4/1
usemtl b
f 4/1/1 3/2/1 5/3/1 6/4/1
";

const TEXEL_A: [u8; 4] = [200, 150, 100, 255];
const TEXEL_B: [u8; 4] = [40, 180, 230, 255];
const KD_A: Vec3 = Vec3::new(0.9, 0.8, 0.7);
const KD_B: Vec3 = Vec3::new(0.5, 1.0, 0.6);
const SUN: Vec3 = Vec3::new(-0.3, -1.0, -0.4);
const E: Vec3 = Vec3::new(3.0, 2.5, 2.0);

/// The scene, and its directory (the textures load with the renderer, so it must outlive it).
fn obj_scene(name: &str) -> (Scene, common::test_files::TestDir) {
    let dir = temp_dir(name);
    write_png(&dir.join("a.png"), TEXEL_A);
    write_png(&dir.join("b.png"), TEXEL_B);
    std::fs::write(
        dir.join("quads.mtl"),
        format!(
            "newmtl a\nKd {} {} {}\nKs 0 0 0\nmap_Kd a.png\nnewmtl b\nKd {} {} {}\nKs 0 0 0\nmap_Kd b.png\n",
            KD_A.x, KD_A.y, KD_A.z, KD_B.x, KD_B.y, KD_B.z
        ),
    )
    .unwrap();
    std::fs::write(dir.join("quads.obj"), OBJ).unwrap();
    let toml = format!(
        "[camera]\nposition = [0.8, 4.0, 3.5]\ntarget = [0.5, 0.0, 0.0]\nfov_y_deg = 50\n\n\
         [[objects]]\nmesh = \"asset\"\npath = \"quads.obj\"\ntranslate = [0.5, 0, 0]\nscale = 2\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [{}, {}, {}]\nirradiance = [{}, {}, {}]\n",
        SUN.x, SUN.y, SUN.z, E.x, E.y, E.z
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    (Scene::from_file(dir.join("scene.toml")).unwrap(), dir)
}

/// The closed form at a ground point: which quad (object space x = (p.x − 0.5)/2) and its
/// ρ/π E cos θ, or 0 well outside both; `None` within `margin` (object units) of an edge.
fn obj_want(p: Vec3, margin: f32) -> Option<Vec3> {
    let q = Vec3::new((p.x - 0.5) / 2.0, 0.0, p.z / 2.0);
    let cos = (-SUN.normalize()).y;
    let lit =
        |kd: Vec3, t: [u8; 4]| kd * Vec3::new(srgb(t[0]), srgb(t[1]), srgb(t[2])) / std::f32::consts::PI * E * cos;
    if q.x.abs() > 1.0 + margin || q.z.abs() > 1.0 + margin {
        return Some(Vec3::ZERO);
    }
    if q.z.abs() > 1.0 - margin || q.x.abs() > 1.0 - margin || q.x.abs() < margin {
        return None;
    }
    Some(if q.x < 0.0 {
        lit(KD_A, TEXEL_A)
    } else {
        lit(KD_B, TEXEL_B)
    })
}

/// Checks every pixel with a sure answer against `want` (relative `tol`, of at least 0.05 for
/// dim channels), returning how many pixels were lit and how many dark.
fn check(img: &HdrImage, want: impl Fn(u32, u32) -> Option<Vec3>, tol: f32) -> (u32, u32) {
    let (mut lit, mut dark) = (0, 0);
    for j in 0..H {
        for i in 0..W {
            let Some(w) = want(i, j) else { continue };
            let p = img.get(i, j);
            for c in 0..3 {
                let err = (p[c] - w[c]).abs();
                assert!(
                    err <= tol * w[c].max(0.05),
                    "pixel ({i},{j}) channel {c}: {} vs {}",
                    p[c],
                    w[c]
                );
            }
            if w == Vec3::ZERO {
                dark += 1;
            } else {
                lit += 1;
            }
        }
    }
    (lit, dark)
}

/// The direct-light reference at 4 spp (the scenes' light is a sun or a point: no noise to speak of).
fn direct_reference(scene: &Scene) -> HdrImage {
    let mut r = ReferenceRenderer::new(common::test_gpu(), scene, (W, H)).unwrap();
    let settings = Settings {
        spp: 4,
        bounces: 0,
        paths: LightPaths::Direct,
        seed: 1,
        batching: Batching::Adaptive,
        ..Settings::default()
    };
    let img = r.render(&settings, &mut |_, _| {}).unwrap();
    common::assert_clean(&r.gpu);
    img.mean
}

/// The answer at pixel (i, j) where `at` gives the same at its four corners, else `None`: the
/// reference averages each pixel's footprint, so only such pixels have one answer.
fn footprint<T: PartialEq + Copy>(i: u32, j: u32, at: impl Fn(f32, f32) -> Option<T>) -> Option<T> {
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(dx, dy)| at(i as f32 + dx, j as f32 + dy));
    let first = corners[0]?;
    corners.iter().all(|c| *c == Some(first)).then_some(first)
}

#[test]
fn obj_mtl_textured_quads_under_a_directional_light() {
    let (scene, _dir) = obj_scene("forward");
    assert_eq!(scene.objects.len(), 2, "one draw per material");
    let img = forward(&scene);
    let want = |i: u32, j: u32| obj_want(ground(&scene, i as f32 + 0.5, j as f32 + 0.5)?, 0.05);
    // The sampler's 8-bit sRGB decoding is approximate (lavapipe: 0.67% at byte 100, 4e-4 of
    // 0.05 at byte 40, measured); the two materials differ by far more than that.
    let (lit, dark) = check(&img, want, 8e-3);
    assert!(lit > 300 && dark > 100, "{lit} lit, {dark} dark pixels");
}

#[test]
fn reference_sees_the_asset_materials() {
    let (scene, _dir) = obj_scene("reference");
    let img = direct_reference(&scene);
    let want = |i, j| footprint(i, j, |x, y| ground(&scene, x, y).and_then(|p| obj_want(p, 0.02)));
    let (lit, dark) = check(&img, want, 2e-3);
    assert!(lit > 300 && dark > 100, "{lit} lit, {dark} dark pixels");
}

/// A glTF with a 2 × 2 quad (y = 0, facing +y) under a node hierarchy, a point light in candela
/// and a camera, written with its buffer as a data URI.
fn gltf_file(dir: &Path) -> PathBuf {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    use base64::Engine as _;
    let mut bytes = Vec::new();
    let positions = [
        [-1.0f32, 0.0, -1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
    ];
    for p in positions {
        bytes.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    for _ in 0..4 {
        bytes.extend([0.0f32, 1.0, 0.0].iter().flat_map(|c| c.to_le_bytes()));
    }
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsRequired": ["KHR_lights_punctual"],
        "extensionsUsed": ["KHR_lights_punctual"],
        "scenes": [{"nodes": [0, 2, 3]}],
        "nodes": [
            {"translation": [1.0, 0.0, 0.0], "children": [1]},
            {"mesh": 0, "scale": [1.5, 1.0, 1.0]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.7, 1.2, 0.3]},
            {"camera": 0, "translation": [1.0, 4.0, 0.0], "rotation": [-h, 0.0, 0.0, h]}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.05}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1.0, 0.9, 0.8], "intensity": 2049.0}]}},
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "buffers": [{"byteLength": bytes.len(), "uri": uri}]
    });
    let path = dir.join("lit.gltf");
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

#[test]
fn gltf_alone_node_transform_and_punctual_light_in_candela() {
    let dir = temp_dir("gltf");
    let scene = Scene::from_file(gltf_file(&dir)).unwrap();
    // Its own camera and light: no sky added.
    assert!(scene.environment.is_none() && scene.lights.len() == 1);
    let img = forward(&scene);
    let m = &scene.materials[0];
    let surface = Surface {
        albedo: m.albedo,
        specular: m.specular,
        exponent: m.exponent,
        emission: Vec3::ZERO,
    };
    let lights = punctual_lights(&scene);
    // 2049 cd × (1, 0.9, 0.8) / 683 lm/W = (3, 2.7, 2.4) W/sr, at (0.7, 1.2, 0.3).
    let light = Vec3::new(0.7, 1.2, 0.3);
    let intensity = Vec3::new(3.0, 2.7, 2.4);
    let (mut inside, mut outside) = (0, 0);
    let want = |i: u32, j: u32| {
        let p = ground(&scene, i as f32 + 0.5, j as f32 + 0.5)?;
        // The quad spans x in [1 - 1.5, 1 + 1.5], z in [-1, 1] (node 0 · node 1).
        let (dx, dz) = ((p.x - 1.0).abs() / 1.5, p.z.abs());
        if dx > 1.02 || dz > 1.02 {
            return Some(Vec3::ZERO);
        }
        if dx > 0.98 || dz > 0.98 {
            return None;
        }
        let to = light - p;
        let lambert = m.albedo / std::f32::consts::PI * intensity * to.y / to.length().powi(3);
        let full = shade(p, Vec3::Y, scene.camera.position, &surface, &lights, Vec3::ZERO);
        // The closed form's diffuse term must be what the project's BRDF adds besides specular.
        assert!((full - lambert).min_element() >= -1e-6);
        Some(full)
    };
    for j in 0..H {
        for i in 0..W {
            match want(i, j) {
                Some(w) if w == Vec3::ZERO => outside += 1,
                Some(_) => inside += 1,
                None => {}
            }
        }
    }
    check(&img, want, 2e-3);
    assert!(inside > 300 && outside > 50, "{inside} on the quad, {outside} off it");
}

/// An asset alone declares no method, so any method is asked for by name at its defaults, as a
/// viewer would: `clustered` draws the glTF quad under its point light as `forward` does. A scene
/// file that declares its methods still refuses others.
#[test]
fn an_asset_alone_takes_any_method_by_name() {
    let dir = temp_dir("any-method");
    let scene = Scene::from_file(gltf_file(&dir)).unwrap();
    let want = forward(&scene);
    let mut r = Renderer::new(common::test_gpu(), scene.clone(), Some("clustered"), (W, H), 1).unwrap();
    assert_eq!(r.configuration.parts[0].decl.name, "clustered");
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    let (mut lit, mut worst) = (0, 0.0f32);
    for (a, b) in img.pixels.iter().zip(&want.pixels) {
        let (a, b) = (Vec3::from_slice(&a[..3]), Vec3::from_slice(&b[..3]));
        lit += usize::from(b.max_element() > 0.01);
        worst = worst.max((a - b).abs().max_element() / b.max_element().max(0.01));
    }
    println!("{lit} lit pixels, worst relative difference {worst}");
    assert!(lit > 300 && worst < 1e-3, "{lit} lit pixels, worst {worst}");
    let declared = Scene::from_str(
        "methods = [\"forward\"]\n[camera]\nposition = [0, 2, 5]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"box\"\n[[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\nintensity = 1\n",
        "declared.toml",
        Path::new("."),
    )
    .unwrap();
    let e = penumbra::lighting::registry::configuration(&declared, Some("shadow_volumes")).unwrap_err();
    assert!(e.to_string().contains("not enabled by the scene"), "{e}");
}

/// A leaf: a 2 × 2 quad at y = 1 (x, z in [-1, 1], facing +y) whose `map_d` is a 4 × 4 grey
/// checker (kept where column + row is even), over a 4 × 4 floor at y = 0; both Lambertian.
const LEAF_OBJ: &str = "mtllib leaf.mtl
v -1 1 -1\nv -1 1 1\nv 1 1 1\nv 1 1 -1
v -2 0 -2\nv -2 0 2\nv 2 0 2\nv 2 0 -2
vt 0 0\nvt 0 1\nvt 1 1\nvt 1 0
vn 0 1 0
usemtl leaf
f 1/1/1 2/2/1 3/3/1 4/4/1
usemtl floor
f 5/1/1 6/2/1 7/3/1 8/4/1
";
const KD_LEAF: f32 = 0.4;
const KD_FLOOR: f32 = 0.7;
const E_DOWN: f32 = 2.0;

/// Whether the leaf is kept over (x, z): the checker cell under it, by the OBJ's uv convention
/// (vt v = 0 is the image's bottom row) and the face's vt (u along x, v along z); `None` within
/// `margin` of a cell's edge or off the leaf.
fn leaf_kept(x: f32, z: f32, margin: f32) -> Option<bool> {
    let (u, v) = ((x + 1.0) / 2.0, (z + 1.0) / 2.0);
    if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
        return None;
    }
    let (cu, cv) = (u * 4.0, (1.0 - v) * 4.0);
    let near = |c: f32| (c - c.round()).abs() < margin * 2.0;
    if near(cu) || near(cv) {
        return None;
    }
    let (col, row) = (cu.floor() as i32, cv.floor() as i32);
    Some((col + row) % 2 == 0)
}

/// The closed form along the ray through continuous pixel coordinates (x, y): the leaf's
/// ρ/π E where the ray meets a kept cell, else the floor's ρ/π E where nothing kept lies above
/// it (the light falls straight down), else 0; `None` near an edge.
fn leaf_want(scene: &Scene, x: f32, y: f32) -> Option<f32> {
    let (o, d) = scene.camera.ray(x, y, W, H);
    let at = |h: f32| o + d * ((h - o.y) / d.y);
    let (top, floor) = (at(1.0), at(0.0));
    let on_leaf = top.x.abs() < 1.0 && top.z.abs() < 1.0;
    if on_leaf && leaf_kept(top.x, top.z, 0.03)? {
        return Some(KD_LEAF / std::f32::consts::PI * E_DOWN);
    }
    if (on_leaf || top.x.abs() < 1.03 && top.z.abs() < 1.03) && leaf_kept(top.x, top.z, 0.03).is_none() {
        return None;
    }
    if floor.x.abs() > 1.97 || floor.z.abs() > 1.97 {
        return (floor.x.abs() > 2.03 || floor.z.abs() > 2.03).then_some(0.0);
    }
    let shade = match leaf_kept(floor.x, floor.z, 0.03) {
        Some(true) => return Some(0.0),
        Some(false) => false,
        None if floor.x.abs() < 1.03 && floor.z.abs() < 1.03 => return None,
        None => false,
    };
    Some(if shade {
        0.0
    } else {
        KD_FLOOR / std::f32::consts::PI * E_DOWN
    })
}

#[test]
fn reference_traces_a_cut_out_leaf_and_the_light_through_its_holes() {
    let dir = temp_dir("leaf");
    let checker = image::GrayImage::from_fn(4, 4, |c, r| image::Luma([if (c + r) % 2 == 0 { 255 } else { 0 }]));
    checker.save(dir.join("checker.png")).unwrap();
    std::fs::write(
        dir.join("leaf.mtl"),
        format!("newmtl leaf\nKd {KD_LEAF} {KD_LEAF} {KD_LEAF}\nmap_d checker.png\nnewmtl floor\nKd {KD_FLOOR} {KD_FLOOR} {KD_FLOOR}\n"),
    )
    .unwrap();
    std::fs::write(dir.join("leaf.obj"), LEAF_OBJ).unwrap();
    let toml = format!(
        "[camera]\nposition = [0.3, 3.5, 1.8]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 50\n\n\
         [[objects]]\nmesh = \"asset\"\npath = \"leaf.obj\"\n\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = [{E_DOWN}, {E_DOWN}, {E_DOWN}]\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    let scene = Scene::from_file(dir.join("scene.toml")).unwrap();
    let img = direct_reference(&scene);
    let want = |i, j| footprint(i, j, |x, y| leaf_want(&scene, x, y)).map(Vec3::splat);
    check(&img, want, 2e-3);
    // How many pixels each case checked: kept cells, floor lit through holes, floor in shadow.
    let (mut on_leaf, mut lit_below, mut shadow_below) = (0, 0, 0);
    let leaf = Vec3::splat(KD_LEAF / std::f32::consts::PI * E_DOWN);
    for j in 0..H {
        for i in 0..W {
            let Some(w) = want(i, j) else { continue };
            let (o, d) = scene.camera.ray(i as f32 + 0.5, j as f32 + 0.5, W, H);
            let floor = o + d * (-o.y / d.y);
            let below = floor.x.abs() < 1.0 && floor.z.abs() < 1.0;
            match (w == leaf, below, w.x > 0.0) {
                (true, _, _) => on_leaf += 1,
                (false, true, true) => lit_below += 1,
                (false, true, false) => shadow_below += 1,
                _ => {}
            }
        }
    }
    println!("{on_leaf} pixels on kept cells, {lit_below} on the floor lit through holes, {shadow_below} in the leaf's shadow");
    assert!(on_leaf > 20 && lit_below > 10 && shadow_below > 10);
}
