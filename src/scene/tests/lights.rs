//! `[[light_arrays]]` and `[light_board]`: expansion into ordinary lights, the board's factors,
//! and errors naming file, line and field. (tests/methods/light_board.rs loads the shipped scenes against
//! the registry's method schemas.)

use std::path::Path;

use glam::Vec3;

use super::super::generators::MAX_ARRAY_LIGHTS;
use super::super::*;

const CAM: &str = "[camera]\nposition = [0, 1, 5]\ntarget = [0, 0, 0]\n"; // lines 1-3

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::from_str(text, "bad.toml", Path::new("."))
}

#[track_caller]
fn fails_at(text: &str, line: usize, field: &str) -> SceneError {
    let e = parse(text).expect_err("scene should be rejected");
    assert_eq!(
        (e.file.as_str(), e.line, e.field.as_str()),
        ("bad.toml", Some(line), field),
        "{e}"
    );
    assert!(!e.to_string().contains('\n'), "error spans lines: {e}");
    e
}

/// A 4 × 1 × 3 rig of spots, lines 4–13; `extra` follows from line 14.
fn rig(extra: &str) -> String {
    format!(
        "{CAM}[[light_arrays]]\nname = \"rig\"\ntype = \"spot\"\ngrid = [4, 1, 3]\nmin = [-2, 3, -1]\nmax = [2, 3, 1]\nintensity = 10\ncolours = [[1, 0, 0], [0, 0, 1], [0, 1, 0]]\nouter_deg = 40\ninner_deg = 20\n{extra}"
    )
}

fn spot(l: &Light) -> (&str, Vec3, Vec3, Vec3, f32, f32) {
    match l {
        Light::Spot {
            name,
            position,
            direction,
            intensity,
            inner_deg,
            outer_deg,
            ..
        } => (name, *position, *direction, *intensity, *inner_deg, *outer_deg),
        other => panic!("expected a spot light, got {other:?}"),
    }
}

fn inside(p: Vec3, lo: Vec3, hi: Vec3) -> bool {
    p.cmpge(lo).all() && p.cmple(hi).all()
}

#[test]
fn a_grid_expands_into_named_spots_at_cell_centres() {
    let s = parse(&rig(
        "[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 1\n",
    ))
    .unwrap();
    // The hand-written light first, then the array's 12 in lattice order.
    assert_eq!(s.lights.len(), 13);
    assert!(matches!(s.lights[0], Light::Point { .. }));
    for (i, l) in s.lights[1..].iter().enumerate() {
        let (name, p, d, intensity, inner, outer) = spot(l);
        assert_eq!(name, format!("rig[{i}]"));
        let (x, z) = (i % 4, i / 4);
        let want = Vec3::new(-2.0 + (x as f32 + 0.5), 3.0, -1.0 + 2.0 * (z as f32 + 0.5) / 3.0);
        assert!((p - want).length() < 1e-5, "light {i} at {p}, expected {want}");
        assert_eq!(d, Vec3::NEG_Y, "no jitter: straight down");
        let tint = [Vec3::X, Vec3::Z, Vec3::Y][i % 3];
        assert_eq!(intensity, 10.0 * tint);
        assert_eq!((inner, outer), (20.0, 40.0));
    }
    assert_eq!(s.light_board, None);
}

