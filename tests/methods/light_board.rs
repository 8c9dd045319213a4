//! The light board (`[light_board]`) as the renderer applies it: a frame's pixel lit by one light
//! is frame 0's times that light's factor `Scene::light_factors(t)`, under the forward method and
//! under shadow_volumes (which reads each light's intensity per frame); frame 0 is the static
//! scene; and without a board frames do not change. Also: every shipped scene loads with methods
//! the registry knows, and the many-light scenes have the lights and triangles they promise.

use crate::support as common;

use penumbra::lighting::registry;
use penumbra::lighting::FrameClock;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::{Light, Scene};
use penumbra::util::image_io::HdrImage;

const SIZE: (u32, u32) = (48, 32);
/// The frame compared with frame 0 (0.75 s: the factors are well away from 1).
const LATER: u64 = 45;

/// A floor seen from straight above, lit by two narrow spots 3 m up at x = ±3 m (the centres of
/// a 2-cell grid 12 m wide; their cones do not overlap), and `board` after them.
fn scene(method: &str, board: &str) -> Scene {
    let text = format!(
        r#"methods = [{method}]
[camera]
position = [0, 6, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov_y_deg = 60

[[objects]]
mesh = "plane"
size = [12, 12]

[[light_arrays]]
name = "pair"
type = "spot"
grid = [2, 1, 1]
min = [-6, 3, 0]
max = [6, 3, 0]
intensity = [4, 3, 2]
inner_deg = 20
outer_deg = 25
{board}"#
    );
    Scene::from_str(&text, "<light board test>", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// Frames 0 and [`LATER`] of `scene`.
fn frames(scene: Scene) -> (HdrImage, HdrImage) {
    let mut r = Renderer::new(common::test_gpu(), scene, None, SIZE, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let first = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    for _ in 1..LATER {
        r.render(&cam, FrameOutput::None).unwrap();
        r.gpu.submit_and_wait(r.last_frame()).unwrap();
    }
    let later = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    (first, later)
}

fn pixel(img: &HdrImage, x: u32, y: u32) -> [f32; 3] {
    let p = img.get(x, y);
    [p[0], p[1], p[2]]
}

/// Under each light's cone axis (x = ±3 m of a 12 m-wide view): the two lit pixels.
fn lit_pixels() -> [(u32, u32); 2] {
    let (w, h) = SIZE;
    // The camera sees 2·6·tan 30° = 6.93 m vertically, so ±3 m is ±0.65 of the half-width.
    let half = 6.0 * (30f32.to_radians()).tan() * w as f32 / h as f32;
    let x = |wx: f32| ((wx / half * 0.5 + 0.5) * w as f32) as u32;
    [(x(-3.0), h / 2), (x(3.0), h / 2)]
}

fn check_board(method: &str) {
    let board = "[light_board]\ndepth = 0.8\nrate_hz = 1.0\nseed = 5\n";
    let s = scene(method, board);
    let factors = s.light_factors(LATER as f32 * FrameClock::STEP_S);
    assert!(
        factors.iter().all(|&f| f < 0.97) && (factors[0] - factors[1]).abs() > 0.02,
        "a useful time: {factors:?}"
    );
    let (first, later) = frames(s);
    let (still_first, _) = frames(scene(method, ""));
    assert_eq!(
        first.pixels, still_first.pixels,
        "{method}: frame 0 is the static scene"
    );
    for (l, (x, y)) in lit_pixels().into_iter().enumerate() {
        let (a, b) = (pixel(&first, x, y), pixel(&later, x, y));
        for c in 0..3 {
            assert!(a[c] > 1e-3, "{method}: pixel ({x}, {y}) is lit by light {l}: {a:?}");
            let ratio = b[c] / a[c];
            assert!(
                (ratio - factors[l]).abs() < 1e-4,
                "{method}: light {l} at ({x}, {y}) channel {c}: {} / {} = {ratio}, factor {}",
                b[c],
                a[c],
                factors[l]
            );
        }
    }
}

#[test]
fn forward_frames_follow_the_board_factors() {
    check_board(r#"{ name = "forward" }"#);
}

#[test]
fn shadow_volumes_frames_follow_the_board_factors() {
    check_board(r#"{ name = "shadow_volumes", mode = "physical", animate = false }"#);
}

#[test]
fn without_a_board_frames_do_not_change() {
    for method in [
        r#"{ name = "forward" }"#,
        r#"{ name = "shadow_volumes", mode = "physical", animate = false }"#,
    ] {
        let (first, later) = frames(scene(method, ""));
        assert_eq!(first.pixels, later.pixels, "{method}");
    }
}

/// The many-light scenes with their light and triangle counts.
const MANY_LIGHT_SCENES: [(&str, usize, usize); 8] = [
    ("many_box.toml", 1, 14),
    ("many_polygon3.toml", 3, 4),
    ("many_intersecting.toml", 10, 6),
    ("many_slanted.toml", 25, 10),
    ("theatre_50.toml", 50, 70),
    ("theatre_100.toml", 100, 70),
    ("many_stress.toml", 1024, 70),
    ("many_bounded.toml", 1024, 70),
];

#[test]
fn every_shipped_scene_loads_and_the_many_light_scenes_are_as_promised() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    for (name, ..) in MANY_LIGHT_SCENES {
        assert!(names.iter().any(|n| n == name), "{name} is missing");
    }
    for name in &names {
        let s = Scene::from_file(dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
        registry::configurations(&s).unwrap_or_else(|e| panic!("{name}: {e}"));
        let Some(&(_, lights, triangles)) = MANY_LIGHT_SCENES.iter().find(|(n, ..)| n == name) else {
            continue;
        };
        assert_eq!(s.lights.len(), lights, "{name}");
        assert!(
            s.lights.iter().all(|l| matches!(l, Light::Spot { .. })),
            "{name}: spot lights (shadow_volumes lights point and spot lights only)"
        );
        let tris: usize = s
            .objects
            .iter()
            .map(|o| o.load_mesh(&dir).unwrap().indices.len() / 3)
            .sum();
        assert_eq!(tris, triangles, "{name}");
        assert!(
            s.materials.iter().all(|m| m.specular == glam::Vec3::ZERO),
            "{name}: the seed's scenes are diffuse"
        );
        let methods: Vec<&str> = s.methods.iter().map(|m| m.name.as_str()).collect();
        // The seed's two systems, the two baselines a user would pick today and the naive loop.
        assert_eq!(
            methods,
            ["bsp_lights", "vls", "clustered", "forward", "shadow_volumes"],
            "{name}"
        );
        assert_eq!(
            s.light_board.is_some(),
            lights >= 50,
            "{name}: the theatres and the stress scene have a light board"
        );
    }
}
