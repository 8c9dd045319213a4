//! Defaults derived from the scene, and methods over their memory budget refused before anything
//! is allocated: `registry::plan` runs on the CPU alone, before a device exists.

use std::path::Path;
use std::time::{Duration, Instant};

use penumbra::lighting::registry;
use penumbra::scene::Scene;

fn shipped(name: &str) -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    Scene::from_file(dir.join("scenes").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// `scene` with its methods replaced by `methods` (a TOML array) and a budget when given.
fn with_methods(name: &str, methods: &str, budget_mb: Option<u32>) -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(dir.join(name)).unwrap();
    let mut out = String::new();
    if let Some(mb) = budget_mb {
        out += &format!("memory_budget_mb = {mb}\n");
    }
    out += &format!("methods = {methods}\n");
    let mut skipping = false;
    for line in text.lines() {
        // The file's own `methods = [...]`, on one line or several, and its combinations.
        if line.starts_with("methods") {
            skipping = !line.trim_end().ends_with(']');
            continue;
        }
        if skipping {
            skipping = line.trim() != "]";
            continue;
        }
        out += line;
        out += "\n";
    }
    let out = out.replace("[[combinations]]", "[[unused]]");
    let out = strip_table(&out, "[[unused]]");
    Scene::from_str(&out, name, &dir).unwrap_or_else(|e| panic!("{e}"))
}

/// `text` without the tables headed `header` (up to the next header).
fn strip_table(text: &str, header: &str) -> String {
    let mut out = String::new();
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with('[') {
            inside = line.trim() == header;
        }
        if !inside {
            out += line;
            out += "\n";
        }
    }
    out
}

/// `method`'s plan on `scene`: its refusal's message and how long it took to come.
fn refusal(scene: &Scene, method: &str) -> (String, Duration) {
    let config = registry::configuration(scene, Some(method)).unwrap_or_else(|e| panic!("{e}"));
    let start = Instant::now();
    let result = registry::plan(&config, scene);
    let took = start.elapsed();
    match result {
        Err(e) => (e.to_string(), took),
        Ok((c, _)) => panic!("{method} was not refused: {:?}", c.parts[0].decl),
    }
}

fn assert_refusal(message: &str, took: Duration, needs: &[&str]) {
    println!("{message} ({took:?})");
    assert!(!message.contains('\n'), "one line: {message}");
    for n in needs.iter().chain(&["would need", "memory_budget_mb"]) {
        assert!(message.contains(n), "`{n}` missing from: {message}");
    }
    // Up front, not after a bake (which takes tens of seconds and more): the triangle soup's
    // refusal, the slowest, took 0.55 s alone and 1.16 s beside a build on lavapipe's 2-core
    // host, so the bound leaves room for a loaded machine.
    assert!(took < Duration::from_secs(3), "refused after {took:?}");
}

/// The size a refusal names, in MB.
fn needed_mb(message: &str) -> f64 {
    let tail = message.split("would need ").nth(1).unwrap();
    let mut words = tail.split_whitespace();
    let value: f64 = words.next().unwrap().parse().unwrap();
    match words.next().unwrap().trim_end_matches(',') {
        "GB" => value * 1024.0,
        "MB" => value,
        other => panic!("unit {other}"),
    }
}