#[test]
fn a_scatter_stays_in_its_box_and_depends_on_its_seed_alone() {
    let text = |seed: u32, jitter: f32| {
        format!("{CAM}[[light_arrays]]\ntype = \"spot\"\ncount = 200\ncenter = [1, 4, 0]\nsize = [6, 0, 3]\ndirection = [0, -1, 0]\njitter_deg = {jitter}\nseed = {seed}\nintensity = [1, 2, 3]\n")
    };
    let a = parse(&text(7, 12.0)).unwrap();
    assert_eq!(
        a.lights,
        parse(&text(7, 12.0)).unwrap().lights,
        "same seed, same lights"
    );
    let b = parse(&text(8, 12.0)).unwrap();
    assert_ne!(a.lights, b.lights, "another seed, other lights");
    let (lo, hi) = (Vec3::new(-2.0, 4.0, -1.5), Vec3::new(4.0, 4.0, 1.5));
    let mut max_tilt = 0f32;
    for (i, l) in a.lights.iter().enumerate() {
        let (name, p, d, intensity, inner, outer) = spot(l);
        assert_eq!(
            name,
            format!("light_arrays[0][{i}]"),
            "unnamed arrays take their field path"
        );
        assert!(inside(p, lo, hi), "light {i} at {p} outside the box");
        let tilt = d.dot(Vec3::NEG_Y).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(
            tilt <= 12.0 + 1e-3 && (d.length() - 1.0).abs() < 1e-5,
            "light {i} tilted {tilt}°"
        );
        max_tilt = max_tilt.max(tilt);
        assert_eq!(
            (intensity, inner, outer),
            (Vec3::new(1.0, 2.0, 3.0), 24.0, 30.0),
            "defaults as a single spot's"
        );
    }
    assert!(max_tilt > 9.0, "the jitter is used: largest tilt {max_tilt}°");
    // The jitter draws from its own stream: changing it turns the lights without moving them.
    let still = parse(&text(7, 0.0)).unwrap();
    for (l, m) in a.lights.iter().zip(&still.lights) {
        assert_eq!(spot(l).1, spot(m).1);
        assert_eq!(spot(m).2, Vec3::NEG_Y);
    }
}

#[test]
fn targets_aim_every_spot_and_point_arrays_take_no_aim() {
    let s = parse(&format!("{CAM}[[light_arrays]]\nname = \"side\"\ntype = \"spot\"\ngrid = [1, 2, 5]\nmin = [-4, 1, -2]\nmax = [-4, 3, 2]\ntarget = [0, 0.5, 0]\nintensity = 3\n")).unwrap();
    assert_eq!(s.lights.len(), 10);
    for l in &s.lights {
        let (_, p, d, ..) = spot(l);
        assert!(d.dot((Vec3::new(0.0, 0.5, 0.0) - p).normalize()) > 0.99999);
        assert!(inside(p, Vec3::new(-4.0, 1.0, -2.0), Vec3::new(-4.0, 3.0, 2.0)));
    }
    let s = parse(
        &format!("{CAM}[[light_arrays]]\nname = \"bulbs\"\ntype = \"point\"\ngrid = [2, 2, 2]\nmin = 0\nmax = 1\nintensity = 1\nradius = 4\n")
            .replace("min = 0\nmax = 1", "min = [0, 0, 0]\nmax = [1, 1, 1]"),
    )
    .unwrap();
    assert_eq!(s.lights.len(), 8);
    assert!(s
        .lights
        .iter()
        .all(|l| matches!(l, Light::Point { radius, .. } if *radius == 4.0)));
    assert_eq!(s.lights[7].name(), "bulbs[7]");
}

