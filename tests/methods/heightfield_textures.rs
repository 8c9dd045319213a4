//! Material maps on height fields, under validation: the albedo map multiplies the shading as in
//! the other raster methods and the reference (sRGB-decoded, bilinear, repeat, the mesh's uv), an
//! untextured field renders exactly as with a white map, a normal map is refused with one line
//! naming the scene, the material and the field, and `penumbra compare` against the reference
//! agrees on a textured field.

use crate::support as common;

use common::{ok, penumbra};
use std::path::{Path, PathBuf};

use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

/// Checker cells of `cell` texels on a `texels`² sRGB PNG, colours `a` (cell (0, 0)) and `b`.
fn checker_png(name: &str, texels: u32, cell: u32, a: [u8; 3], b: [u8; 3]) -> PathBuf {
    let path = common::temp_path(name);
    let img = image::RgbImage::from_fn(texels, texels, |x, y| {
        image::Rgb(if (x / cell + y / cell).is_multiple_of(2) { a } else { b })
    });
    img.save(&path).unwrap();
    path
}

fn srgb_decode(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A flat 8 m field at y = 0 under a unit sky, seen straight down from 6 m (60° field of view,
/// image right = +x, image down = +z), so every pixel sees the field; `material` is the body of
/// the field's `[[materials]]` entry (named "ground").
fn flat_scene(methods: &str, material: &str) -> String {
    format!(
        r#"methods = [{methods}]
[camera]
position = [0, 6, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov_y_deg = 60
[[materials]]
name = "ground"
{material}
[[objects]]
name = "terrain"
mesh = "heightfield"
material = "ground"
size = 8
resolution = 32
generator = "flat"
height = 0
[environment]
type = "constant"
radiance = 1
"#
    )
}

fn render(scene: &Scene, method: &str, size: u32) -> HdrImage {
    let mut r = Renderer::new(common::test_gpu(), scene.clone(), Some(method), (size, size), 1).unwrap();
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

const METHODS: &str = r#""heightfield_pyramid", { name = "heightfield_bruteforce", march_step = 1, resolution = 16 }"#;

/// A flat field under a unit sky shades to 1 (± 1e-4), so each pixel's exit radiance is the
/// material colour times the sRGB-decoded texel under it: checked at every pixel whose bilinear
/// footprint lies inside one checker cell, for both methods (the brute force working at 16² on
/// the 32² mesh: the uv depends on the world position only).
#[test]
fn checker_albedo_map_times_shading() {
    let (a, b) = ([200u8, 100, 30], [20u8, 180, 240]);
    let (texels, cell) = (16u32, 4u32);
    let map = checker_png("hf-checker.png", texels, cell, a, b);
    let colour = [1.0f32, 0.5, 0.8];
    let text = flat_scene(
        METHODS,
        &format!(
            "albedo = [{}, {}, {}]\nalbedo_map = {:?}",
            colour[0], colour[1], colour[2], map
        ),
    );
    let scene = Scene::from_str(&text, "<test>", Path::new("/")).unwrap();
    let size = 64u32;
    let half = 6.0 * 30f32.to_radians().tan();
    for method in ["heightfield_pyramid", "heightfield_bruteforce"] {
        let img = render(&scene, method, size);
        let (mut checked, mut worst, mut seen) = (0, 0.0f32, [0usize; 2]);
        for py in 0..size {
            for px in 0..size {
                let ndc = |p: u32| (p as f32 + 0.5) / size as f32 * 2.0 - 1.0;
                let (x, z) = (ndc(px) * half, ndc(py) * half);
                // Texel coordinates of the mesh uv (x + 4)/8, (z + 4)/8.
                let (tu, tv) = ((x + 4.0) / 8.0 * texels as f32, (z + 4.0) / 8.0 * texels as f32);
                let inside = |t: f32| (t % cell as f32) > 0.75 && (t % cell as f32) < cell as f32 - 0.75;
                if !inside(tu) || !inside(tv) {
                    continue;
                }
                let which = ((tu as u32 / cell + tv as u32 / cell) % 2) as usize;
                let texel = if which == 0 { a } else { b };
                let p = img.get(px, py);
                for c in 0..3 {
                    let want = colour[c] * srgb_decode(texel[c]);
                    // lavapipe's 8-bit sRGB decode is approximate: 0.67% at 100, 2e-4 absolute at
                    // 30 (measured); the shading adds 1e-4.
                    let err = (p[c] - want).abs() / want.max(0.05);
                    worst = worst.max(err);
                    assert!(
                        err < 1e-2,
                        "{method}: pixel ({px}, {py}) channel {c}: {} against {want} (cell colour {texel:?})",
                        p[c]
                    );
                }
                seen[which] += 1;
                checked += 1;
            }
        }
        assert!(
            seen[0] > 200 && seen[1] > 200,
            "{method}: too few pixels checked: {seen:?}"
        );
        eprintln!("{method}: {checked} pixels, worst error {worst:.2e} of max(expected, 0.05)");
    }
}

/// Without an albedo map the field gets the 1×1 white default: the image is bit-identical to
/// one with an explicit white map, on a field with shadows and a sphere light.
#[test]
fn untextured_field_is_unchanged() {
    let white = common::temp_path("hf-white.png");
    image::RgbImage::from_pixel(4, 4, image::Rgb([255, 255, 255]))
        .save(&white)
        .unwrap();
    let lit = |material: &str| {
        let text = flat_scene(r#""heightfield_pyramid""#, material).replace(
            "generator = \"flat\"\nheight = 0",
            "generator = \"cones\"\ncount = 3\nradius = 1.5\nring_radius = 2\nheight = 1",
        ) + "[[lights]]\ntype = \"sphere\"\ncenter = [0.5, 2, 0.3]\nradius = 0.3\nradiance = 5\n";
        Scene::from_str(&text, "<test>", Path::new("/")).unwrap()
    };
    let plain = render(&lit("albedo = [0.7, 0.5, 0.3]"), "heightfield_pyramid", 32);
    let mapped = render(
        &lit(&format!("albedo = [0.7, 0.5, 0.3]\nalbedo_map = {white:?}")),
        "heightfield_pyramid",
        32,
    );
    let differing = plain
        .pixels
        .iter()
        .zip(&mapped.pixels)
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.to_bits() != y.to_bits()))
        .count();
    assert_eq!(differing, 0, "pixels differ from the white-map image");
    let field = plain.pixels.iter().filter(|p| p[0] > 0.0 && p[0] < 1.0).count();
    assert!(field > 500, "the field covers only {field} pixels");
}

/// A normal map cannot be honoured (the transfer uses the field's own normals): one line naming
/// the scene file, the material and the height field, from both methods, and from the CLI.
#[test]
fn normal_map_is_refused() {
    let normal = common::temp_path("hf-normal.png");
    image::RgbImage::from_pixel(2, 2, image::Rgb([128, 128, 255]))
        .save(&normal)
        .unwrap();
    let text = flat_scene(METHODS, "albedo = 0.5\nnormal_map = \"hf-normal.png\"");
    let dir = normal.parent().unwrap();
    let scene = Scene::from_str(&text, "bumpy.toml", dir).unwrap();
    for method in ["heightfield_pyramid", "heightfield_bruteforce"] {
        let e = match Renderer::new(common::test_gpu(), scene.clone(), Some(method), (16, 16), 1) {
            Ok(_) => panic!("{method}: a normal map on the field was accepted"),
            Err(e) => e.to_string(),
        };
        let want = format!(
            "bumpy.toml: materials[0] (\"ground\").normal_map: {method} cannot apply a normal map (it shades with the height field's own normals); used by the height field objects[0] (\"terrain\")"
        );
        assert_eq!(e, want);
    }
    let path = dir.join("bumpy.toml");
    std::fs::write(&path, &text).unwrap();
    let o = penumbra(&[
        "capture",
        path.to_str().unwrap(),
        "--size",
        "16x16",
        "-o",
        common::temp_path("bumpy.png").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.lines().count() == 1
            && err.contains("bumpy.toml")
            && err.contains("\"ground\"")
            && err.contains("\"terrain\""),
        "{err}"
    );
}

/// `penumbra capture` of a textured flat field against `penumbra reference --direct-only`, as
/// a user checks it: `penumbra compare` gives a small relative MSE (without the map the method
/// drew the field in its flat colour: relative MSE 30.2 here, 6.7e-4 with it on lavapipe; what
/// is left is the reference's pixel average across the checker's half-texel blend).
#[test]
fn textured_field_matches_the_reference() {
    // A 2×2 checker over the field: its edges at x = 0 and z = 0 fall on pixel boundaries and
    // the texels are small, so the reference's pixel average and the method's pixel centre
    // differ only where a pixel reaches into the half-texel blend at an edge.
    let map = checker_png("hf-ref-checker.png", 256, 128, [230, 120, 40], [40, 160, 220]);
    let text = flat_scene(
        r#""heightfield_pyramid""#,
        &format!("albedo = [0.9, 0.8, 1]\nalbedo_map = {map:?}"),
    );
    let scene = common::temp_path("hf-textured.toml");
    std::fs::write(&scene, text).unwrap();
    let (test, reference) = (
        common::temp_path("hf-textured.exr"),
        common::temp_path("hf-textured-ref.exr"),
    );
    let s = scene.to_str().unwrap();
    ok(&penumbra(&[
        "capture",
        s,
        "--size",
        "32x32",
        "-o",
        common::temp_path("hf-textured.png").to_str().unwrap(),
        "--exr",
        test.to_str().unwrap(),
    ]));
    ok(&penumbra(&[
        "reference",
        s,
        "--size",
        "32x32",
        "--spp",
        "256",
        "--direct-only",
        "-o",
        reference.to_str().unwrap(),
    ]));
    let out = ok(&penumbra(&[
        "compare",
        test.to_str().unwrap(),
        reference.to_str().unwrap(),
        "--json",
    ]));
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rel = v["rel_mse"].as_f64().unwrap();
    eprintln!("relative MSE {rel:.2e}, bias {}", v["mean_bias"]);
    assert!(rel < 0.01, "relative MSE {rel}: {out}");
}
