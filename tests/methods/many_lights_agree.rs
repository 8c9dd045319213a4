//! Ridderhof 2002 digest §5 item 12, across the two systems: on the shading scene (a box floating above
//! a plane under an overhead light, here with three more lights, so ≤ K = 8 and VLS drops
//! none), virtualised light sources and the BSP shadow system draw the same frame within 1e-3
//! when they use the same light model, wherever neither has a reason to differ. The two share
//! no shading code on the GPU: VLS sums its segment's light set per fragment
//! (`glsl/vls/vls.frag`), the BSP system sums baked per-vertex colours scaled by the current
//! intensities in a compute GEMV and interpolates them (`glsl/bsp_lights/`).
//!
//! Where they may differ, and which pixels are therefore left out, is decided from the scene
//! alone, not from either image: near a shadow's edge (VLS decides a whole segment by one
//! feeler, BSP shades vertices exactly and interpolates) and in a spot's soft ramp (the BSP
//! system interpolates a ramp VLS evaluates per fragment). Each kept pixel is at least 0.3 m
//! from both, measured by ray casts around it.

use crate::support as common;

use glam::DVec3;
use penumbra::lighting::many_lights::Occluders;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;
use penumbra::world::Polygon;

const SIZE: (u32, u32) = (64, 48);
const FLOOR: f64 = 2.5;
const BOX_LOW: f64 = 0.05;
const BOX_HIGH: f64 = 1.05;

/// Position; spot (target, inner, outer degrees); intensity.
type TestLight = (DVec3, Option<(DVec3, f64, f64)>, DVec3);

fn lights() -> Vec<TestLight> {
    vec![
        // Overhead, a little off the axis as in the seed's figure, its full cone over the scene.
        (
            DVec3::new(-0.4, 4.0, -0.3),
            Some((DVec3::ZERO, 60.0, 75.0)),
            DVec3::new(9.0, 8.0, 7.0),
        ),
        (DVec3::new(1.8, 2.2, 1.2), None, DVec3::new(2.0, 2.5, 3.0)),
        (DVec3::new(-1.6, 1.6, 1.7), None, DVec3::new(1.5, 1.0, 0.5)),
        // A narrow spot: its ramp crosses the floor, where the comparison must leave it out.
        (
            DVec3::new(1.2, 3.0, -1.5),
            Some((DVec3::new(0.6, 0.0, -0.8), 12.0, 20.0)),
            DVec3::new(3.0, 1.0, 1.0),
        ),
    ]
}

fn scene_text(methods: &str) -> String {
    let mut s = format!(
        r#"
methods = [{methods}]

[camera]
position = [2.2, 4.6, 3.4]
target = [0, 0.2, 0]
fov_y_deg = 55

[[materials]]
name = "floor"
albedo = 0.7
specular = 0

[[materials]]
name = "box"
albedo = [0.75, 0.6, 0.45]
specular = 0

[[objects]]
name = "floor"
mesh = "plane"
size = [{side}, {side}]
material = "floor"

[[objects]]
name = "box"
mesh = "box"
size = [1, 1, 1]
translate = [0, {centre}, 0]
material = "box"
"#,
        side = 2.0 * FLOOR,
        centre = 0.5 * (BOX_LOW + BOX_HIGH)
    );
    for (i, (p, spot, c)) in lights().iter().enumerate() {
        s += &format!(
            "\n[[lights]]\nname = \"l{i}\"\nposition = [{}, {}, {}]\nintensity = [{}, {}, {}]\n",
            p.x, p.y, p.z, c.x, c.y, c.z
        );
        match spot {
            None => s += "type = \"point\"\n",
            Some((t, inner, outer)) => {
                s += &format!(
                    "type = \"spot\"\ntarget = [{}, {}, {}]\ninner_deg = {inner}\nouter_deg = {outer}\n",
                    t.x, t.y, t.z
                )
            }
        }
    }
    s
}

