//! A scene drawn at four scales: what a user meets with a model in millimetres (a CAD export
//! read as metres, a thousand times too large) or a small object modelled in metres. The lengths
//! are scaled by `s` and the lights' intensities by s², so the light reaching every surface, and
//! the image, stay the same. Every method at its defaults, with the sizes it derives from the
//! scene, must draw the same image at every scale.

use crate::support::{ok, penumbra, temp_path};
use penumbra::util::image_io::HdrImage;

/// The room of `scenes/room_gi.toml` (a floor, two walls and a box) under a spot light and a
/// constant sky, every length times `s`.
fn room(s: f64) -> String {
    let v = |p: [f64; 3]| format!("[{}, {}, {}]", p[0] * s, p[1] * s, p[2] * s);
    let quad = |name: &str, corner: [f64; 3], u: [f64; 3], w: [f64; 3], material: &str| {
        format!(
            "[[objects]]\nname = \"{name}\"\nmesh = \"quad\"\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"{material}\"\n",
            v(corner),
            v(u),
            v(w)
        )
    };
    format!(
        r#"methods = ["forward", "clustered", {{ name = "shadow_volumes", mode = "physical" }}, "vls", "bsp_lights", "radiosity", "sh_lightmap", "prt", "lpv"]
[camera]
position = {camera}
target = {target}
fov_y_deg = 55
near = {near}
[[materials]]
name = "white"
albedo = 0.7
[[materials]]
name = "red"
albedo = [0.7, 0.15, 0.1]
{floor}{back}{left}[[objects]]
name = "box"
mesh = "box"
size = {size}
translate = {at}
rotate_deg = [0, 25, 0]
material = "white"
[[lights]]
type = "spot"
position = {spot}
target = {spot_target}
intensity = {intensity}
inner_deg = 20
outer_deg = 35
[environment]
type = "constant"
radiance = 0.2
"#,
        camera = v([2.2, 1.6, 2.6]),
        target = v([0.0, 0.5, 0.0]),
        near = 0.05 * s,
        floor = quad("floor", [-1.5, 0.0, -1.5], [0.0, 0.0, 3.0], [3.0, 0.0, 0.0], "white"),
        back = quad(
            "back wall",
            [-1.5, 0.0, -1.5],
            [3.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            "white"
        ),
        left = quad("left wall", [-1.5, 0.0, -1.5], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0], "red"),
        size = v([0.7, 0.9, 0.7]),
        at = v([0.1, 0.45, -0.2]),
        spot = v([-1.0, 1.8, 1.2]),
        spot_target = v([-0.6, 0.0, -0.8]),
        intensity = 6.0 * s * s,
    )
}

/// Measured on lavapipe, the worst pixel against the image at 1 m: at most 1.4e-6 for the
/// direct methods and radiosity, 2.0e-4 for the SH light-map, 5.8e-4 for PRT and 7.3e-5 for the
/// LPV (their fp16 storage and sampling). Before the derived sizes lost their bounds in metres
/// (patches of 0.005–10 m, segments of 1e-6–1e4 m²), PRT's rays' `near` followed the scene's
/// size and the LPV's sets stored W/sr over a cell's area, the 3 mm room read: VLS 0.099, BSP
/// lights 0.21, radiosity 0.25, the SH light-map 0.038 (and 0.0044 at 300 m), PRT 0.068, the
/// LPV 0.093 (no indirect light at all: it rounded to nothing in fp16). A room in millimetres
/// (a thousand times) made radiosity a bake of hours at the 10 m patch it was held to, and the
/// many-light methods' shadow rays, kept clear of their ends by 0.1 mm, under one step of an
/// f32 position 3 km out, shadowed VLS segments by their own polygons (0.013).
#[test]
fn every_method_draws_the_same_image_at_any_scale_of_the_scene() {
    let dir = temp_path("scale");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let methods = [
        "forward",
        "clustered",
        "shadow_volumes",
        "vls",
        "bsp_lights",
        "radiosity",
        "sh_lightmap",
        "prt",
        "lpv",
    ];
    let capture = |s: f64, method: &str| -> HdrImage {
        let scene = dir.join(format!("room_{s}.toml"));
        std::fs::write(&scene, room(s)).unwrap();
        let exr = dir.join(format!("{method}_{s}.exr"));
        let out = penumbra(&[
            "capture",
            scene.to_str().unwrap(),
            "--method",
            method,
            "--size",
            "32x24",
            "--exr",
            exr.to_str().unwrap(),
            "--cache-dir",
            dir.join("cache").to_str().unwrap(),
        ]);
        ok(&out);
        HdrImage::read_exr(&exr).unwrap_or_else(|e| panic!("{e}"))
    };
    let (mut worst, mut failed) = (Vec::new(), Vec::new());
    for method in methods {
        let at_1 = capture(1.0, method);
        let mean =
            at_1.pixels.iter().map(|p| f64::from(p[0] + p[1] + p[2])).sum::<f64>() / (3 * at_1.pixels.len()) as f64;
        assert!(mean > 1e-3, "{method}: a dark image at 1 m ({mean}) tells nothing");
        for s in [0.001, 100.0, 1000.0] {
            let img = capture(s, method);
            let d = (img.pixels.iter().zip(&at_1.pixels))
                .flat_map(|(a, b)| (0..3).map(move |c| f64::from((a[c] - b[c]).abs())))
                .fold(0.0, f64::max);
            worst.push(format!("{method} at {s}: {d:.2e}"));
            if !(d.is_finite() && d <= 2e-3) {
                failed.push(format!(
                    "{method} at {s} times the size differs by up to {d} (image mean {mean:.3})"
                ));
            }
        }
    }
    eprintln!("{}", worst.join("; "));
    assert!(failed.is_empty(), "{}", failed.join("; "));
    let _ = std::fs::remove_dir_all(&dir);
}
