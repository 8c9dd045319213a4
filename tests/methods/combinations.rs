//! Methods that compose: a frame is base + direct + indirect, each term from the method a scene's
//! `[[combinations]]` entry names. A combination must render exactly the sum of its terms rendered
//! alone, and bad combinations are one error line naming file, line and field.

use crate::support as common;

use penumbra::lighting::registry;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

const SIZE: (u32, u32) = (64, 48);

/// A box on a floor under a point light and a spot light, and a dim constant sky: forward and
/// shadow volumes, and the combinations of their terms.
const SCENE: &str = r#"
methods = ["forward", { name = "shadow_volumes", mode = "physical", animate = false }]

[camera]
position = [0.0, 2.2, 4.0]
target = [0.0, 0.3, 0.0]
fov_y_deg = 50

[[materials]]
name = "floor"
albedo = 0.6

[[materials]]
name = "shiny"
albedo = [0.5, 0.3, 0.2]
specular = 0.3
exponent = 40

[[objects]]
mesh = "plane"
size = [6, 6]
material = "floor"

[[objects]]
mesh = "box"
size = [0.8, 0.8, 0.8]
translate = [0.0, 0.4, 0.0]
material = "shiny"

[[lights]]
type = "point"
position = [1.2, 2.5, 0.8]
intensity = 6

[[lights]]
type = "spot"
position = [-1.5, 2.0, 1.0]
target = [0.0, 0.0, 0.0]
intensity = 8
inner_deg = 20
outer_deg = 35

[environment]
type = "constant"
radiance = [0.05, 0.06, 0.08]

[[combinations]]
name = "shadowed_over_forward"
base = "forward"
direct = "shadow_volumes"

[[combinations]]
name = "forward_base"
base = "forward"

[[combinations]]
name = "forward_direct"
direct = "forward"

[[combinations]]
name = "shadowed_direct"
direct = "shadow_volumes"
"#;