/// Radiosity at 5 mm patches on the BSP rooms grew to 6 GB before anything was said: the patches
/// are counted before any is made and the bake refused with the size it would need.
#[test]
fn radiosity_over_the_budget_is_refused_before_baking() {
    let scene = with_methods(
        "bsp_rooms.toml",
        r#"[{ name = "radiosity", patch_size = 0.005 }]"#,
        None,
    );
    let (message, took) = refusal(&scene, "radiosity");
    assert_refusal(
        &message,
        took,
        &["bsp_rooms.toml", "radiosity", "patch_size = 0.005", "patches", "GB"],
    );
    assert!(needed_mb(&message) > 2048.0, "{message}");
    // The same bake at the shipped 50 cm fits.
    let scene = with_methods("bsp_rooms.toml", r#"[{ name = "radiosity", patch_size = 0.5 }]"#, None);
    let config = registry::configuration(&scene, Some("radiosity")).unwrap();
    registry::plan(&config, &scene).unwrap_or_else(|e| panic!("{e}"));
}

/// The SH light-map's CPU baker never checked its patch count (2.2 GB at 5 mm on the courtyard).
#[test]
fn sh_lightmap_over_the_budget_is_refused_before_baking() {
    let scene = with_methods(
        "sh_courtyard.toml",
        r#"[{ name = "sh_lightmap", patch_size = 0.005, baker = "cpu" }]"#,
        None,
    );
    let (message, took) = refusal(&scene, "sh_lightmap");
    assert_refusal(
        &message,
        took,
        &[
            "sh_lightmap",
            "patch_size = 0.005",
            "patches",
            "rays",
            "set a larger patch_size",
        ],
    );
    assert!(needed_mb(&message) > 2048.0, "{message}");
}

/// A triangle soup (8,192 triangles that share no edge, as scanned foliage or debris is often
/// modelled) makes a chart per triangle, each at least a texel in its border frame, so no
/// patch_size brings its light-map within the budget: the refusal says so, with its chart count
/// and the samples that would fit, instead of asking for a larger patch_size. (A curved surface
/// merges its triangles into charts instead: `src/lighting/radiosity/tests/curved.rs`.)
#[test]
fn a_triangle_soups_light_map_is_refused_with_advice_that_can_work() {
    let dir = crate::support::temp_path("soup");
    std::fs::create_dir_all(&dir).unwrap();
    let mut obj = String::new();
    let mut rng = crate::support::rng::Lcg(7);
    for t in 0..8192 {
        let centre = [0; 3].map(|_| rng.next_f64() * 4.0 - 2.0);
        for _ in 0..3 {
            let p: Vec<String> = (0..3)
                .map(|a| format!("{}", centre[a] + rng.next_f64() * 0.05))
                .collect();
            obj += &format!("v {}\n", p.join(" "));
        }
        obj += &format!("f {} {} {}\n", 3 * t + 1, 3 * t + 2, 3 * t + 3);
    }
    std::fs::write(dir.join("soup.obj"), obj).unwrap();
    let text = |methods: &str| {
        format!(
            "memory_budget_mb = 100\nmethods = {methods}\n[camera]\nposition = [0, 2, 4]\ntarget = [0, 0, 0]\n\
             [[objects]]\nmesh = \"obj\"\npath = \"soup.obj\"\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n"
        )
    };
    let scene_of = |methods: &str| Scene::from_str(&text(methods), "<test>", &dir).unwrap_or_else(|e| panic!("{e}"));
    let (message, took) = refusal(&scene_of(r#"["sh_lightmap"]"#), "sh_lightmap");
    assert_refusal(&message, took, &["charts", "at any patch_size", "at most fit"]);
    assert!(!message.contains("set a larger patch_size"), "{message}");
    let samples: u64 = message
        .split("samples (")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((20..10_000).contains(&samples), "{message}");
    // The samples it names fit.
    let fitted = scene_of(&format!(r#"[{{ name = "sh_lightmap", samples = {samples} }}]"#));
    let config = registry::configuration(&fitted, Some("sh_lightmap")).unwrap();
    registry::plan(&config, &fitted).unwrap_or_else(|e| panic!("{samples} samples: {e}"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A budget the scene raises lets the same bake through; one it lowers refuses the shipped one.
#[test]
fn the_scene_sets_the_budget() {
    let raised = with_methods(
        "bsp_rooms.toml",
        r#"[{ name = "radiosity", patch_size = 0.005 }]"#,
        Some(1 << 20),
    );
    let config = registry::configuration(&raised, Some("radiosity")).unwrap();
    registry::plan(&config, &raised).unwrap_or_else(|e| panic!("{e}"));
    let lowered = with_methods(
        "bsp_rooms.toml",
        r#"[{ name = "radiosity", patch_size = 0.5 }]"#,
        Some(1),
    );
    let (message, took) = refusal(&lowered, "radiosity");
    assert_refusal(
        &message,
        took,
        &["the scene's memory_budget_mb or --memory-budget-mb", "budget of 1.0 MB"],
    );
    let bad = Scene::from_str(
        "memory_budget_mb = 0\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n",
        "b.toml",
        Path::new("."),
    );
    let Err(e) = bad else {
        panic!("a budget of 0 MB is refused")
    };
    let e = e.to_string();
    assert!(e.contains("b.toml") && e.contains("memory_budget_mb"), "{e}");
}

/// The VQ table is part of what the SH light-map needs: the same small bake fits without it and
/// is refused with 65,536 representatives (8 MB of f64 at 16 coefficients) in an 8 MB budget.
#[test]
fn sh_lightmap_vq_table_over_the_budget_is_refused() {
    let plain = with_methods(
        "sh_courtyard.toml",
        r#"[{ name = "sh_lightmap", patch_size = 2.0, samples = 1024 }]"#,
        Some(8),
    );
    let config = registry::configuration(&plain, Some("sh_lightmap")).unwrap();
    registry::plan(&config, &plain).unwrap_or_else(|e| panic!("{e}"));
    let vq = with_methods(
        "sh_courtyard.toml",
        r#"[{ name = "sh_lightmap", patch_size = 2.0, samples = 1024, reps = 65536 }]"#,
        Some(8),
    );
    let (message, took) = refusal(&vq, "sh_lightmap");
    assert_refusal(
        &message,
        took,
        &["VQ table of 65536 representatives", "fewer representatives (reps)"],
    );
    assert!(needed_mb(&message) > 8.0, "{message}");
}

/// The LPV at its largest (128³ in f32, 4 cascades: 2.2 GB of volumes) is refused.
#[test]
fn lpv_volume_over_the_budget_is_refused() {
    let scene = with_methods(
        "lpv_cornell.toml",
        r#"[{ name = "lpv", grid = 128, storage = "f32", cascades = 4 }]"#,
        None,
    );
    let (message, took) = refusal(&scene, "lpv");
    assert_refusal(&message, took, &["4 volume(s) of 128³ cells in f32", "GB"]);
    // 4 × (3 sets of 128³ × 48 bytes + 128³ × 128 bytes): 2,281 MB, and the 256² RSM.
    let want = 4.0 * (3.0 * 48.0 + 128.0) * 128f64.powi(3) / (1024.0 * 1024.0);
    assert!(
        (needed_mb(&message) - want).abs() < 0.05 * 1024.0,
        "{message}: want {want} MB"
    );
    let fits = with_methods(
        "lpv_cornell.toml",
        r#"[{ name = "lpv", grid = 128, storage = "f32" }]"#,
        None,
    );
    let config = registry::configuration(&fits, Some("lpv")).unwrap();
    registry::plan(&config, &fits).unwrap_or_else(|e| panic!("{e}"));
}

/// VLS's set-up over the 1,024-light stage at 1 cm² segments does not fit 16 MB.
#[test]
fn vls_setup_over_the_budget_is_refused() {
    let scene = with_methods(
        "many_stress.toml",
        r#"[{ name = "vls", max_segment_area = 0.0001 }]"#,
        Some(16),
    );
    let (message, took) = refusal(&scene, "vls");
    assert_refusal(
        &message,
        took,
        &["segments at max_segment_area = 0.0001", "budget of 16.0 MB"],
    );
}

/// A value derived for the corrected mode stays out of the chart's faithful point: the thesis's
/// VLS keeps its 8 lights (not the 32 derived for the theatre's 100) and the document's PRT bakes
/// the meshes as they are (no derived `max_edge`).
#[test]
fn the_faithful_sweep_point_keeps_the_documents_own_defaults() {
    for (scene, method, param, faithful_label) in [
        (
            "theatre_100.toml",
            "vls",
            "k",
            "vls faithful k=8 closest feeler=thesis area=0.043",
        ),
        (
            "prt_teapot_box.toml",
            "prt",
            "max_edge",
            "prt faithful orthographic 32² n=16",
        ),
    ] {
        let scene = shipped(scene);
        let config = registry::configuration(&scene, Some(method)).unwrap();
        let (planned, notes) = registry::plan(&config, &scene).unwrap();
        assert!(
            notes.iter().any(|n| n.starts_with(&format!("{method}: {param} = "))),
            "{notes:?}"
        );
        assert!(planned.parts[0].decl.param(param).is_some());
        let sweep = registry::sweep(&planned).unwrap();
        let labels: Vec<&str> = sweep.iter().map(|(l, _)| l.as_str()).collect();
        let (_, faithful) = sweep
            .iter()
            .find(|(l, _)| l == faithful_label)
            .unwrap_or_else(|| panic!("no {faithful_label:?} in {labels:?}"));
        assert_eq!(faithful.parts[0].decl.param(param), None, "{method}");
    }
}

/// Parameters the scene leaves unset are derived from it and said in one line each; set ones
/// are kept and draw no line.
#[test]
fn unset_parameters_are_derived_from_the_scene() {
    // Two rooms side by side, 6.05 m along x: the fitted 32³ volume spans them in 30 cells, and
    // light from their middle crosses 15.
    let scene = shipped("lpv_two_rooms.toml");
    let config = registry::configuration(&scene, Some("lpv")).unwrap();
    let (planned, notes) = registry::plan(&config, &scene).unwrap();
    println!("{notes:?}");
    assert_eq!(
        planned.parts[0].decl.param("iterations").and_then(|v| v.as_integer()),
        Some(15)
    );
    assert!(
        notes.iter().any(
            |n| n.starts_with("lpv: iterations = 15 (grid 32 cells: the scene's 6.05 m spans 30")
                && n.ends_with("set iterations to override)")
        ),
        "{notes:?}"
    );
    // Set by the scene: kept, nothing said.
    let set = with_methods("lpv_two_rooms.toml", r#"[{ name = "lpv", iterations = 8 }]"#, None);
    let config = registry::configuration(&set, Some("lpv")).unwrap();
    let (planned, notes) = registry::plan(&config, &set).unwrap();
    assert_eq!(
        planned.parts[0].decl.param("iterations").and_then(|v| v.as_integer()),
        Some(8)
    );
    assert!(notes.is_empty(), "{notes:?}");
    // A region of 3 m at 32³ (cells of 9.4 cm) over the 6.05 m rooms: all 32 cells, 16 passes.
    let region = with_methods(
        "lpv_two_rooms.toml",
        r#"[{ name = "lpv", centre = [0, 1, 0], size = 3.0 }]"#,
        None,
    );
    let config = registry::configuration(&region, Some("lpv")).unwrap();
    let (planned, _) = registry::plan(&config, &region).unwrap();
    assert_eq!(
        planned.parts[0].decl.param("iterations").and_then(|v| v.as_integer()),
        Some(16)
    );
    // ... and one of 12 m: the rooms span 6.05 / 0.375 → 17 cells, 9 passes.
    let region = with_methods(
        "lpv_two_rooms.toml",
        r#"[{ name = "lpv", centre = [0, 1, 0], size = 12.0 }]"#,
        None,
    );
    let config = registry::configuration(&region, Some("lpv")).unwrap();
    let (planned, _) = registry::plan(&config, &region).unwrap();
    assert_eq!(
        planned.parts[0].decl.param("iterations").and_then(|v| v.as_integer()),
        Some(9)
    );
    // The document's mode keeps its own 2.
    let faithful = with_methods("lpv_two_rooms.toml", r#"[{ name = "lpv", mode = "faithful" }]"#, None);
    let config = registry::configuration(&faithful, Some("lpv")).unwrap();
    let (planned, _) = registry::plan(&config, &faithful).unwrap();
    assert_eq!(planned.parts[0].decl.param("iterations"), None);
}

/// Light-map patches and many-light segments from the scene's area: the two rooms' 24 quads
/// hold 2 × (2 × 12 + 2 × 7.5 + 2 × 10) − 2 × 2 (the door) + 4 × 0.05-wide door faces m².
#[test]
fn patch_and_segment_sizes_follow_the_scene_area() {
    let area: f64 = 2.0 * (2.0 * 12.0 + 2.0 * 7.5 + 2.0 * 10.0) - 2.0 * 2.0 + 0.05 * (1.0 + 2.0 + 2.0 + 1.0);
    let derived = |method: &str, param: &str| {
        let scene = with_methods("lpv_two_rooms.toml", &format!(r#"["{method}"]"#), None);
        let config = registry::configuration(&scene, Some(method)).unwrap();
        let (planned, notes) = registry::plan(&config, &scene).unwrap();
        println!("{notes:?}");
        assert!(notes.iter().any(|n| n.contains(&format!("{area:.3} m²"))), "{notes:?}");
        planned.parts[0].decl.param(param).and_then(|v| v.as_float()).unwrap()
    };
    let close = |got: f64, want: f64| (got / want - 1.0).abs() < 0.03;
    let radiosity = derived("radiosity", "patch_size");
    assert!(
        close(radiosity, (area / 4096.0).sqrt()),
        "radiosity patch_size {radiosity}"
    );
    let sh = derived("sh_lightmap", "patch_size");
    assert!(close(sh, (area / 2048.0).sqrt()), "sh_lightmap patch_size {sh}");
    let vls = derived("vls", "max_segment_area");
    assert!(close(vls, area / 8192.0), "vls max_segment_area {vls}");
    let bsp = derived("bsp_lights", "max_segment_area");
    assert!(close(bsp, area / 8192.0), "bsp_lights max_segment_area {bsp}");
}

#[test]
fn derived_sizes_keep_two_significant_digits_and_sizes_read_in_mb_or_gb() {
    use penumbra::lighting::plan::{bytes, round2};
    assert_eq!(round2(0.012345), 0.012);
    assert_eq!(round2(1234.0), 1200.0);
    assert_eq!(round2(0.1), 0.1);
    assert_eq!(bytes(512 * 1024 * 1024), "512.0 MB");
    assert_eq!(bytes(3 * 1024 * 1024 * 1024), "3.0 GB");
}

mod prt_vertex_spacing {
    use glam::Vec3;
    use penumbra::lighting::prt::sampling::{undersampled, Object};

    /// A square of side `side` at height 0 cut into `n` × `n` quads.
    fn ground(side: f32, n: u32) -> Object {
        let mut triangles = Vec::new();
        let step = side / n as f32;
        for j in 0..n {
            for i in 0..n {
                let p = |a: u32, b: u32| Vec3::new(a as f32 * step, 0.0, b as f32 * step);
                triangles.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                triangles.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        Object {
            name: "ground".into(),
            triangles,
        }
    }

    /// An object `side` across (one triangle spanning a cube's diagonal).
    fn small(side: f32) -> Object {
        Object {
            name: "box".into(),
            triangles: vec![[Vec3::ZERO, Vec3::new(side, 0.0, 0.0), Vec3::splat(side)]],
        }
    }

    /// A 4 m ground in two triangles under a 0.5 m object: its vertices are 4 m apart.
    #[test]
    fn a_ground_in_two_triangles_under_a_small_object_is_undersampled() {
        let lines = undersampled(&[ground(4.0, 1), small(0.5)]);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(
            lines[0].contains("\"ground\"") && lines[0].contains("4.000 m apart"),
            "{lines:?}"
        );
        assert!(lines[0].contains("to 0.250 m"), "{lines:?}");
    }

    /// 32 × 32 quads of 0.125 m hold 4 vertices across the object's shadow; 8 × 8 of 0.5 m one.
    #[test]
    fn a_ground_finer_than_half_the_object_is_not() {
        assert!(undersampled(&[ground(4.0, 32), small(0.5)]).is_empty());
        assert_eq!(undersampled(&[ground(4.0, 8), small(0.5)]).len(), 1);
    }
}

/// A sphere light, which the light-map bakers refuse when they bake, does not stop the others'
/// defaults from being derived from the scene.
#[test]
fn a_sphere_light_leaves_the_derivations_to_run() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(dir.join("lpv_two_rooms.toml")).unwrap()
        + "\n[[lights]]\ntype = \"sphere\"\ncenter = [2.0, 1.5, 0.0]\nradius = 0.1\nradiance = 5\n";
    let scene = Scene::from_str(&text, "lpv_two_rooms.toml", &dir).unwrap_or_else(|e| panic!("{e}"));
    let config = registry::configuration(&scene, Some("lpv")).unwrap();
    let (planned, _) = registry::plan(&config, &scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        planned.parts[0].decl.param("iterations").and_then(|v| v.as_integer()),
        Some(15)
    );
}

/// On the 1,024-light stage the BSP light matrix (a row per segment vertex, 12 bytes per light
/// in f32) bounds the segments before the budget does: the derived area leaves room for four
/// rows per segment in the 2²⁷ bytes a storage buffer is sure to hold (the stage's set-up then
/// made 6,753 vertices, 83 MB, on lavapipe).
#[test]
fn bsp_lights_segments_fit_the_light_matrix() {
    let scene = with_methods("many_stress.toml", r#"["bsp_lights"]"#, None);
    let config = registry::configuration(&scene, Some("bsp_lights")).unwrap();
    let (planned, notes) = registry::plan(&config, &scene).unwrap();
    println!("{notes:?}");
    let area = planned.parts[0]
        .decl
        .param("max_segment_area")
        .and_then(|v| v.as_float())
        .unwrap();
    let rows = (1u64 << 27) as f64 / (1024.0 * 12.0);
    let stage = 351.46;
    assert!(4.0 * stage / area <= rows, "max_segment_area {area}: {rows} rows");
    assert!(notes.iter().any(|n| n.contains("matrix of 1024 lights")), "{notes:?}");
}

/// A scene whose triangles' corners alone fill the light matrix (8,192 triangles under 1,024
/// lights: 24,576 rows where the matrix holds 10,922) is refused in one line before anything is
/// built, naming what fills it, instead of deriving a size from a negative row count.
#[test]
fn bsp_lights_refuses_a_scene_whose_corners_fill_the_light_matrix() {
    let text = "methods = [\"bsp_lights\"]\n[camera]\nposition = [0, 5, 5]\ntarget = [0, 0, 0]\n\
                [[objects]]\nmesh = \"plane\"\nsize = 20\nsubdivisions = 64\n\
                [[light_arrays]]\ntype = \"point\"\ngrid = [32, 1, 32]\nmin = [-9, 2, -9]\nmax = [9, 2, 9]\nintensity = 1\n";
    let scene = Scene::from_str(text, "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let config = registry::configuration(&scene, Some("bsp_lights")).unwrap();
    let start = Instant::now();
    let message = match registry::plan(&config, &scene) {
        Err(e) => e.to_string(),
        Ok((c, notes)) => panic!("not refused: {:?} {notes:?}", c.parts[0].decl),
    };
    println!("{message}");
    assert!(start.elapsed() < Duration::from_secs(1));
    assert!(!message.contains('\n') && !message.contains(" -"), "{message}");
    for needed in [
        "8192 triangles",
        "24576 corners",
        "1024 lights",
        "10922 vertex rows",
        "storage = \"f16\"",
    ] {
        assert!(message.contains(needed), "`{needed}` missing from: {message}");
    }
}

/// A scene too large for the raster PRT baker (a plane of 131,072 triangles: each vertex would
/// draw them all, over twice the 17,408 tree steps of its 1,024 rays) gets the compute rays,
/// said in one line; a declaration that names a raster parameter, the faithful mode and a small
/// scene keep the document's raster baker. The chart's sweep holds the rays at 256, 1,024 and
/// 4,096 samples, and still the raster points.
#[test]
fn a_large_scene_gets_the_prt_ray_baker() {
    let text = |methods: &str, subdivisions: u32| {
        format!(
            "methods = {methods}\n[camera]\nposition = [0, 5, 5]\ntarget = [0, 0, 0]\n\
             [[objects]]\nmesh = \"plane\"\nsize = 20\nsubdivisions = {subdivisions}\n\
             [[objects]]\nmesh = \"box\"\ntranslate = [0, 1, 0]\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n"
        )
    };
    let planned = |methods: &str, subdivisions: u32| {
        let scene =
            Scene::from_str(&text(methods, subdivisions), "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
        let config = registry::configuration(&scene, Some("prt")).unwrap();
        registry::plan(&config, &scene).unwrap_or_else(|e| panic!("{e}"))
    };
    let (config, notes) = planned(r#"["prt"]"#, 256);
    println!("{notes:?}");
    assert_eq!(
        config.parts[0].decl.param("baker").and_then(|v| v.as_str()),
        Some("rays")
    );
    assert!(
        notes
            .iter()
            .any(|n| n.contains("baker = \"rays\"") && n.contains("131084 triangles")),
        "{notes:?}"
    );
    let labels: Vec<String> = registry::sweep(&config).unwrap().into_iter().map(|(l, _)| l).collect();
    println!("{labels:?}");
    for want in [
        "prt rays 256",
        "prt rays 1024",
        "prt rays 4096",
        "prt corrected stereographic 32²",
        "prt faithful orthographic 32²",
    ] {
        assert!(
            labels.iter().any(|l| l.starts_with(want)),
            "`{want}` missing from the sweep {labels:?}"
        );
    }
    for (methods, subdivisions) in [
        (r#"[{ name = "prt", mapping = "equal_area" }]"#, 256),
        (r#"[{ name = "prt", mode = "faithful" }]"#, 256),
        (r#"["prt"]"#, 64),
    ] {
        let (config, notes) = planned(methods, subdivisions);
        assert!(
            config.parts[0].decl.param("baker").is_none(),
            "{methods} at {subdivisions}: {notes:?}"
        );
    }
}
