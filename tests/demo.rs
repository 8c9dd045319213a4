//! The windowed demo under an X server (tools/test.sh runs the suite under Xvfb): it opens,
//! presents frames with validation on, and its screenshot — the presented swapchain pixels — shows
//! the same image as a headless capture of the same scene.
//!
//! Its own test binary: it opens a window and owns the process's display connection.

use std::process::Command;

mod support;
use support as common;

#[test]
fn demo_presents_the_scene_under_xvfb() {
    assert!(
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(),
        "no display: run the suite through tools/test.sh, which starts Xvfb"
    );
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let shot = common::temp_path("demo.png");
    let capture = common::temp_path("demo-reference.png");
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args([
            "demo",
            "--size",
            "96x64",
            "--frames",
            "4",
            "--validation",
            "--device",
            &device,
            "--screenshot",
        ])
        .arg(&shot)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "demo failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("after 4 frames"));
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["capture", "--size", "96x64", "--device", &device, "-o"])
        .arg(&capture)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let window = image::open(&shot).unwrap().to_rgba8();
    let headless = image::open(&capture).unwrap().to_rgba8();
    assert_eq!(window.dimensions(), (96, 64));
    // GPU tone mapping + sRGB store vs the CPU path: equal up to rounding, except where the fly
    // camera's rebuilt view matrix moves a silhouette by a fraction of a pixel.
    let diffs: Vec<i32> = window
        .pixels()
        .zip(headless.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] as i32 - b[c] as i32).abs()))
        .collect();
    let mean = diffs.iter().sum::<i32>() as f64 / diffs.len() as f64;
    let within = diffs.iter().filter(|&&d| d <= 2).count() as f64 / diffs.len() as f64;
    assert!(
        mean < 1.0 && within > 0.98,
        "window vs headless: mean |diff| {mean:.3}, {:.1}% within 2",
        within * 100.0
    );
    // And it is a real picture, not a cleared screen.
    let distinct: std::collections::HashSet<[u8; 4]> = window.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 100, "only {} distinct colours", distinct.len());
}

#[test]
fn demo_survives_a_resize_under_validation() {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let shot = common::temp_path("demo-resized.png");
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args([
            "demo",
            "--size",
            "96x64",
            "--frames",
            "8",
            "--resize-at",
            "3:120x40",
            "--validation",
            "--device",
            &device,
            "--screenshot",
        ])
        .arg(&shot)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "demo failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // The last frame was presented at the new size: the swapchain and targets were rebuilt.
    let window = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(window.dimensions(), (120, 40));
    let distinct: std::collections::HashSet<[u8; 4]> = window.pixels().map(|p| p.0).collect();
    assert!(
        distinct.len() > 50,
        "only {} distinct colours after the resize",
        distinct.len()
    );
}

#[test]
fn demo_cycles_through_the_scenes_methods_and_combinations() {
    // The M key's switch, scripted: every 2 frames the next configuration; the window keeps
    // presenting under validation through each switch, and wraps around.
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let scene = common::temp_path("demo-cycle.toml");
    std::fs::write(
        &scene,
        "methods = [\"forward\", { name = \"shadow_volumes\", mode = \"physical\" }]\n[[combinations]]\nname = \"mixed\"\nbase = \"forward\"\ndirect = \"shadow_volumes\"\n[camera]\nposition = [0, 2, 4]\ntarget = [0, 0.3, 0]\n[[objects]]\nmesh = \"plane\"\nsize = [4, 4]\n[[objects]]\nmesh = \"box\"\nsize = [0.5, 0.5, 0.5]\ntranslate = [0, 0.25, 0]\n[[lights]]\ntype = \"point\"\nposition = [1, 2, 1]\nintensity = 5\n",
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("demo")
        .arg(&scene)
        .args([
            "--size",
            "64x48",
            "--frames",
            "9",
            "--cycle-every",
            "2",
            "--validation",
            "--device",
            &device,
        ])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "demo failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let out = String::from_utf8_lossy(&o.stdout);
    let switches: Vec<&str> = out.lines().filter_map(|l| l.strip_prefix("configuration: ")).collect();
    assert_eq!(
        switches,
        ["shadow_volumes", "mixed", "forward", "shadow_volumes"],
        "{out}"
    );
}
