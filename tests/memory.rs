//! Memory stays flat over long runs. Each method renders a few hundred small frames (under
//! validation) and the process's anonymous resident memory must stop growing after warm-up.
//!
//! The counter is `RssAnon` from /proc/self/status: the resident anonymous pages (heap, driver
//! allocations, JIT code of the CPU driver), which is where a leak lands. `VmRSS` also counts
//! file-backed pages (shared libraries paged in the first time a code path runs), noise that a
//! leak check does not need. This file holds one test, so no other test of the binary allocates
//! while it measures.
//!
//! `soak_every_shipped_scene_and_method` (ignored; `tools/soak.sh` runs it) renders every shipped
//! scene with every method it enables for many frames and prints RSS per 100 frames.
//!
//! Its own test binary: it measures the process's resident memory, which other tests in the
//! same process would disturb.

use std::path::Path;

use penumbra::renderer::Renderer;
use penumbra::scene::Scene;

mod support;
use support as common;

/// Resident anonymous memory of this process, in MiB (Linux).
fn rss_anon_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("read /proc/self/status");
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("RssAnon:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .expect("RssAnon in /proc/self/status");
    kb / 1024.0
}

fn shipped(name: &str) -> Scene {
    penumbra::commands::capture::load_scene(
        Some(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)),
        &Default::default(),
    )
    .unwrap()
}

/// theatre_50.toml with segments of up to 0.5 m² for VLS and bsp_lights (the per-frame work
/// at a set-up that bakes in seconds).
fn theatre() -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut text = std::fs::read_to_string(dir.join("theatre_50.toml")).unwrap();
    for name in ["vls", "bsp_lights"] {
        let decl = format!("{{ name = \"{name}\" }}");
        assert!(text.contains(&decl), "theatre_50.toml declares {decl}");
        text = text.replacen(&decl, &format!("{{ name = \"{name}\", max_segment_area = 0.5 }}"), 1);
    }
    Scene::from_str(&text, "<memory test: theatre_50>", &dir).unwrap()
}

/// lpv_cornell.toml with a 16³ volume, 8 propagations and a 128² RSM.
fn small_lpv() -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(dir.join("lpv_cornell.toml")).unwrap();
    let decl = r#"{ name = "lpv" }"#;
    assert!(text.contains(decl), "lpv_cornell.toml declares {decl}");
    let text = text.replacen(decl, r#"{ name = "lpv", grid = 16, iterations = 8, rsm = 128 }"#, 1);
    Scene::from_str(&text, "<memory test: lpv_cornell, 16³>", &dir).unwrap()
}

/// A 16² sine field that moves every frame (so the generator block is uploaded and bound every
/// frame), one sphere light, a constant sky: the per-frame work of the height-field methods at a
/// size that renders in milliseconds.
/// A floor and a bobbing ball under the image sky, spinning: per-vertex PRT with SH keys blended
/// and the light rotated every frame.
fn small_prt() -> Scene {
    let toml = r#"methods = [{ name = "prt", env_spin = 30, key_rate = 5, loop_s = 1 }]
[camera]
position = [0.0, 2.0, 3.0]
target = [0.0, 0.3, 0.0]
[environment]
type = "image"
path = "terrain/sky.hdr"
[[objects]]
name = "floor"
mesh = "plane"
size = 3
subdivisions = 8
[[objects]]
name = "ball"
mesh = "sphere"
radius = 0.3
segments = 12
rings = 6
translate = [0, 0.5, 0]
bob_amplitude = [0, 0.2, 0]
bob_period_s = 1
"#;
    Scene::from_str(
        toml,
        "<memory test>",
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"),
    )
    .unwrap()
}

fn small_field(method: &str) -> Scene {
    let toml = format!(
        r#"methods = [{{ name = "{method}" }}]
[camera]
position = [0.0, 6.0, 7.0]
target = [0.0, 0.0, 0.4]
[[materials]]
name = "ground"
albedo = 0.7
[[objects]]
mesh = "heightfield"
material = "ground"
size = 8
resolution = 16
generator = "sine"
wavelength = 2.0
height = 0.4
speed = 0.1
[[lights]]
type = "sphere"
center = [-4.5, 1.5, 0.0]
radius = 0.3
radiance = 60
[environment]
type = "constant"
radiance = [0.3, 0.35, 0.45]
"#
    );
    Scene::from_str(&toml, "<memory test>", Path::new("/")).unwrap()
}

/// Renders `warmup` frames, then `frames` more, reading the counter every `every` frames; returns
/// (frame, MiB) samples, the first taken after warm-up. Stops early once memory has grown by more
/// than `limit_mib` (a leak of megabytes per frame would otherwise exhaust the machine).
fn run(
    scene: Scene,
    method: &str,
    warmup: usize,
    frames: usize,
    every: usize,
    limit_mib: f64,
) -> (Vec<(usize, f64)>, Vec<u64>) {
    let camera = scene.camera.clone();
    let mut r = Renderer::new(common::test_gpu(), scene, Some(method), (48, 32), 1).unwrap();
    r.profile(&camera, warmup).unwrap();
    let mut samples = vec![(warmup, rss_anon_mib())];
    let mut device = vec![r.gpu.device_memory().0];
    let mut done = 0;
    while done < frames {
        r.profile(&camera, every).unwrap();
        done += every;
        samples.push((warmup + done, rss_anon_mib()));
        device.push(r.gpu.device_memory().0);
        if samples.last().unwrap().1 - samples[0].1 > limit_mib {
            break;
        }
    }
    common::assert_clean(&r.gpu);
    (samples, device)
}

