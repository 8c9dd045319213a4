//! The bake stage as users meet it: `penumbra bake` builds a scene's bakes into the cache, a
//! second run reads them back, a changed input rebuilds, and a corrupt cache file is rebuilt
//! with a one-line warning (never a panic, never silently used).

use crate::support as common;

use std::process::{Command, Output};

fn bake(cache: &std::path::Path, args: &[&str]) -> Output {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("bake")
        .args(args)
        .args(["--device", &device, "--validation"])
        .env("PENUMBRA_CACHE", cache)
        .output()
        .expect("run penumbra")
}

/// (bake name, source) rows of `penumbra bake`'s table.
fn rows(o: &Output) -> Vec<(String, String)> {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    out.lines()
        .filter(|l| l.starts_with("hf wedge table"))
        .map(|l| {
            let cols: Vec<&str> = l.split_whitespace().collect();
            let source_at = cols
                .iter()
                .position(|c| *c == "built" || *c == "cache")
                .expect("a source column");
            (cols[..source_at - 2].join(" "), cols[source_at].to_string())
        })
        .collect()
}

#[test]
fn bake_builds_then_reads_the_cache_and_rebuilds_what_changed_or_broke() {
    let cache = common::temp_path("bake-cache");
    let _ = std::fs::remove_dir_all(&cache);
    let scene = "scenes/terrain_sine.toml";
    let first = rows(&bake(&cache, &[scene, "--method", "heightfield_pyramid"]));
    assert_eq!(first.len(), 2, "{first:?}");
    assert!(first.iter().all(|(_, s)| s == "built"), "{first:?}");
    let second = rows(&bake(&cache, &[scene, "--method", "heightfield_pyramid"]));
    assert!(second.iter().all(|(_, s)| s == "cache"), "{second:?}");

    // A changed parameter is another key: built, while the old entries stay valid.
    let dir = common::temp_path("bake-scene");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(scene).unwrap().replace(
        "{ name = \"heightfield_pyramid\" }",
        "{ name = \"heightfield_pyramid\", nphi = 16 }",
    );
    assert!(text.contains("nphi = 16"), "the scene's method line changed: {text}");
    let changed = dir.join("terrain_sine_16.toml");
    std::fs::write(&changed, text).unwrap();
    let third = rows(&bake(
        &cache,
        &[changed.to_str().unwrap(), "--method", "heightfield_pyramid"],
    ));
    assert!(
        third.iter().all(|(n, s)| s == "built" && n.contains("nphi=16")),
        "{third:?}"
    );

    // Corrupt every cached file of the first scene: rebuilt, with a warning naming the file.
    let bake_dir = cache.join("bake");
    let mut corrupted = 0;
    for e in std::fs::read_dir(&bake_dir).unwrap() {
        let p = e.unwrap().path();
        let mut bytes = std::fs::read(&p).unwrap();
        if bytes.len() > 100 {
            let n = bytes.len();
            bytes[n / 2] ^= 0xff;
            std::fs::write(&p, &bytes[..n - 7]).unwrap();
            corrupted += 1;
        }
    }
    assert_eq!(corrupted, 4);
    let o = bake(&cache, &[scene, "--method", "heightfield_pyramid"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let fourth = rows(&o);
    assert!(fourth.iter().all(|(_, s)| s == "built"), "{fourth:?}");
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("warning: ") && l.contains("bake cache unusable (truncated"))
        .collect();
    assert_eq!(warnings.len(), 2, "{err}");
    // And the rebuilt files are whole: the next run reads them.
    assert!(rows(&bake(&cache, &[scene, "--method", "heightfield_pyramid"]))
        .iter()
        .all(|(_, s)| s == "cache"));
}

#[test]
fn a_scene_without_bakes_says_so() {
    let cache = common::temp_path("bake-none");
    let o = bake(&cache, &["scenes/cornell.toml"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(String::from_utf8_lossy(&o.stdout), "forward: nothing to bake\n");
}
