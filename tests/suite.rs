//! The generated-scene suite at a small N: scenes nobody tuned a method for, each method at its
//! defaults against the path-traced reference, supersampled.
//!
//! `issue_targets_on_generated_scenes` (ignored) is the measurement: the issue's targets over
//! 12 scenes, printing the table; docs/results/lavapipe/suite_seed1_n12_32x24.* hold a run of
//! `penumbra suite` with the same settings.

use penumbra::commands::suite::{self, Status, SuiteOptions};
use penumbra::scene::generate::Theme;

mod support;
use support as common;

fn options(out: &str, scenes: u64, size: (u32, u32), methods: &[&str]) -> SuiteOptions {
    let dir = common::temp_path(out);
    let _ = std::fs::remove_dir_all(&dir);
    SuiteOptions {
        scenes,
        seed: 1,
        shard: (1, 1),
        size,
        supersample: 2,
        frames: 3,
        timing_budget_s: 0.5,
        reference_spp: 256,
        reference_noise: 0.1,
        out: dir.clone(),
        cache_dir: dir.join("cache"),
        gpu: common::test_gpu_desc(),
        methods: methods.iter().map(|m| m.to_string()).collect(),
        worst: 1,
    }
}

/// Shards split the scenes without overlap or gap, the same way every time.
#[test]
fn shards_partition_the_scenes_by_index() {
    let mut seen = Vec::new();
    for k in 1..=3 {
        let mut o = options("shards", 10, (8, 8), &[]);
        o.shard = (k, 3);
        seen.extend(o.indices());
    }
    seen.sort();
    assert_eq!(seen, (0..10).collect::<Vec<u64>>());
    let mut o = options("shards", 10, (8, 8), &[]);
    o.shard = (2, 3);
    assert_eq!(o.indices(), vec![1, 4, 7]);
}

/// Configurations the small suite runs: every method whose defaults bake in seconds on
/// lavapipe (radiosity, the SH light-map and PRT bake for minutes at their defaults on room
/// scenes; the ignored measurement runs them).
const FAST: [&str; 9] = [
    "forward",
    "shadow_volumes",
    "clustered",
    "vls",
    "bsp_lights",
    "lpv",
    "lpv_over_shadow_volumes",
    "heightfield_pyramid",
    "heightfield_bruteforce",
];

/// The first six scenes (one of each theme) at 16x12, supersampled 2x2: every configuration
/// renders or refuses with its reason; none gives a NaN, an error, a panic or a validation
/// message; and the numbers that hold at the defaults hold.
#[test]
fn small_suite_runs_every_method_on_every_theme() {
    let opts = options("small-suite", 6, (16, 12), &FAST);
    let summary = suite::run(&opts).unwrap();
    print!("{}", summary.markdown());
    let rows = &summary.rows;
    let themes: std::collections::BTreeSet<&str> = rows.iter().map(|r| r.theme.as_str()).collect();
    assert_eq!(themes.len(), Theme::ALL.len(), "{themes:?}");
    for r in rows {
        assert!(!r.status.is_failure(), "{} {}: {:?}", r.scene, r.config, r.status);
        if r.status == Status::Ok {
            let m = r.metrics.as_ref().expect("an ok row is measured");
            assert!(
                m.rel_mse.is_finite() && m.mean_ratio.is_finite(),
                "{} {}",
                r.scene,
                r.config
            );
        }
    }
    let row = |theme: &str, config: &str| {
        rows.iter()
            .find(|r| r.theme == theme && r.config == config)
            .unwrap_or_else(|| panic!("no {config} row on the {theme} scene"))
    };
    // Methods lighting with point and spot lights only refuse quad panels, saying so.
    for m in ["vls", "bsp_lights", "shadow_volumes"] {
        if let Some(r) = rows.iter().find(|r| r.theme == "panels" && r.config == m) {
            assert!(
                matches!(&r.status, Status::Refused(why) if why.contains("point and spot lights only")),
                "{m}: {:?}",
                r.status
            );
        }
    }
    // The light propagation volume over shadow volumes carries the missing bounce: its image
    // mean is within 0.8-1.25 of the one-bounce reference (measured 1.022), where the direct
    // light alone has 0.793 of it.
    let lpv = row("lamps", "lpv_over_shadow_volumes");
    let (m, alone) = (lpv.metrics.as_ref().unwrap(), lpv.direct_alone.as_ref().unwrap());
    assert!((0.8..=1.25).contains(&m.mean_ratio), "{m:?}");
    assert!(m.mean_ratio > alone.mean_ratio + 0.1, "{m:?} against {alone:?}");
    // Shadowed direct light from point and spot lights: shadow volumes (physical) and the BSP
    // light matrix within 5e-3 and 2% of the mean (measured 2.6e-3 and 0.5%).
    for m in ["shadow_volumes", "bsp_lights"] {
        let r = row("crowd", m);
        let x = r.metrics.as_ref().unwrap();
        assert!(x.rel_mse <= 5e-3 && (x.mean_ratio - 1.0).abs() <= 0.02, "{m}: {x:?}");
    }
    // The height fields under a sphere light and a sky: within 3e-3 and 3% (measured 1.2e-3
    // and 1.5 % for the pyramid, 1.5e-3 and 1.9 % brute force).
    for m in ["heightfield_pyramid", "heightfield_bruteforce"] {
        let x = row("terrain", m).metrics.clone().unwrap();
        assert!(x.rel_mse <= 3e-3 && (x.mean_ratio - 1.0).abs() <= 0.03, "{m}: {x:?}");
    }
    // The worst scene of each configuration is saved and reads back as a scene.
    let worst: Vec<_> = std::fs::read_dir(opts.out.join("worst")).unwrap().collect();
    assert!(worst.len() >= summary.methods.len(), "{worst:?}");
    for f in worst {
        penumbra::scene::Scene::from_file(f.unwrap().path()).unwrap();
    }
}

/// The issue's targets over generated scenes (PENUMBRA_SUITE_SCENES, default 12) at 32x24,
/// supersampled 8x8 against references of up to 1,024 spp (at 2x2 and 256 spp edge aliasing and
/// the reference's noise alone failed the direct targets), every configuration at its defaults;
/// prints the table and writes it to PENUMBRA_SUITE_OUT (default a temporary folder). Not all
/// met at the defaults when last run (12 scenes, lavapipe): see
/// docs/results/lavapipe/suite_seed1_n12_32x24.md.
#[test]
#[ignore]
fn issue_targets_on_generated_scenes() {
    let scenes = std::env::var("PENUMBRA_SUITE_SCENES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(12);
    let mut opts = options("targets", scenes, (32, 24), &[]);
    opts.supersample = 8;
    opts.reference_spp = 1024;
    if let Some(dir) = std::env::var_os("PENUMBRA_SUITE_OUT") {
        opts.out = dir.into();
    }
    let summary = suite::run(&opts).unwrap();
    print!("{}", summary.markdown());
    let missed: Vec<String> = summary
        .targets
        .iter()
        .filter(|t| t.applies > 0 && !t.met())
        .map(|t| format!("{}: {} of {}", t.name, t.holds, t.applies))
        .collect();
    assert!(missed.is_empty(), "targets not met:\n{}", missed.join("\n"));
}