/// Lavapipe recompiled (and leaked) a shader every time a uniform block steering a branch was
/// bound: ≈ 11 MB a frame with `shadow_volumes` on bsp_rooms, ≈ 0.3 MB with the height fields.
/// After 40 frames of warm-up, 240 more frames (160 for the height fields) may add at most 6 MiB
/// (the allocator's and the validation layer's slack; the leak added gigabytes and ≈ 50 MB).
#[test]
fn every_method_renders_hundreds_of_frames_in_flat_memory() {
    const LIMIT_MIB: f64 = 6.0;
    // (method, scene, frames after warm-up): the height fields cost more per frame.
    let cases: Vec<(&str, Scene, usize)> = vec![
        ("forward", shipped("default.toml"), 240),
        ("shadow_volumes", shipped("bsp_rooms.toml"), 240),
        ("heightfield_pyramid", small_field("heightfield_pyramid"), 160),
        ("heightfield_bruteforce", small_field("heightfield_bruteforce"), 160),
        ("radiosity", shipped("cornell_radiosity.toml"), 240),
        // A combination: the light-map base under shadow volumes' direct term.
        ("gi", shipped("room_gi.toml"), 240),
        // The SH light-map relit every frame by a turning sun, and by an image environment
        // projected every frame.
        ("sh_lightmap", shipped("sh_courtyard.toml"), 240),
        ("sh_lightmap", shipped("sh_courtyard_sky.toml"), 240),
        // Per-vertex PRT: SH keys blended and the light turned by SH rotation every frame.
        ("prt", small_prt(), 240),
        // The light propagation volume: RSM, injection, propagation and the lookup every frame,
        // under a spot light in the Cornell box (a 16³ volume: the per-frame work, not its size).
        ("lpv", small_lpv(), 240),
        // The many-light methods on theatre_50, whose lighting desk changes every light's
        // intensity every frame (new uploads, and VLS and bsp_lights re-weight their tables).
        ("clustered", theatre(), 240),
        ("vls", theatre(), 240),
        ("bsp_lights", theatre(), 240),
    ];
    let mut failures = Vec::new();
    for (method, scene, frames) in cases {
        let t = std::time::Instant::now();
        let (samples, device) = run(scene, method, 40, frames, 40, LIMIT_MIB);
        let growth = samples.last().unwrap().1 - samples[0].1;
        let trace: Vec<String> = samples.iter().map(|(f, m)| format!("{f}: {m:.1}")).collect();
        eprintln!(
            "{method}: RssAnon MiB by frame {} ({:.1} s); device memory allocated {:.2} MiB at every sample",
            trace.join(", "),
            t.elapsed().as_secs_f64(),
            device[0] as f64 / 1048576.0
        );
        if growth > LIMIT_MIB {
            failures.push(format!(
                "{method}: +{growth:.1} MiB after warm-up ({})",
                trace.join(", ")
            ));
        }
        // Device memory (live allocations) is allocated up front: a frame adds none.
        if device.iter().any(|&d| d != device[0]) {
            failures.push(format!(
                "{method}: device memory changes after warm-up: {device:?} bytes"
            ));
        }
    }
    assert!(failures.is_empty(), "memory grows:\n{}", failures.join("\n"));
}

/// Every shipped scene with each of its configurations (every method it enables, then every
/// combination it declares), `PENUMBRA_SOAK_FRAMES` frames each (default 10,000) at
/// `PENUMBRA_SOAK_SIZE` (default 64x36), printing RssAnon every 100 frames as CSV lines
/// `scene,method,frame,rss_anon_mib,device_mib` (device memory: live allocations).
/// `PENUMBRA_SOAK_METHODS` (comma-separated configuration names) keeps only those;
/// `PENUMBRA_SOAK_SCENE_DIR` reads the scenes from another folder (e.g. shipped scenes with a
/// parameter changed). Run by tools/soak.sh.
#[test]
#[ignore]
fn soak_every_shipped_scene_and_method() {
    let frames: usize = std::env::var("PENUMBRA_SOAK_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000);
    let size = std::env::var("PENUMBRA_SOAK_SIZE").unwrap_or_else(|_| "64x36".into());
    let (w, h) = size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
        .expect("PENUMBRA_SOAK_SIZE is WxH");
    let only = std::env::var("PENUMBRA_SOAK_SCENES").ok();
    let dir = std::env::var_os("PENUMBRA_SOAK_SCENE_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"));
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    if let Some(only) = &only {
        names.retain(|n| only.split(',').any(|o| n.starts_with(o)));
    }
    println!("scene,method,frame,rss_anon_mib,device_mib");
    for name in names {
        let scene = penumbra::commands::capture::load_scene(Some(&dir.join(&name)), &Default::default()).unwrap();
        // Every configuration: each method alone, then each declared combination.
        let mut methods: Vec<String> = penumbra::lighting::registry::configurations(&scene)
            .unwrap()
            .into_iter()
            .map(|c| c.name)
            .collect();
        if let Ok(keep) = std::env::var("PENUMBRA_SOAK_METHODS") {
            methods.retain(|m| keep.split(',').any(|k| k == m));
        }
        for method in methods {
            let camera = scene.camera.clone();
            let mut r = Renderer::new(common::test_gpu(), scene.clone(), Some(&method), (w, h), 1).unwrap();
            let device_mib = |r: &Renderer| r.gpu.device_memory().0 as f64 / 1048576.0;
            println!("{name},{method},0,{:.1},{:.2}", rss_anon_mib(), device_mib(&r));
            let mut done = 0;
            while done < frames {
                let n = 100.min(frames - done);
                r.profile(&camera, n).unwrap();
                done += n;
                println!("{name},{method},{done},{:.1},{:.2}", rss_anon_mib(), device_mib(&r));
            }
            common::assert_clean(&r.gpu);
        }
    }
}
