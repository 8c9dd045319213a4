//! The `penumbra` binary as users meet it: deterministic captures, profiling output, device
//! info, and one clear error line (never a panic) for every kind of bad input.

use crate::support as common;

use common::penumbra;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn capture_is_deterministic_and_writes_both_files() {
    let (png1, exr1, png2, exr2) = (
        common::temp_path("a.png"),
        common::temp_path("a.exr"),
        common::temp_path("b.png"),
        common::temp_path("b.exr"),
    );
    for (png, exr) in [(&png1, &exr1), (&png2, &exr2)] {
        let o = penumbra(&[
            "capture",
            "--size",
            "64x48",
            "-o",
            path_str(png),
            "--exr",
            path_str(exr),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(
        std::fs::read(&png1).unwrap(),
        std::fs::read(&png2).unwrap(),
        "PNG differs between runs"
    );
    assert_eq!(
        std::fs::read(&exr1).unwrap(),
        std::fs::read(&exr2).unwrap(),
        "EXR differs between runs"
    );
    let hdr = penumbra::util::image_io::HdrImage::read_exr(&exr1).unwrap();
    assert_eq!((hdr.width, hdr.height), (64, 48));
    // The EXR is unclamped linear radiance: the glossy sphere's highlight exceeds 1.
    let max = hdr
        .pixels
        .iter()
        .map(|p| p[0].max(p[1]).max(p[2]))
        .fold(0.0f32, f32::max);
    assert!(max > 1.0, "brightest radiance {max}");
    // The PNG is its tone-mapped image.
    let png = image::open(&png1).unwrap().to_rgba8();
    assert_eq!(png, hdr.to_display(1.0));
}

#[test]
fn profile_reports_every_pass_as_json() {
    let json = common::temp_path("profile.json");
    let o = penumbra(&["profile", "--size", "64x48", "--frames", "5", "--json", path_str(&json)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("forward") && table.contains("median ms"), "{table}");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(
        v["device"].as_str().unwrap().to_lowercase().contains("llvmpipe")
            || std::env::var("PENUMBRA_TEST_DEVICE").is_ok()
    );
    assert!(!v["driver"].as_str().unwrap().is_empty());
    assert_eq!(v["frames"], 5);
    let passes: Vec<&str> = v["passes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    // The renderer's background pass (targets cleared, the sky), then the method's.
    assert_eq!(passes, vec!["frame", "background", "forward"]);
    assert_eq!(v["configuration"], "forward");
    assert_eq!(v["methods"], serde_json::json!(["forward"]));
    assert_eq!(v["bakes"], serde_json::json!([]), "forward bakes nothing");
    for p in v["passes"].as_array().unwrap() {
        let (lo, med, hi) = (
            p["min_ms"].as_f64().unwrap(),
            p["median_ms"].as_f64().unwrap(),
            p["max_ms"].as_f64().unwrap(),
        );
        assert!(0.0 < lo && lo <= med && med <= hi, "{p}");
    }
}

#[test]
fn info_names_the_device_and_its_limits() {
    let o = penumbra(&["info"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for key in [
        "device",
        "driver",
        "depth clamp",
        "timestamps",
        "max push constants",
        "validation",
    ] {
        assert!(text.contains(key), "missing {key}: {text}");
    }
}

/// Writes `content` as a scene file and returns the error line of `capture` on it.
fn scene_error(name: &str, content: &str) -> (String, PathBuf) {
    let path = common::temp_path(name);
    std::fs::write(&path, content).unwrap();
    let out = common::temp_path(&format!("{name}.png"));
    let o = penumbra(&["capture", path_str(&path), "--size", "16x16", "-o", path_str(&out)]);
    assert!(!o.status.success(), "{name}: bad scene was accepted");
    assert!(!out.exists(), "{name}: an output was written for a bad scene");
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{name}: panic: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{name}: expected one error line, got:\n{err}");
    (lines[0].to_string(), path)
}

const CAMERA: &str = "[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n";

#[test]
fn malformed_scenes_get_one_clear_error_line() {
    let cases: Vec<(&str, String, &str, &str)> = vec![
        (
            "syntax.toml",
            format!("{CAMERA}[[lights]\ntype = \"point\"\n"),
            ":4:",
            "",
        ),
        (
            "unknown_key.toml",
            format!("{CAMERA}colour = 3\n"),
            ":4: camera.colour",
            "unknown field",
        ),
        (
            "negative.toml",
            format!("{CAMERA}[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [1, -2, 1]\n"),
            ":7: lights[0].intensity",
            "non-negative",
        ),
        (
            "material.toml",
            format!("{CAMERA}[[objects]]\nmesh = \"box\"\nmaterial = \"marble\"\n"),
            ":6: objects[0].material",
            "marble",
        ),
        (
            "method.toml",
            format!("methods = [\"raytraced_gi\"]\n{CAMERA}"),
            ":1: methods[0]",
            "forward",
        ),
        (
            "obj_missing.toml",
            format!("{CAMERA}[[objects]]\nmesh = \"obj\"\npath = \"nowhere.obj\"\n"),
            ":6: objects[0].path",
            "nowhere.obj",
        ),
        (
            "fov.toml",
            "[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\nfov_y_deg = 190\n".to_string(),
            ":4: camera.fov_y_deg",
            "180",
        ),
    ];
    for (name, content, location, detail) in cases {
        let (line, path) = scene_error(name, &content);
        assert!(
            line.starts_with(&format!("error: {}", path.display())),
            "{name}: {line}"
        );
        assert!(line.contains(location), "{name}: expected `{location}` in: {line}");
        assert!(line.contains(detail), "{name}: expected `{detail}` in: {line}");
    }
}

#[test]
fn nan_in_a_mesh_names_the_obj_and_vertex() {
    let obj = common::temp_path("nan.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n").unwrap();
    let (line, _) = scene_error(
        "nan_mesh.toml",
        &format!("{CAMERA}[[objects]]\nmesh = \"obj\"\npath = \"{}\"\n", path_str(&obj)),
    );
    assert!(
        line.contains("nan.obj") && line.to_lowercase().contains("vertex 3"),
        "{line}"
    );
}

#[test]
fn bad_command_line_values_are_reported() {
    let o = penumbra(&["capture", "no/such/scene.toml"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).starts_with("error: no/such/scene.toml: file: cannot read"),
        "{}",
        stderr(&o)
    );
    let o = penumbra(&["capture", "--size", "64by48"]);
    assert!(
        !o.status.success() && stderr(&o).contains("WIDTHxHEIGHT"),
        "{}",
        stderr(&o)
    );
    // A method the renderer knows but a scene that declares its methods does not enable, and
    // one nobody knows. (The default scene declares none, so it takes any method by name.)
    let declared = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell_radiosity.toml");
    let o = penumbra(&["capture", declared, "--method", "shadow_volumes", "--size", "8x8"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("method `shadow_volumes` is not enabled") && e.contains("radiosity, forward"),
        "{e}"
    );
    let o = penumbra(&["capture", "--method", "bogus", "--size", "8x8"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.starts_with("error: --method bogus: unknown method; known methods: forward, shadow_volumes"),
        "{e}"
    );
    // Numbers that mean nothing are refused before anything runs.
    for (args, says) in [
        (vec!["capture", "--frames", "0"], "--frames"),
        (vec!["profile", "--frames", "0"], "--frames"),
        (vec!["chart", "scenes/default.toml", "--frames", "0"], "--frames"),
        (
            vec!["capture", "scenes/default.toml", "--max-error", "NaN"],
            "--max-error",
        ),
        (vec!["capture", "scenes/default.toml", "--max-error=-1"], "--max-error"),
        (vec!["capture", "--exposure", "inf"], "--exposure"),
    ] {
        let o = penumbra(&args);
        let e = stderr(&o);
        assert!(
            !o.status.success() && e.starts_with("error: invalid value") && e.contains(says),
            "{args:?}: {e}"
        );
    }
}

/// Bad data in the files a scene names: one line with the scene file, the field (and its line
/// where the scene parser finds it), and what is wrong, never a decoder's Debug dump.
#[test]
fn bad_images_and_parameters_name_the_scene_file_and_field() {
    let dir = common::temp_path("bad-data");
    std::fs::create_dir_all(&dir).unwrap();
    let good_png =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures/bricks_albedo.png")).unwrap();
    // Header CRC broken; image data scrambled; the file cut short; a 99999² HDR header.
    let mut crc = good_png.clone();
    crc[29] ^= 0xff;
    let mut scrambled = good_png.clone();
    for b in &mut scrambled[200..260] {
        *b ^= 0x5a;
    }
    std::fs::write(dir.join("crc.png"), crc).unwrap();
    std::fs::write(dir.join("scrambled.png"), scrambled).unwrap();
    std::fs::write(dir.join("short.png"), &good_png[..100]).unwrap();
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 99999 +X 99999\n".to_vec();
    hdr.extend([7u8; 64]);
    std::fs::write(dir.join("huge.hdr"), hdr).unwrap();
    let texture = |file: &str| {
        format!("{CAMERA}[[materials]]\nname = \"m\"\nalbedo_map = \"{}\"\n[[objects]]\nmesh = \"sphere\"\nmaterial = \"m\"\n", dir.join(file).display())
    };
    let field = |extra: &str| {
        format!("methods = [{{ name = \"heightfield_pyramid\"{extra} }}]\n{CAMERA}[[materials]]\nname = \"g\"\n[[objects]]\nmesh = \"heightfield\"\nmaterial = \"g\"\nresolution = 16\n")
    };
    let heights = |file: &str| format!("{}path = \"{}\"\n", field(""), dir.join(file).display());
    let cases: Vec<(&str, String, &str, &str)> = vec![
        (
            "tex_crc.toml",
            texture("crc.png"),
            ":6: materials[0].albedo_map",
            "CRC error",
        ),
        (
            "tex_scrambled.toml",
            texture("scrambled.png"),
            ": materials[0] (\"m\").albedo_map",
            "corrupt or truncated PNG data",
        ),
        (
            "tex_short.toml",
            texture("short.png"),
            ": materials[0] (\"m\").albedo_map",
            "truncated",
        ),
        ("hf_crc.toml", heights("crc.png"), ":11: objects[0].path", "CRC error"),
        (
            "hf_scrambled.toml",
            heights("scrambled.png"),
            ":11: objects[0].path",
            "corrupt or truncated PNG data",
        ),
        (
            "env_huge.toml",
            format!(
                "{CAMERA}[environment]\ntype = \"image\"\npath = \"{}\"\n",
                dir.join("huge.hdr").display()
            ),
            ":6: environment.path",
            "99999×99999",
        ),
        (
            "bands.toml",
            format!("{}generator = \"sine\"\n", field(", bands = 99")),
            ":1: methods[0].bands",
            "from 1 to 6, got 99",
        ),
        (
            "far_camera.toml",
            "[camera]\nposition = [1e30, 1, 3]\ntarget = [0, 0, 0]\n".to_string(),
            ":2: camera.position",
            "too far from the origin",
        ),
    ];
    for (name, content, location, detail) in cases {
        let (line, path) = scene_error(name, &content);
        assert!(
            line.starts_with(&format!("error: {}", path.display())),
            "{name}: {line}"
        );
        assert!(line.contains(location), "{name}: expected `{location}` in: {line}");
        assert!(line.contains(detail), "{name}: expected `{detail}` in: {line}");
        assert!(
            !line.contains('{') && !line.contains("Memory limit"),
            "{name}: a decoder's internals: {line}"
        );
    }
}

/// `compare` reads linear radiance: an 8-bit PNG is refused, not read as radiance.
#[test]
fn compare_refuses_a_png_as_radiance() {
    let (png, exr) = (common::temp_path("cmp.png"), common::temp_path("cmp.exr"));
    common::ok(&penumbra(&[
        "capture",
        "--size",
        "16x16",
        "-o",
        path_str(&png),
        "--exr",
        path_str(&exr),
    ]));
    for (test, reference) in [(&png, &exr), (&exr, &png)] {
        let o = penumbra(&["compare", path_str(test), path_str(reference)]);
        let e = stderr(&o);
        assert!(
            !o.status.success() && e.starts_with(&format!("error: {}: is a PNG image, not OpenEXR", png.display())),
            "{e}"
        );
    }
    common::ok(&penumbra(&["compare", path_str(&exr), path_str(&exr)]));
}

/// `penumbra info | true`, `capture … | true` and `reference … | true` used to exit 101 with
/// "failed printing to stdout: Broken pipe". A closed standard output (or standard error) now
/// loses only the text: the command does its work and exits 0.
#[test]
fn a_closed_pipe_loses_the_text_not_the_work() {
    use std::process::{Command, Stdio};
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let (png, exr) = (common::temp_path("pipe.png"), common::temp_path("pipe.exr"));
    let furnace = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/furnace.toml");
    let runs: [Vec<&str>; 3] = [
        vec!["info"],
        vec!["capture", "--size", "16x16", "-o", path_str(&png)],
        vec![
            "reference",
            path_str(&furnace),
            "--size",
            "4x4",
            "--spp",
            "4",
            "-o",
            path_str(&exr),
        ],
    ];
    for args in &runs {
        for close_stderr in [false, true] {
            let _ = std::fs::remove_file(&png);
            let _ = std::fs::remove_file(&exr);
            let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
                .args(args)
                .args(["--device", &device])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            // Closed before the command gets to print (starting Vulkan alone takes longer).
            drop(child.stdout.take());
            if close_stderr {
                drop(child.stderr.take());
            }
            let o = child.wait_with_output().unwrap();
            let e = stderr(&o);
            assert!(
                o.status.success() && !e.contains("panicked"),
                "{args:?} (stderr closed: {close_stderr}): {:?}\n{e}",
                o.status
            );
            match args[0] {
                "capture" => assert!(png.exists(), "{args:?} wrote no PNG"),
                "reference" => assert!(exr.exists(), "{args:?} wrote no EXR"),
                _ => {}
            }
        }
    }
}

/// Outputs are written to a hidden partial file and renamed into place, so a capture or chart
/// killed halfway through writing never leaves a truncated file under the real name, and the
/// chart's cache stays usable. The kill is injected (PENUMBRA_FAULT_ABORT_WRITE=N aborts the
/// process halfway through its N-th file).
#[test]
fn an_interrupted_write_never_leaves_a_truncated_output() {
    let dir = common::temp_path("interrupted");
    std::fs::create_dir_all(&dir).unwrap();
    let (png, exr) = (dir.join("shot.png"), dir.join("shot.exr"));
    let capture = |abort: Option<&str>| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
        cmd.args([
            "capture",
            "--size",
            "32x24",
            "--device",
            &std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()),
        ]);
        cmd.args(["-o", path_str(&png), "--exr", path_str(&exr)]);
        if let Some(n) = abort {
            cmd.env("PENUMBRA_FAULT_ABORT_WRITE", n);
        }
        cmd.output().unwrap()
    };
    assert!(capture(None).status.success());
    let (old_png, old_exr) = (std::fs::read(&png).unwrap(), std::fs::read(&exr).unwrap());
    // Killed while writing the EXR (written first), then while writing the PNG: each output is
    // the previous complete file or the new complete file, never a part.
    for n in ["1", "2"] {
        let o = capture(Some(n));
        assert!(!o.status.success(), "the injected abort did not happen");
        assert!(
            std::fs::read(&exr).unwrap() == old_exr,
            "abort in write {n}: shot.exr changed"
        );
        if n == "1" {
            assert!(
                std::fs::read(&png).unwrap() == old_png,
                "abort in write {n}: shot.png changed"
            );
        }
        assert!(
            image::open(&png).is_ok(),
            "abort in write {n}: shot.png does not decode"
        );
    }
    // A chart killed while caching its reference leaves no cache entry; the next run renders it.
    let cache = dir.join("cache");
    let chart_png = dir.join("chart.png");
    let chart = |abort: Option<&str>| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
        cmd.args([
            "chart",
            "scenes/default.toml",
            "--size",
            "16x16",
            "--reference-spp",
            "4",
            "--frames",
            "1",
            "--cache-dir",
            path_str(&cache),
            "-o",
            path_str(&chart_png),
        ]);
        cmd.args([
            "--device",
            &std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()),
        ]);
        if let Some(n) = abort {
            cmd.env("PENUMBRA_FAULT_ABORT_WRITE", n);
        }
        cmd.output().unwrap()
    };
    assert!(!chart(Some("1")).status.success());
    let visible: Vec<String> = std::fs::read_dir(&cache)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| !n.starts_with('.'))
        .collect();
    assert!(visible.is_empty(), "a killed chart left {visible:?} in its cache");
    assert!(!chart_png.exists());
    let o = chart(None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(image::open(&chart_png).is_ok());
}

/// A report printed to a standard output closed from the start (`>&-`) is an error, not a
/// silent exit 0; `>/dev/null` is the user's choice and succeeds.
#[test]
fn a_closed_standard_output_is_reported() {
    let scene = common::temp_path("closed_stdout.toml");
    std::fs::write(&scene, format!("methods = [\"forward\"]\n{CAMERA}")).unwrap();
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let run = |redirect: &str| {
        std::process::Command::new("sh")
            .args([
                "-c",
                &format!("exec \"$0\" \"$@\" {redirect}"),
                env!("CARGO_BIN_EXE_penumbra"),
                "bake",
                path_str(&scene),
                "--device",
                &device,
            ])
            .output()
            .expect("run penumbra")
    };
    let closed = run(">&-");
    assert!(!closed.status.success(), "exit 0 with standard output closed");
    assert!(
        stderr(&closed).contains("error: standard output is closed"),
        "{}",
        stderr(&closed)
    );
    let null = run(">/dev/null");
    assert!(null.status.success(), "{}", stderr(&null));
}

/// The progress line (rate, elapsed, remaining, redrawn with `\r`) belongs on a terminal: with
/// stderr piped, a reference render that runs past the line's one-second start leaves only its
/// summary. The samples double until the render takes long enough for the line to have shown.
#[test]
fn the_progress_line_is_silent_when_stderr_is_not_a_terminal() {
    let exr = common::temp_path("progress-silent.exr");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml");
    let mut spp = 64u32;
    loop {
        let t = std::time::Instant::now();
        let o = penumbra(&[
            "reference",
            scene,
            "--size",
            "32x32",
            "--spp",
            &spp.to_string(),
            "-o",
            path_str(&exr),
        ]);
        let secs = t.elapsed().as_secs_f64();
        let err = stderr(&o);
        assert!(o.status.success(), "{err}");
        // Past 10 s a piped run logs a plain line every few seconds (util::progress); below
        // that, nothing but the summary.
        assert!(
            !err.contains('\r') && !err.contains("\x1b[K") && (secs >= 10.0 || !err.contains("% (")),
            "a progress line on a pipe after {secs:.1} s at {spp} spp:\n{err:?}"
        );
        // The line starts after one second: a shorter render proves nothing.
        if secs > 2.0 {
            break;
        }
        assert!(spp < 1 << 16, "{spp} spp took only {secs:.1} s");
        spp *= 2;
    }
}

/// `profile --json` lists the bakes the methods ran when they were created, with their time and
/// size: radiosity's light-map on the Cornell box.
#[test]
fn profile_json_lists_a_bake() {
    let json = common::temp_path("profile-bake.json");
    let cache = common::temp_path("profile-bake-cache");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell_radiosity.toml");
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
    cmd.args([
        "profile",
        scene,
        "--method",
        "radiosity",
        "--size",
        "32x32",
        "--frames",
        "2",
    ])
    .args(["--json", path_str(&json)])
    .args([
        "--device",
        &std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()),
    ])
    .env("PENUMBRA_VALIDATION", "1")
    .env("PENUMBRA_CACHE", &cache);
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let bakes = v["bakes"].as_array().unwrap();
    assert!(!bakes.is_empty(), "no bake listed: {v}");
    for b in bakes {
        assert!(!b["name"].as_str().unwrap().is_empty(), "{b}");
        assert!(
            b["ms"].as_f64().unwrap() > 0.0 && b["bytes"].as_u64().unwrap() > 0,
            "{b}"
        );
        assert_eq!(b["cached"], false, "a fresh cache: {b}");
    }
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("bakes (at creation, not frame time)"), "{table}");
}

/// `--memory-budget-mb` and `--camera` reach the scene: a budget below what the bake needs is
/// refused up front naming the flag, a raised one lets the same plan through, and a camera the
/// scene does not carry is one error line.
#[test]
fn the_command_line_sets_the_memory_budget_and_the_camera() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bsp_rooms.toml");
    let run = |extra: &[&str]| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
        cmd.args(["bake", path_str(&scene), "--method", "radiosity", "--size", "8x8"]);
        cmd.args([
            "--device",
            &std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()),
        ]);
        cmd.args(extra);
        let o = cmd.output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let started = std::time::Instant::now();
    let (ok, err) = run(&["--memory-budget-mb", "1"]);
    assert!(!ok, "a 1 MB budget refuses the radiosity bake: {err}");
    assert!(
        err.contains("budget of 1.0 MB (the scene's memory_budget_mb or --memory-budget-mb)"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(started.elapsed().as_secs_f64() < 20.0, "refused before baking");
    let (ok, err) = run(&["--memory-budget-mb", "0"]);
    assert!(!ok && err.contains("at least 1"), "{err}");
    let (ok, err) = run(&["--camera", "3"]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("bsp_rooms.toml: cameras: --camera 3 asked for, no asset of the scene carries a camera"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

/// `penumbra bake` whose result cannot be stored (the cache directory is a file) says so in its
/// table and fails, rather than reporting "built" and exiting 0.
#[test]
fn a_bake_that_cannot_be_stored_fails() {
    let blocker = common::temp_path("cache-is-a-file");
    std::fs::write(&blocker, b"not a directory").unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/many_box.toml");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args([
            "bake",
            path_str(&scene),
            "--method",
            "bsp_lights",
            "--size",
            "8x8",
            "--device",
        ])
        .arg(std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into()))
        .env("PENUMBRA_CACHE", &blocker)
        .output()
        .unwrap();
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(!o.status.success(), "exit 0 although nothing was stored:\n{out}\n{err}");
    assert!(out.contains("built, NOT stored"), "{out}");
    assert!(err.contains("a bake could not be stored in the cache"), "{err}");
    assert!(
        std::fs::read(&blocker).unwrap() == b"not a directory",
        "the file in the way is kept"
    );
}

/// The three light-map bakes light a surface's front side only: from inside a closed box (whose
/// faces look out) the camera sees every face from behind, and each method says so in one line
/// from `capture`; from outside, none does.
#[test]
fn light_map_bakes_warn_when_the_camera_sees_surfaces_from_behind() {
    let dir = common::temp_path("behind");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = |name: &str, camera: &str| {
        let path = dir.join(name);
        std::fs::write(
            &path,
            format!(
                "methods = [\"radiosity\", \"sh_lightmap\", \"prt\"]\n[camera]\n{camera}\n\
                 [[materials]]\nname = \"m\"\nalbedo = 0.5\n\
                 [[objects]]\nmesh = \"box\"\nsize = 4\nmaterial = \"m\"\n\
                 [[lights]]\ntype = \"directional\"\ndirection = [0.3, -1, 0.2]\nirradiance = [2, 2, 2]\n"
            ),
        )
        .unwrap();
        path
    };
    let inside = scene("inside.toml", "position = [0.3, 0.2, 0.5]\ntarget = [0, 0, -1]");
    let outside = scene("outside.toml", "position = [0, 1, 8]\ntarget = [0, 0, 0]");
    for method in ["radiosity", "sh_lightmap", "prt"] {
        let said = |path: &Path| {
            let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
                .args(["capture", path_str(path), "--method", method, "--size", "16x12"])
                .args(["-o", path_str(&dir.join(format!("{method}.png")))])
                .env("PENUMBRA_CACHE", dir.join("cache"))
                .env("PENUMBRA_VALIDATION", "1")
                .output()
                .unwrap();
            common::ok(&o);
            stderr(&o)
        };
        let warning = format!("{method}: 100% of the camera's view sees surfaces from behind");
        let (from_inside, from_outside) = (said(&inside), said(&outside));
        assert!(
            from_inside.lines().filter(|l| l.contains(&warning)).count() == 1,
            "{method} from inside:\n{from_inside}"
        );
        assert!(
            !from_outside.contains("from behind"),
            "{method} from outside:\n{from_outside}"
        );
    }
}
