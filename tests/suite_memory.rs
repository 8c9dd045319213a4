//! Memory stays flat over 300 frames of every method on a generated scene (see tests/memory.rs
//! for the counter: `RssAnon`, the resident anonymous pages, where a leak lands). This file holds
//! one test, so no other test of the binary allocates while it measures.

use penumbra::renderer::Renderer;
use penumbra::scene::generate::{generate, Theme};
use penumbra::scene::Scene;

mod support;
use support as common;

fn rss_anon_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("read /proc/self/status");
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("RssAnon:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .expect("RssAnon in /proc/self/status");
    kb / 1024.0
}

/// The first generated scene of seed 1 with this theme.
fn scene_of(theme: Theme) -> Scene {
    let g = (0..)
        .map(|i| generate(1, i))
        .find(|g| g.theme == theme)
        .expect("every theme is generated");
    Scene::from_str(&g.text, &g.name, std::path::Path::new("/")).unwrap()
}

/// Each configuration of the first generated scene of three themes (spot-lit rooms, a sun
/// through a window, terrain): 40 frames of warm-up, then 300 more at 12x8 (the height fields
/// trace every pixel; a frame of theirs takes seconds at 32x24 on lavapipe), reading RssAnon
/// every 50. The growth after warm-up may be at most 6 MiB (the allocator's and the validation
/// layer's slack, as in tests/memory.rs), and device memory must not change. Radiosity is left
/// out: its default bake of these rooms takes many minutes on lavapipe, and its frame (a
/// light-map lookup) is soaked by tests/memory.rs.
///
/// Ignored: 300 frames of the light propagation volume (its volume does not shrink with the
/// image) take several minutes per configuration on lavapipe; run it with `--ignored`.
#[test]
#[ignore]
fn every_method_renders_300_frames_of_a_generated_scene_in_flat_memory() {
    const LIMIT_MIB: f64 = 6.0;
    let mut failures = Vec::new();
    for theme in [Theme::Lamps, Theme::Sun, Theme::Terrain] {
        let scene = scene_of(theme);
        let configs = penumbra::lighting::registry::configurations(&scene).unwrap();
        for config in configs.into_iter().filter(|c| c.name != "radiosity") {
            let camera = scene.camera.clone();
            let t = std::time::Instant::now();
            let mut r = Renderer::new(common::test_gpu(), scene.clone(), Some(&config.name), (12, 8), 1).unwrap();
            r.profile(&camera, 40).unwrap();
            let mut samples = vec![rss_anon_mib()];
            let device = r.gpu.device_memory().0;
            let mut device_changed = false;
            for _ in 0..6 {
                r.profile(&camera, 50).unwrap();
                samples.push(rss_anon_mib());
                device_changed |= r.gpu.device_memory().0 != device;
            }
            common::assert_clean(&r.gpu);
            let growth = samples.last().unwrap() - samples[0];
            let trace: Vec<String> = samples.iter().map(|m| format!("{m:.1}")).collect();
            eprintln!(
                "{} {}: RssAnon MiB every 50 frames {} ({:.1} s)",
                theme.name(),
                config.name,
                trace.join(", "),
                t.elapsed().as_secs_f64()
            );
            if growth > LIMIT_MIB {
                failures.push(format!(
                    "{} {}: +{growth:.1} MiB ({})",
                    theme.name(),
                    config.name,
                    trace.join(", ")
                ));
            }
            if device_changed {
                failures.push(format!(
                    "{} {}: device memory changes after warm-up",
                    theme.name(),
                    config.name
                ));
            }
        }
    }
    assert!(failures.is_empty(), "memory grows:\n{}", failures.join("\n"));
}
