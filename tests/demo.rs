//! The windowed demo under an X server (tools/test.sh runs the suite under Xvfb): it opens,
//! presents frames with validation on, and its screenshot — the presented swapchain pixels — shows
//! the same image as a headless capture of the same scene.

use std::process::Command;

mod common;

#[test]
fn demo_presents_the_scene_under_xvfb() {
    assert!(std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some(), "no display: run the suite through tools/test.sh, which starts Xvfb");
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let shot = common::temp_path("demo.png");
    let capture = common::temp_path("demo-reference.png");
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra")).args(["demo", "--size", "96x64", "--frames", "4", "--validation", "--device", &device, "--screenshot"]).arg(&shot).output().unwrap();
    assert!(o.status.success(), "demo failed:\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("after 4 frames"));
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra")).args(["capture", "--size", "96x64", "--device", &device, "-o"]).arg(&capture).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let window = image::open(&shot).unwrap().to_rgba8();
    let headless = image::open(&capture).unwrap().to_rgba8();
    assert_eq!(window.dimensions(), (96, 64));
    // GPU tone mapping + sRGB store vs the CPU path: equal up to rounding, except where the fly
    // camera's rebuilt view matrix moves a silhouette by a fraction of a pixel.
    let diffs: Vec<i32> = window.pixels().zip(headless.pixels()).flat_map(|(a, b)| (0..3).map(move |c| (a[c] as i32 - b[c] as i32).abs())).collect();
    let mean = diffs.iter().sum::<i32>() as f64 / diffs.len() as f64;
    let within = diffs.iter().filter(|&&d| d <= 2).count() as f64 / diffs.len() as f64;
    assert!(mean < 1.0 && within > 0.98, "window vs headless: mean |diff| {mean:.3}, {:.1}% within 2", within * 100.0);
    // And it is a real picture, not a cleared screen.
    let distinct: std::collections::HashSet<[u8; 4]> = window.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 100, "only {} distinct colours", distinct.len());
}

#[test]
fn demo_survives_a_resize_under_validation() {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let shot = common::temp_path("demo-resized.png");
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["demo", "--size", "96x64", "--frames", "8", "--resize-at", "3:120x40", "--validation", "--device", &device, "--screenshot"])
        .arg(&shot)
        .output()
        .unwrap();
    assert!(o.status.success(), "demo failed:\n{}", String::from_utf8_lossy(&o.stderr));
    // The last frame was presented at the new size: the swapchain and targets were rebuilt.
    let window = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(window.dimensions(), (120, 40));
    let distinct: std::collections::HashSet<[u8; 4]> = window.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 50, "only {} distinct colours after the resize", distinct.len());
}