fn render(text: &str, method: &str) -> HdrImage {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::from_str(text, "item 12 test", &dir).unwrap_or_else(|e| panic!("{e}"));
    let mut r = Renderer::new(common::test_gpu(), scene, Some(method), SIZE, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

fn quad(corner: DVec3, u: DVec3, w: DVec3) -> Polygon {
    Polygon::from_vertices(vec![corner, corner + u, corner + u + w, corner + w]).unwrap()
}

/// The box's six faces: what can shadow anything here.
fn box_faces() -> Vec<Polygon> {
    let (x, y, z) = (DVec3::X, DVec3::Y * (BOX_HIGH - BOX_LOW), DVec3::Z);
    let c = DVec3::new(-0.5, BOX_LOW, -0.5);
    vec![
        quad(c + y, z, x),
        quad(c, x, z),
        quad(c + x, y, z),
        quad(c, z, y),
        quad(c + z, x, y),
        quad(c, y, x),
    ]
}

/// The spot factor of a light at p: 1 inside the inner cone, 0 outside the outer, else between.
fn cone(light: &TestLight, p: DVec3) -> f64 {
    let Some((target, inner, outer)) = light.1 else {
        return 1.0;
    };
    let cos = (p - light.0).normalize().dot((target - light.0).normalize());
    let (ci, co) = (inner.to_radians().cos(), outer.to_radians().cos());
    ((cos - co) / (ci - co)).clamp(0.0, 1.0)
}

/// Pixels that see the floor or the box's top, each at least `r` from every shadow edge and
/// spot ramp, with the point and normal seen.
fn clear_pixels(r: f64) -> Vec<usize> {
    let text = scene_text(r#""forward""#);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::from_str(&text, "item 12 test", &dir).unwrap();
    let faces = box_faces();
    let occluders = Occluders::new(faces.iter());
    let lights = lights();
    let (w, h) = SIZE;
    let mut out = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let (o, d) = scene.camera.pixel_center_ray(i, j, w, h);
            let (o, d) = (o.as_dvec3(), d.as_dvec3());
            let t_top = (BOX_HIGH - o.y) / d.y;
            let top = o + d * t_top;
            let p = if t_top > 0.0 && top.x.abs() < 0.5 - r && top.z.abs() < 0.5 - r {
                top
            } else {
                let p = o + d * (-o.y / d.y);
                let inside = p.x.abs() < FLOOR - r && p.z.abs() < FLOOR - r;
                // Seen past the box, and not within r of its footprint (the thin lit gap under it).
                if !inside || occluders.blocked(o, p) || (p.x.abs() < 0.5 + r && p.z.abs() < 0.5 + r) {
                    continue;
                }
                p
            };
            let around = (0..8).map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_4;
                p + DVec3::new(a.cos(), 0.0, a.sin()) * r
            });
            let points: Vec<DVec3> = std::iter::once(p).chain(around).collect();
            let clear = lights.iter().all(|l| {
                let lit: Vec<bool> = points
                    .iter()
                    .map(|&q| !occluders.blocked(q + DVec3::Y * 1e-6, l.0))
                    .collect();
                let ramp: Vec<f64> = points.iter().map(|&q| cone(l, q)).collect();
                lit.iter().all(|&b| b == lit[0])
                    && ramp.iter().all(|&c| c == ramp[0])
                    && (ramp[0] == 0.0 || ramp[0] == 1.0)
            });
            if clear {
                out.push((j * w + i) as usize);
            }
        }
    }
    out
}

fn compare(vls_decl: &str, bsp_decl: &str) -> (f64, usize) {
    let text = scene_text(&format!("{vls_decl}, {bsp_decl}"));
    let vls = render(&text, "vls");
    let bsp = render(&text, "bsp_lights");
    let pixels = clear_pixels(0.3);
    assert!(
        pixels.len() > SIZE.0 as usize * SIZE.1 as usize / 10,
        "only {} pixels to compare",
        pixels.len()
    );
    let mut worst = 0.0f64;
    for &i in &pixels {
        let (a, b) = (vls.pixels[i], bsp.pixels[i]);
        for c in 0..3 {
            worst = worst.max((a[c] - b[c]).abs() as f64 / (b[c].abs() as f64).max(1e-3));
        }
    }
    (worst, pixels.len())
}

#[test]
fn vls_and_the_bsp_system_agree_within_1e_3_under_the_physical_model() {
    let (worst, n) = compare(
        r#"{ name = "vls", mode = "corrected", selection = "closest", can_illuminate = false, feeler = "bvh", max_segment_area = 0.01 }"#,
        r#"{ name = "bsp_lights", mode = "corrected", storage = "f32", max_segment_area = 0.0025 }"#,
    );
    println!("physical model: worst relative difference {worst:.2e} over {n} pixels");
    assert!(worst < 1e-3, "vls and bsp_lights differ by {worst:.2e}");
}

#[test]
fn vls_and_the_bsp_system_agree_within_1e_3_under_the_seed_model() {
    let (worst, n) = compare(
        r#"{ name = "vls", mode = "corrected", model = "seed", seed_k = 1.5, selection = "closest", can_illuminate = false, feeler = "bvh", max_segment_area = 0.01 }"#,
        r#"{ name = "bsp_lights", mode = "faithful", k = 1.5, storage = "f32", max_segment_area = 0.0025 }"#,
    );
    println!("seed model: worst relative difference {worst:.2e} over {n} pixels");
    assert!(worst < 1e-3, "vls and bsp_lights differ by {worst:.2e}");
}
