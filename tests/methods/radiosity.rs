//! The radiosity light-map as a base term on the GPU (the Ca3D-Engine thesis §3): a closed box whose inside
//! emits L_e and reflects ρ shows L_e/(1 − ρ) in every pixel (the furnace's geometric series,
//! independent of the baker), and a bad parameter is one line naming file and field.

use crate::support as common;

use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;

/// Six inward-facing quads around [-1, 1]³, all of one material, the camera inside.
fn furnace_box(method: &str, emission: f32, albedo: f32) -> String {
    let faces = [
        ([-1, -1, -1], [2, 0, 0], [0, 0, 2]),
        ([-1, 1, -1], [0, 0, 2], [2, 0, 0]),
        ([-1, -1, -1], [0, 0, 2], [0, 2, 0]),
        ([1, -1, -1], [0, 2, 0], [0, 0, 2]),
        ([-1, -1, -1], [0, 2, 0], [2, 0, 0]),
        ([-1, -1, 1], [2, 0, 0], [0, 2, 0]),
    ];
    let mut s =
        format!("methods = [{method}]\n[camera]\nposition = [0.1, -0.2, 0.3]\ntarget = [0.5, 0.3, -1]\nfov_y_deg = 90\n[[materials]]\nname = \"wall\"\nalbedo = {albedo}\nemission = {emission}\n");
    for (c, u, v) in faces {
        // Light-map patches are lit on their front (edge_u × edge_v) side: v × u faces inward.
        s += &format!(
            "[[objects]]\nmesh = \"quad\"\ncorner = {c:?}\nedge_u = {v:?}\nedge_v = {u:?}\nmaterial = \"wall\"\n"
        );
    }
    s
}