fn scene() -> Scene {
    Scene::from_str(SCENE, "combo.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

fn render(name: &str) -> HdrImage {
    let mut r =
        Renderer::new(common::test_gpu(), scene(), Some(name), SIZE, 1).unwrap_or_else(|e| panic!("{name}: {e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

/// Largest per-channel |a + b − c| over the image, relative to max(|c|, 1e-3).
fn sum_error(a: &HdrImage, b: &HdrImage, c: &HdrImage) -> f32 {
    let mut worst = 0.0f32;
    for ((pa, pb), pc) in a.pixels.iter().zip(&b.pixels).zip(&c.pixels) {
        for k in 0..3 {
            worst = worst.max((pa[k] + pb[k] - pc[k]).abs() / pc[k].abs().max(1e-3));
        }
    }
    worst
}

fn total(img: &HdrImage) -> f64 {
    img.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum()
}

#[test]
fn a_combination_is_the_sum_of_its_terms_alone() {
    let base = render("forward_base");
    let shadowed = render("shadowed_direct");
    let combo = render("shadowed_over_forward");
    // Additive blending adds the direct term onto the base in fp32: one rounding per light.
    let e = sum_error(&base, &shadowed, &combo);
    assert!(
        e < 1e-5,
        "forward base + shadow-volume direct vs the combination: worst relative error {e}"
    );
    // The terms are real: the direct term carries more light than the base (sky and ambient).
    let (tb, td) = (total(&base), total(&shadowed));
    assert!(tb > 0.0 && td > tb, "base {tb}, direct {td}");

    // Forward's own terms alone add up to forward whole (one pass, same arithmetic order up to
    // the one blend).
    let (fb, fd, whole) = (base, render("forward_direct"), render("forward"));
    let e = sum_error(&fb, &fd, &whole);
    assert!(
        e < 1e-5,
        "forward base + forward direct vs forward: worst relative error {e}"
    );
    // And the shadows are what the combination adds over forward: the box's shadow on the floor
    // darkens a part of the image that forward lights.
    // (Each shadow is lit by the other light, hence "a third darker".)
    let darker = whole
        .pixels
        .iter()
        .zip(&combo.pixels)
        .filter(|(w, c)| c[1] < 0.67 * w[1] && w[1] > 0.05)
        .count();
    let brighter = whole
        .pixels
        .iter()
        .zip(&combo.pixels)
        .filter(|(w, c)| c[1] > w[1] * 1.0001 + 1e-6)
        .count();
    eprintln!("{darker} pixels a third darker than forward, {brighter} brighter");
    assert!(
        darker > 15 && brighter == 0,
        "{darker} pixels in shadow in the combination, {brighter} brighter than unshadowed forward"
    );
}

#[test]
fn a_direct_term_alone_tests_against_the_scene_depth() {
    // Without a base, the renderer lays the depth: the floor behind the box gets no light from
    // the direct term where the box covers it, so no pixel is lit twice (front and back).
    let fd = render("forward_direct");
    let whole = render("forward");
    for (d, w) in fd.pixels.iter().zip(&whole.pixels) {
        for k in 0..3 {
            assert!(d[k] <= w[k] + 1e-5, "direct alone {d:?} exceeds the whole frame {w:?}");
        }
    }
    // The background stays black without a base (no sky), and is the sky with one.
    assert_eq!(fd.get(0, 0)[..3], [0.0, 0.0, 0.0]);
    assert!((whole.get(0, 0)[2] - 0.08).abs() < 1e-6, "{:?}", whole.get(0, 0));
}

#[test]
fn configurations_list_methods_then_combinations() {
    let names: Vec<String> = registry::configurations(&scene())
        .unwrap()
        .into_iter()
        .map(|c| c.name)
        .collect();
    assert_eq!(
        names,
        [
            "forward",
            "shadow_volumes",
            "shadowed_over_forward",
            "forward_base",
            "forward_direct",
            "shadowed_direct"
        ]
    );
    let c = registry::configuration(&scene(), Some("shadowed_over_forward")).unwrap();
    let parts: Vec<(String, String)> = c
        .parts
        .iter()
        .map(|p| (p.decl.name.clone(), p.terms.to_string()))
        .collect();
    assert_eq!(
        parts,
        [
            ("forward".to_string(), "base".to_string()),
            ("shadow_volumes".to_string(), "direct".to_string())
        ]
    );
    // The chart measures a combination as declared, then with each part swept.
    let sweep = registry::sweep(&c).unwrap();
    assert_eq!(sweep[0].0, "shadowed_over_forward");
    assert!(
        sweep.len() > 2 && sweep.iter().all(|(l, _)| l.starts_with("shadowed_over_forward")),
        "{:?}",
        sweep.iter().map(|s| &s.0).collect::<Vec<_>>()
    );
}

fn config_error(extra: &str, methods: &str) -> String {
    let text = format!("methods = {methods}\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"heightfield\"\ngenerator = \"flat\"\n{extra}");
    let scene = Scene::from_str(&text, "mix.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    registry::configurations(&scene)
        .expect_err("a bad combination must be refused")
        .to_string()
}

#[test]
fn bad_combinations_are_one_line_naming_file_line_and_field() {
    let e = config_error(
        "[[combinations]]\nname = \"mix\"\ndirect = \"heightfield_pyramid\"\n",
        r#"["heightfield_pyramid"]"#,
    );
    assert_eq!(e, "mix.toml:10: combinations[0].direct: heightfield_pyramid draws its terms (base + direct) in one pass and cannot supply direct alone");
    let e = config_error(
        "[[combinations]]\nname = \"mix\"\nbase = \"forward\"\n",
        r#"["heightfield_pyramid"]"#,
    );
    assert_eq!(
        e,
        "mix.toml:10: combinations[0].base: \"forward\" is not one of the scene's methods (heightfield_pyramid)"
    );
    let e = config_error(
        "[[combinations]]\nname = \"mix\"\nindirect = \"forward\"\n",
        r#"["forward"]"#,
    );
    assert_eq!(
        e,
        "mix.toml:10: combinations[0].indirect: forward cannot supply the indirect term (it supplies base + direct)"
    );
    let e = config_error(
        "[[combinations]]\nname = \"forward\"\nbase = \"forward\"\n",
        r#"["forward"]"#,
    );
    assert_eq!(
        e,
        "mix.toml:9: combinations[0].name: \"forward\" is already the name of a method or combination"
    );
    let e = config_error("[[combinations]]\nname = \"empty\"\n", r#"["forward"]"#);
    assert_eq!(
        e,
        "mix.toml:9: combinations[0]: names no term: give at least one of base, direct, indirect"
    );
    // Unknown keys are caught by the parser, with the same promise.
    let text =
        "[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[combinations]]\nname = \"x\"\nambient = \"forward\"\n";
    let e = Scene::from_str(text, "mix.toml", std::path::Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("mix.toml:6: combinations[0].ambient"), "{e}");
}

/// One method declared twice with different parameters is refused unless an `id` tells the
/// two apart; with one, `--method` and combinations reach each declaration by its label.
#[test]
fn a_method_declared_twice_needs_an_id() {
    let e = config_error(
        "",
        r#"["forward", { name = "shadow_volumes", mode = "physical" }, { name = "shadow_volumes", mode = "faithful" }]"#,
    );
    assert_eq!(
        e,
        "mix.toml:1: methods[2]: \"shadow_volumes\" names methods[1] (line 1) too, with other parameters: give one of them an `id = \"...\"` to tell them apart"
    );
    let text = format!(
        "methods = {}\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[combinations]]\nname = \"mix\"\nbase = \"forward\"\ndirect = \"sv_faithful\"\n",
        r#"["forward", { name = "shadow_volumes", mode = "physical" }, { name = "shadow_volumes", id = "sv_faithful", mode = "faithful" }]"#
    );
    let scene = Scene::from_str(&text, "mix.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let all = registry::configurations(&scene).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = all.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["forward", "shadow_volumes", "sv_faithful", "mix"]);
    let mode = |c: &penumbra::lighting::Configuration, i: usize| {
        c.parts[i]
            .decl
            .param("mode")
            .and_then(|v| v.as_str())
            .map(str::to_owned)
    };
    let by_id = registry::configuration(&scene, Some("sv_faithful")).unwrap();
    assert_eq!(
        (by_id.parts[0].decl.name.as_str(), mode(&by_id, 0).as_deref()),
        ("shadow_volumes", Some("faithful"))
    );
    let plain = registry::configuration(&scene, Some("shadow_volumes")).unwrap();
    assert_eq!(mode(&plain, 0).as_deref(), Some("physical"));
    let mix = registry::configuration(&scene, Some("mix")).unwrap();
    assert_eq!(
        mode(&mix, 1).as_deref(),
        Some("faithful"),
        "the combination takes the declaration it names"
    );
    // The same declaration written twice is no ambiguity.
    let text = text
        .replace("id = \"sv_faithful\", mode = \"faithful\"", "mode = \"physical\"")
        .replace("sv_faithful", "shadow_volumes");
    let scene = Scene::from_str(&text, "mix.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    registry::configurations(&scene).unwrap_or_else(|e| panic!("{e}"));
}

/// Switching configurations (the demo's M key) frees what the previous methods created: after
/// each full cycle through every configuration, the device holds exactly as many buffers, images
/// and pipelines as after the first, and the frames still render.
#[test]
fn switching_configurations_frees_the_previous_methods() {
    let scene = Scene::from_file(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/room_gi.toml")).unwrap();
    let configurations = registry::configurations(&scene).unwrap();
    assert!(configurations.len() >= 3, "room_gi has methods and a combination");
    let mut r = Renderer::new(common::test_gpu(), scene, None, (32, 24), 1).unwrap();
    let cam = r.scene.camera.clone();
    let mut after_cycle = Vec::new();
    for _ in 0..3 {
        for c in &configurations {
            r.set_configuration(c.clone())
                .unwrap_or_else(|e| panic!("{}: {e}", c.name));
            r.render(&cam, FrameOutput::Readback).unwrap();
        }
        after_cycle.push(r.gpu.live_objects());
    }
    eprintln!("live (buffers, images, pipelines) after each cycle: {after_cycle:?}");
    assert!(
        after_cycle.windows(2).all(|w| w[0] == w[1]),
        "objects grow with switching: {after_cycle:?}"
    );
    common::assert_clean(&r.gpu);
}