#[test]
fn malformed_arrays_name_their_field_and_line() {
    // Each replaces one line of `rig` (or adds one).
    let with = |old: &str, new: &str| {
        let t = rig("");
        assert!(t.contains(old), "{old}");
        t.replacen(old, new, 1)
    };
    fails_at(&with("type = \"spot\"\n", ""), 4, "light_arrays[0].type");
    fails_at(&with("type = \"spot\"", "type = \"laser\""), 6, "light_arrays[0].type");
    fails_at(&with("intensity = 10\n", ""), 4, "light_arrays[0].intensity");
    fails_at(
        &with("intensity = 10", "intensity = inf"),
        10,
        "light_arrays[0].intensity",
    );
    fails_at(&with("grid = [4, 1, 3]\n", ""), 4, "light_arrays[0].grid");
    fails_at(&with("max = [2, 3, 1]\n", ""), 4, "light_arrays[0].max");
    fails_at(
        &with("min = [-2, 3, -1]", "min = [nan, 3, -1]"),
        8,
        "light_arrays[0].min",
    );
    fails_at(&with("max = [2, 3, 1]", "max = [2, 2, 1]"), 9, "light_arrays[0].max");
    fails_at(
        &with("max = [2, 3, 1]", "max = [2, 3, 1]\ncenter = [0, 0, 0]"),
        10,
        "light_arrays[0].center",
    );
    fails_at(&with("grid = [4, 1, 3]", "grid = [4, 0, 3]"), 7, "light_arrays[0].grid");
    fails_at(&with("grid = [4, 1, 3]", "grid = [4, 3]"), 7, "light_arrays[0].grid");
    fails_at(
        &with("grid = [4, 1, 3]", "grid = [4, 1, 3]\ncount = 5"),
        7,
        "light_arrays[0].grid",
    );
    fails_at(
        &with("colours = [[1, 0, 0], [0, 0, 1], [0, 1, 0]]", "colours = []"),
        11,
        "light_arrays[0].colours",
    );
    fails_at(
        &with(
            "colours = [[1, 0, 0], [0, 0, 1], [0, 1, 0]]",
            "colours = [[1, 0, 0], [0, -1, 1]]",
        ),
        11,
        "light_arrays[0].colours[1]",
    );
    fails_at(
        &with("inner_deg = 20", "inner_deg = 50"),
        13,
        "light_arrays[0].inner_deg",
    );
    fails_at(
        &with("outer_deg = 40", "outer_deg = 40\njitter_deg = 120"),
        13,
        "light_arrays[0].jitter_deg",
    );
    fails_at(
        &with("name = \"rig\"", "name = \"rig\"\nintensty = 3"),
        6,
        "light_arrays[0].intensty",
    );
    fails_at(
        &with("type = \"spot\"", "type = \"point\""),
        12,
        "light_arrays[0].outer_deg",
    );
    // A light exactly on the target has no axis.
    let on_target =
        with("grid = [4, 1, 3]", "grid = [1, 1, 1]").replace("max = [2, 3, 1]", "max = [2, 3, 1]\ntarget = [0, 3, 0]");
    fails_at(&on_target, 10, "light_arrays[0].target");

    // The limit: one array, a grid whose product overflows a u32, and the scene's total.
    let e = fails_at(
        &with("grid = [4, 1, 3]\n", &format!("count = {}\n", MAX_ARRAY_LIGHTS + 1)),
        7,
        "light_arrays[0].count",
    );
    assert!(e.message.contains("65536"), "{e}");
    let e = fails_at(
        &with("grid = [4, 1, 3]", "grid = [65536, 65536, 2]"),
        7,
        "light_arrays[0].grid",
    );
    assert_eq!(
        e.message, "8589934592 lights: the light arrays of a scene may make at most 65536",
        "{e}"
    );
    let two = |n: u32| {
        format!("{CAM}[[light_arrays]]\ntype = \"point\"\ncount = {n}\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nintensity = 1\n[[light_arrays]]\ntype = \"point\"\ncount = {n}\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nintensity = 1\n")
    };
    assert_eq!(
        parse(&two(MAX_ARRAY_LIGHTS / 2)).unwrap().lights.len(),
        MAX_ARRAY_LIGHTS as usize,
        "exactly the limit loads"
    );
    let e = fails_at(&two(MAX_ARRAY_LIGHTS / 2 + 1), 12, "light_arrays[1].count");
    assert!(e.message.contains("after 32769 from the arrays before it"), "{e}");
}

#[test]
fn malformed_boards_name_their_field_and_line() {
    let board = |body: &str| rig(&format!("[light_board]\n{body}"));
    fails_at(&board("depth = 1.5\n"), 15, "light_board.depth");
    fails_at(&board("depth = -0.1\n"), 15, "light_board.depth");
    fails_at(&board("rate_hz = 1\ndepth = nan\n"), 16, "light_board.depth");
    fails_at(&board("rate_hz = 0\n"), 15, "light_board.rate_hz");
    fails_at(&board("rate_hz = inf\n"), 15, "light_board.rate_hz");
    fails_at(&board("seed = -1\n"), 15, "light_board.seed");
    fails_at(&board("dept = 0.5\n"), 15, "light_board.dept");
    fails_at(&format!("light_board = 3\n{CAM}"), 1, "light_board");
    let s = parse(&board("")).unwrap();
    assert_eq!(
        s.light_board,
        Some(LightBoard {
            depth: 0.5,
            rate_hz: 0.5,
            seed: 1
        }),
        "documented defaults"
    );
}

