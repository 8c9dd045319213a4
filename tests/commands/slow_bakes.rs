//! Bakes that would run for minutes say so, with an estimate, before their long work: `penumbra
//! bake` on a small scene at a setting estimated past a minute warns on stderr (no terminal) in
//! one line; the run is stopped there.

use crate::support as common;

use std::io::BufRead;
use std::time::{Duration, Instant};

/// The line every estimate made before a bake starts carries.
const ESTIMATED: &str = "estimated before it starts";

/// What a run printed up to its estimate, and when the estimate came.
struct Seen {
    lines: Vec<String>,
    seconds: f64,
}

/// `penumbra bake SCENE --method METHOD` (a fresh cache of its own) until it prints the estimate
/// on stderr, exits, or `limit` passes; then stops it.
fn until_estimate(scene: &std::path::Path, method: &str, limit: Duration) -> Seen {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    // The scene's folder names the run (`scene_with`'s `name`): runs beside each other keep
    // their caches apart.
    let name = scene.parent().and_then(|d| d.file_name()).unwrap().to_string_lossy();
    let cache = common::temp_path(&format!("slow-bake-cache-{name}"));
    let start = Instant::now();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["bake", scene.to_str().unwrap(), "--method", method, "--device", &device])
        .env("PENUMBRA_CACHE", &cache)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("run penumbra");
    let stderr = child.stderr.take().unwrap();
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
            if send.send(line).is_err() {
                return;
            }
        }
    });
    let mut seen = Seen {
        lines: Vec::new(),
        seconds: f64::NAN,
    };
    while let Ok(line) = receive.recv_timeout(limit.saturating_sub(start.elapsed())) {
        let found = line.contains(ESTIMATED);
        seen.lines.push(line);
        if found {
            seen.seconds = start.elapsed().as_secs_f64();
            break;
        }
    }
    let _ = child.kill();
    let _ = child.wait();
    let _ = std::fs::remove_dir_all(&cache);
    seen
}

/// `scene` with `from` replaced by `to`, in a temporary folder beside links to the scene
/// folder's asset folders (the scene names its assets relative to itself).
fn scene_with(scene: &str, from: &str, to: &str, name: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(scene).unwrap();
    assert!(text.contains(from), "{scene} no longer declares {from}");
    let dir = common::temp_path(name);
    std::fs::create_dir_all(&dir).unwrap();
    let scenes = std::fs::canonicalize("scenes").unwrap();
    for assets in ["meshes", "textures", "terrain"] {
        let _ = std::os::unix::fs::symlink(scenes.join(assets), dir.join(assets));
    }
    let path = dir.join("scene.toml");
    std::fs::write(&path, text.replace(from, to)).unwrap();
    path
}

/// The seconds the warning's "about …" gives.
fn estimate_seconds(line: &str) -> f64 {
    let about = line.split("about ").nth(1).unwrap_or_default();
    let mut words = about.split_whitespace();
    let n: f64 = words.next().and_then(|n| n.parse().ok()).unwrap_or(f64::NAN);
    match words.next() {
        Some("s") => n,
        Some("min") => n * 60.0,
        Some("h") => n * 3600.0,
        _ => f64::NAN,
    }
}

/// What `penumbra bake` of `base` (a shipped scene) with its method entry `from` set to `to`
/// prints up to its estimate, within a minute.
fn estimate_of(base: &str, from: &str, to: &str, tag: &str, method: &str) -> Seen {
    let scene = scene_with(base, from, to, tag);
    let seen = until_estimate(&scene, method, Duration::from_secs(60));
    let _ = std::fs::remove_file(&scene);
    seen
}

/// Checks the warning: one line naming the bake, an estimate past a minute and past the time the
/// run took to say it, the method and the dominant stage.
fn assert_warned(seen: &Seen, bake: &str, dominant: &str) {
    let line = seen.lines.last().cloned().unwrap_or_default();
    println!("{:.1} s: {line}", seen.seconds);
    assert!(
        line.starts_with(&format!("warning: {bake}")) && line.contains(ESTIMATED),
        "no estimate: {:?}",
        seen.lines
    );
    // The dominant stage: what stands between the method's closing parenthesis and "dominates".
    let said = line.split(" dominates").next().unwrap_or_default();
    let stage = said.rsplit("); ").next().unwrap_or_default();
    assert!(line.contains(" dominates") && stage.contains(dominant), "{line}");
    let estimate = estimate_seconds(&line);
    assert!(
        estimate > 60.0 && estimate > 3.0 * seen.seconds,
        "{estimate} s estimated after {} s",
        seen.seconds
    );
}

/// PRT's CPU ray caster at a million rays a vertex: the teapot's bake is estimated from a few
/// vertices' rays before the first ray of the bake is cast.
#[test]
fn a_million_rays_a_vertex_warn_before_the_bake() {
    let seen = estimate_of(
        "scenes/prt_teapot_box.toml",
        "{ name = \"prt\" },",
        "{ name = \"prt\", baker = \"rays_cpu\", samples = 1048576 },",
        "prt-million",
        "prt",
    );
    assert_warned(&seen, "prt RaysCpu 1048576 rays", "tracing");
}

/// Radiosity at 1 cm patches in the Cornell box (about 300,000 patches): estimated from the same
/// bake at a few hundred patches before the patches are made.
#[test]
fn fine_radiosity_patches_warn_before_the_bake() {
    let seen = estimate_of(
        "scenes/cornell_radiosity.toml",
        "{ name = \"radiosity\", patch_size = 0.1 }",
        "{ name = \"radiosity\", patch_size = 0.01, block = 1 }",
        "radiosity-fine",
        "radiosity",
    );
    assert_warned(&seen, "radiosity light-map patch=0.01", "shooting");
}

/// The SH light-map's CPU visibility at 2 cm patches on the courtyard (about 280,000 patches ×
/// 20,000 samples): estimated from a few patches' rays before the buried parts and the rays,
/// beside the bounces that follow (which dominate: about 91,000 shots to 280,000 patches).
#[test]
fn fine_sh_light_map_patches_warn_before_the_bake() {
    let seen = estimate_of(
        "scenes/sh_courtyard.toml",
        "{ name = \"sh_lightmap\", bands = 4, patch_size = 0.25, sun_speed = 20 }",
        "{ name = \"sh_lightmap\", bands = 4, patch_size = 0.02, samples = 20000, baker = \"cpu\" }",
        "sh-fine",
        "sh_lightmap",
    );
    assert_warned(&seen, "sh_lightmap bands=4 patch=0.02", "the bounces");
    let line = seen.lines.last().unwrap();
    assert!(line.contains("20164 samples timed"), "the rays not estimated: {line}");
}

/// The SH light-map's bounces at 2 cm patches on the courtyard with the GPU baker: its rays
/// are not estimated, but the bounces that follow them (shot on the CPU, growing as patches ×
/// shots) are, from the same bounces at coarse patches, before the buried parts and the rays.
#[test]
fn fine_sh_light_map_bounces_warn_before_the_bake() {
    let seen = estimate_of(
        "scenes/sh_courtyard.toml",
        "{ name = \"sh_lightmap\", bands = 4, patch_size = 0.25, sun_speed = 20 }",
        "{ name = \"sh_lightmap\", bands = 4, patch_size = 0.02, baker = \"gpu\" }",
        "sh-fine-bounces",
        "sh_lightmap",
    );
    assert_warned(&seen, "sh_lightmap bands=4 patch=0.02", "bounces");
}