fn render(text: &str, size: (u32, u32)) -> penumbra::util::image_io::HdrImage {
    let scene = Scene::from_str(text, "box.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let mut r = Renderer::new(common::test_gpu(), scene, None, size, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

#[test]
fn a_closed_emitting_box_shows_the_furnace_series_everywhere() {
    let (le, rho) = (0.5f32, 0.6f32);
    let img = render(
        &furnace_box(
            r#"{ name = "radiosity", patch_size = 0.25, threshold = 1e-4 }"#,
            le,
            rho,
        ),
        (48, 32),
    );
    let want = le / (1.0 - rho);
    let worst = img
        .pixels
        .iter()
        .map(|p| (p[0] - want).abs() / want)
        .fold(0.0f32, f32::max);
    // The solve stops with 1e-4 of the light unshot; the form factors are exact.
    assert!(worst < 2e-3, "worst pixel {worst:.2e} off L_e/(1 − ρ) = {want}");
    // Without the light-map (a lookup of 0, or emission only) every pixel would be L_e: 2.5× less.
    assert!(img.pixels.iter().all(|p| p[0] > 1.5 * le));
}

/// CaLight's one reflectivity for every surface: the bounces reflect 0.3 whatever the material,
/// so the light-map holds irradiance H = E/(1 − 0.3) over π and the box shows
/// L_e + ρ_material·H/π = L_e·(1 + ρ/0.7), not the material's own series L_e/(1 − ρ).
#[test]
fn a_fixed_reflectivity_replaces_the_materials_in_the_bounces() {
    let (le, rho) = (0.5f32, 0.6f32);
    let img = render(
        &furnace_box(
            r#"{ name = "radiosity", patch_size = 0.25, threshold = 1e-4, reflectivity = 0.3 }"#,
            le,
            rho,
        ),
        (24, 16),
    );
    let want = le * (1.0 + rho / 0.7);
    let worst = img
        .pixels
        .iter()
        .map(|p| (p[0] - want).abs() / want)
        .fold(0.0f32, f32::max);
    // As the furnace above: 1e-4 of the light left unshot, exact form factors. The material's
    // own series would be 2.5·L_e, 35% brighter.
    assert!(worst < 2e-3, "worst pixel {worst:.2e} off L_e·(1 + ρ/0.7) = {want}");
}

#[test]
fn bad_parameters_name_the_field() {
    let text = furnace_box(r#"{ name = "radiosity", patch_size = -1 }"#, 0.5, 0.5);
    let scene = Scene::from_str(&text, "box.toml", std::path::Path::new(".")).unwrap();
    let e = Renderer::new(common::test_gpu(), scene, None, (8, 8), 1)
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("box.toml:") && e.contains("methods[0].patch_size: expected a size in metres above 0, got -1"),
        "{e}"
    );
}

/// The Ca3D-Engine thesis's composition on `scenes/room_gi.toml`: the light-map's bounced light under shadow
/// volumes' direct light is much closer to the multi-bounce path tracer than the direct light
/// alone, and the light-map alone is close to the tracer's indirect-only image.
#[test]
fn bounced_light_under_shadow_volumes_approaches_the_path_tracer() {
    use penumbra::metrics::{compare, CompareOptions};
    use penumbra::reference::{Batching, LightPaths, ReferenceRenderer, Settings};
    let size = (32, 24);
    let scene = Scene::from_file("scenes/room_gi.toml").unwrap();
    let mut tracer = ReferenceRenderer::new(common::test_gpu(), &scene, size).unwrap();
    let mut truth = |paths| {
        tracer
            .render(
                &Settings {
                    spp: 128,
                    bounces: 12,
                    paths,
                    seed: 3,
                    batching: Batching::Adaptive,
                    ..Settings::default()
                },
                &mut |_, _| {},
            )
            .unwrap()
            .mean
    };
    let (all, indirect) = (truth(LightPaths::All), truth(LightPaths::Indirect));
    common::assert_clean(&tracer.gpu);
    let frame = |name: &str| {
        let mut r = Renderer::new(common::test_gpu(), scene.clone(), Some(name), size, 1)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let cam = r.scene.camera.clone();
        let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
        common::assert_clean(&r.gpu);
        img
    };
    let o = CompareOptions::default();
    let gi = compare(&frame("gi"), &all, &o).unwrap();
    let direct = compare(&frame("shadow_volumes"), &all, &o).unwrap();
    let bounces = compare(&frame("radiosity"), &indirect, &o).unwrap();
    eprintln!(
        "relative MSE against the tracer: gi {:.4}, direct only {:.4}; light-map against indirect only {:.4}",
        gi.rel_mse, direct.rel_mse, bounces.rel_mse
    );
    // Measured at 64×48, 512 spp: 0.0060 and 0.0243 (docs/methods/radiosity.md).
    assert!(
        gi.rel_mse < 0.5 * direct.rel_mse,
        "gi {} vs direct {}",
        gi.rel_mse,
        direct.rel_mse
    );
    assert!(
        gi.mean_bias.abs() < 0.25 * direct.mean_bias.abs(),
        "bias: gi {} vs direct {}",
        gi.mean_bias,
        direct.mean_bias
    );
    assert!(
        bounces.mean_bias.abs() < 0.01,
        "the light-map's bounced light is unbiased against the tracer's: {}",
        bounces.mean_bias
    );
}

#[test]
fn each_configuration_is_judged_against_what_it_models() {
    use penumbra::lighting::{registry, ReferenceKind};
    let scene = Scene::from_file("scenes/room_gi.toml").unwrap();
    let kind = |name: &str| registry::reference_kind(&registry::configuration(&scene, Some(name)).unwrap()).unwrap();
    assert_eq!(kind("radiosity"), ReferenceKind::Indirect(16));
    assert_eq!(kind("shadow_volumes"), ReferenceKind::Direct);
    assert_eq!(kind("gi"), ReferenceKind::Bounces(16));
    assert_eq!(
        ReferenceKind::Bounces(3).combine(ReferenceKind::Indirect(8)),
        ReferenceKind::Bounces(8)
    );
    assert_eq!(
        ReferenceKind::Indirect(2).combine(ReferenceKind::Indirect(5)),
        ReferenceKind::Indirect(5)
    );
}

/// scenes/two_rooms.toml on the GPU, in both modes (faithful: the light-map as RGB8 bytes,
/// corrected: floats): seen from room B, looking at the 5 cm wall and the floor along it, every
/// pixel is exactly 0 — no texel of room B holds light and bilinear filtering reads none from
/// room A; seen from room A the same light-map is lit.
#[test]
fn no_light_bleeds_into_the_dark_room_on_screen() {
    let text = std::fs::read_to_string("scenes/two_rooms.toml").unwrap();
    for mode in ["faithful", "corrected"] {
        let methods =
            format!(r#"methods = [{{ name = "radiosity", mode = "{mode}", patch_size = 0.2, threshold = 1e-2 }}]"#);
        let text = text
            .lines()
            .map(|l| if l.starts_with("methods") { methods.as_str() } else { l })
            .collect::<Vec<_>>()
            .join("\n");
        let scene =
            Scene::from_str(&text, "two_rooms.toml", std::path::Path::new("scenes")).unwrap_or_else(|e| panic!("{e}"));
        let mut r = Renderer::new(common::test_gpu(), scene, None, (48, 32), 1).unwrap_or_else(|e| panic!("{e}"));
        let mut look = |from: [f32; 3], to: [f32; 3]| {
            let mut cam = r.scene.camera.clone();
            cam.position = from.into();
            cam.target = to.into();
            let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
            img.pixels
                .iter()
                .map(|p| p[0].max(p[1]).max(p[2]))
                .fold(0.0f32, f32::max)
        };
        let dark = look([1.6, 1.2, 1.6], [0.05, 0.2, -1.2]);
        let lit = look([-0.5, 1.2, 1.6], [-2.5, 0.5, -1.0]);
        common::assert_clean(&r.gpu);
        eprintln!("{mode}: brightest pixel in room B {dark}, in room A {lit}");
        assert_eq!(dark, 0.0, "{mode}: light on screen in room B");
        assert!(lit > 0.05, "{mode}: room A is lit: {lit}");
    }
}

/// A room lit by a ceiling quad light only, out of view: the light-map of bounced light
/// (`light = "bounces"`) holds none of the quad light's direct light, so its mean over the frame
/// is that of the path tracer's indirect-only image, well below the direct-only image's.
#[test]
fn a_quad_lights_bounces_leave_out_its_direct_light() {
    use penumbra::reference::{Batching, LightPaths, ReferenceRenderer, Settings};
    let mut text = String::from(
        "methods = [{ name = \"radiosity\", light = \"bounces\", patch_size = 0.25, threshold = 1e-3 }]\n\
         [camera]\nposition = [0.0, 1.0, 1.4]\ntarget = [0.0, 0.6, -1.5]\nfov_y_deg = 60\n\
         [[materials]]\nname = \"white\"\nalbedo = 0.7\n\
         [[lights]]\ntype = \"quad\"\ncorner = [-0.5, 2.49, -1.0]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, 1]\nradiance = 4\n",
    );
    // Floor, ceiling, back, left and right walls of [-1.5, 1.5] × [0, 2.5] × [-1.5, 1.5], facing in.
    for (c, u, v) in [
        ([-1.5, 0.0, -1.5], [0.0, 0.0, 3.0], [3.0, 0.0, 0.0]),
        ([-1.5, 2.5, -1.5], [3.0, 0.0, 0.0], [0.0, 0.0, 3.0]),
        ([-1.5, 0.0, -1.5], [3.0, 0.0, 0.0], [0.0, 2.5, 0.0]),
        ([-1.5, 0.0, -1.5], [0.0, 2.5, 0.0], [0.0, 0.0, 3.0]),
        ([1.5, 0.0, -1.5], [0.0, 0.0, 3.0], [0.0, 2.5, 0.0]),
    ] {
        text += &format!(
            "[[objects]]\nmesh = \"quad\"\ncorner = {c:?}\nedge_u = {u:?}\nedge_v = {v:?}\nmaterial = \"white\"\n"
        );
    }
    let scene = Scene::from_str(&text, "quad_room.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let size = (32, 24);
    let mut tracer = ReferenceRenderer::new(common::test_gpu(), &scene, size).unwrap();
    let mut truth = |paths| {
        let s = Settings {
            spp: 64,
            bounces: 12,
            paths,
            seed: 5,
            batching: Batching::Adaptive,
            ..Settings::default()
        };
        tracer.render(&s, &mut |_, _| {}).unwrap().mean
    };
    let (indirect, direct) = (truth(LightPaths::Indirect), truth(LightPaths::Direct));
    common::assert_clean(&tracer.gpu);
    let mut r = Renderer::new(common::test_gpu(), scene, None, size, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    let mean = |i: &penumbra::util::image_io::HdrImage| {
        i.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / i.pixels.len() as f64
    };
    let (got, want, first) = (mean(&img), mean(&indirect), mean(&direct));
    eprintln!("frame means: light-map of bounces {got:.4}, tracer indirect only {want:.4}, direct only {first:.4}");
    assert!(
        first > want,
        "the quad light must light the room directly more than by bounces"
    );
    assert!(
        (got - want).abs() < 0.05 * want,
        "bounces {got:.4} against indirect only {want:.4} (direct only {first:.4})"
    );
}

/// A room of solid boxes lit only by the sky through a slot in its ceiling: walls stand on a
/// floor that runs on under them, as modelled rooms are built. The corrected light-map gathers
/// the environment through the opening (and its bounces), and leaves the floor under the walls
/// out of the patches along the junctions, so its frame's mean is the path tracer's; the
/// document's light-map, which has no environment, is black.
#[test]
fn a_room_lit_by_the_sky_through_its_roof_matches_the_path_tracer() {
    use penumbra::reference::{Batching, LightPaths, ReferenceRenderer, Settings};
    let boxes = [
        ("floor", [4.4, 0.1, 4.4], [0.0, -0.05, 0.0]),
        ("wall -x", [0.27, 2.5, 4.4], [-2.065, 1.25, 0.0]),
        ("wall +x", [0.27, 2.5, 4.4], [2.065, 1.25, 0.0]),
        ("wall -z", [4.4, 2.5, 0.27], [0.0, 1.25, -2.065]),
        ("wall +z", [4.4, 2.5, 0.27], [0.0, 1.25, 2.065]),
        ("roof -x", [1.9, 0.1, 4.4], [-1.25, 2.55, 0.0]),
        ("roof +x", [1.9, 0.1, 4.4], [1.25, 2.55, 0.0]),
        ("table", [0.8, 0.6, 0.8], [0.7, 0.3, -0.6]),
    ];
    let frame = |mode: &str| {
        let mut text = format!(
            "methods = [{{ name = \"radiosity\", mode = \"{mode}\", patch_size = 0.25 }}]\n\
             [camera]\nposition = [-1.2, 1.6, 1.5]\ntarget = [0.8, 0.4, -1.0]\nfov_y_deg = 60\n\
             [environment]\ntype = \"constant\"\nradiance = [1.0, 1.0, 1.0]\n\
             [[materials]]\nname = \"grey\"\nalbedo = 0.5\n"
        );
        for (name, size, at) in boxes {
            text += &format!(
                "[[objects]]\nname = \"{name}\"\nmesh = \"box\"\nsize = {size:?}\ntranslate = {at:?}\nmaterial = \"grey\"\n"
            );
        }
        Scene::from_str(&text, "sky_room.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
    };
    let size = (32, 24);
    let scene = frame("corrected");
    let mut tracer = ReferenceRenderer::new(common::test_gpu(), &scene, size).unwrap();
    let s = Settings {
        spp: 128,
        bounces: 12,
        paths: LightPaths::All,
        seed: 7,
        batching: Batching::Adaptive,
        ..Settings::default()
    };
    let truth = tracer.render(&s, &mut |_, _| {}).unwrap().mean;
    common::assert_clean(&tracer.gpu);
    let mean = |i: &penumbra::util::image_io::HdrImage| {
        i.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / i.pixels.len() as f64
    };
    let draw = |scene: Scene| {
        let mut r = Renderer::new(common::test_gpu(), scene, None, size, 1).unwrap_or_else(|e| panic!("{e}"));
        let cam = r.scene.camera.clone();
        let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
        common::assert_clean(&r.gpu);
        mean(&img)
    };
    let (corrected, faithful, want) = (draw(scene), draw(frame("faithful")), mean(&truth));
    eprintln!("frame means: corrected light-map {corrected:.4}, faithful {faithful:.4}, path tracer {want:.4}");
    assert!(
        (corrected / want - 1.0).abs() < 0.03,
        "corrected {corrected:.4} against the path tracer's {want:.4}"
    );
    assert!(
        faithful < 0.01 * want,
        "the document's light-map has no sky: {faithful:.4}"
    );
}