#[test]
fn board_factors_start_at_one_change_every_frame_and_stay_in_range() {
    let depth = 0.6;
    let s = parse(&rig(&format!("[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n[light_board]\ndepth = {depth}\nrate_hz = 2\nseed = 9\n"))).unwrap();
    let n = s.lights.len();
    assert_eq!(s.light_factors(0.0), vec![1.0; n], "frame 0 is the static scene");
    // The renderer's clock step (lighting::FrameClock::STEP_S; the scene module sits below the
    // lighting layer, so it is not named here).
    let step = 1.0 / 60.0;
    let mut previous = s.light_factors(0.0);
    let mut lowest = vec![1f32; n];
    for frame in 1..=600u64 {
        let f = s.light_factors(frame as f32 * step);
        assert_eq!(f.len(), n);
        for l in 1..n {
            assert!(f[l] != previous[l], "light {l} unchanged at frame {frame}");
            assert!(
                f[l] >= 1.0 - depth - 1e-6 && f[l] <= 1.0,
                "light {l} at frame {frame}: {}",
                f[l]
            );
            lowest[l] = lowest[l].min(f[l]);
        }
        assert_eq!(f[0], 1.0, "the directional light is not on the board");
        previous = f;
    }
    // Over 10 s at 1–3 Hz every light dims nearly to the bottom, and the rates differ.
    assert!(lowest[1..].iter().all(|&m| m < 1.0 - 0.95 * depth), "{lowest:?}");
    let board = s.light_board.unwrap();
    let rates: Vec<f64> = (1..n).map(|l| board.rate_of(l)).collect();
    assert!(rates.iter().all(|&r| (1.0..3.0).contains(&r)), "{rates:?}");
    assert!(rates.windows(2).all(|w| w[0] != w[1]));
    // Without a board every factor is 1 at every time.
    let still = parse(&rig("")).unwrap();
    assert!([0.0, 0.5, 17.25]
        .iter()
        .all(|&t| still.light_factors(t).iter().all(|&f| f == 1.0)));
}

/// Reading a scene is linear in its entries: 8,192 explicit `[[lights]]` load in well under a
/// second here (when every field's line was found by counting newlines from the top, 4,096 took
/// 25 s and 8,192 about 100 s).
#[test]
fn many_explicit_lights_load_in_linear_time() {
    let mut text = String::from("[camera]\nposition = [0, 2, 5]\ntarget = [0, 0, 0]\n");
    for i in 0..8192 {
        text += &format!(
            "\n[[lights]]\nname = \"l{i}\"\ntype = \"point\"\nposition = [{}, 3, {}]\nintensity = [1, 1, 1]\n",
            i % 97,
            i / 97
        );
    }
    let start = std::time::Instant::now();
    let scene = parse(&text).unwrap();
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(scene.lights.len(), 8192);
    assert!(seconds < 5.0, "8,192 lights took {seconds:.1} s to read");
    // Errors still name the right line deep in the file.
    let bad = text.replace(
        "name = \"l8000\"\ntype = \"point\"",
        "name = \"l8000\"\ntype = \"pointy\"",
    );
    let e = parse(&bad).unwrap_err().to_string();
    let line = bad.lines().position(|l| l == "type = \"pointy\"").unwrap() + 1;
    assert!(e.contains(&format!(":{line}:")), "{e} (want line {line})");
}

/// A tiny but non-zero direction is a direction (its f32 squared length underflows, not the
/// vector), and a zero one is refused naming the values given.
#[test]
fn a_tiny_direction_is_kept_and_a_zero_one_reported_as_given() {
    let sun = |d: &str| format!("{CAM}[[lights]]\ntype = \"directional\"\ndirection = {d}\nirradiance = 1\n");
    let s = parse(&sun("[1e-30, -2e-30, 0]")).unwrap_or_else(|e| panic!("{e}"));
    match &s.lights[0] {
        Light::Directional { direction, .. } => {
            let want = Vec3::new(1.0, -2.0, 0.0).normalize();
            assert!((*direction - want).length() < 1e-6, "{direction}");
        }
        l => panic!("{l:?}"),
    }
    let e = fails_at(&sun("[0, 0, -0.0]"), 6, "lights[0].direction");
    assert!(e.to_string().contains("got [0, 0, -0]"), "{e}");
}
