//! PRT on a scene nobody tuned it for: a generated sun room, as a user's capture sees it.

use crate::support::{ok, penumbra, temp_path};

/// `penumbra compare`'s "mean ratio" (Σ test / Σ reference).
fn mean_ratio(test: &std::path::Path, reference: &std::path::Path) -> f64 {
    let out = ok(&penumbra(&[
        "compare",
        test.to_str().unwrap(),
        reference.to_str().unwrap(),
    ]));
    out.lines()
        .find_map(|l| l.strip_prefix("mean ratio")?.split_whitespace().next()?.parse().ok())
        .unwrap_or_else(|| panic!("no mean ratio in {out}"))
}

/// The generated sun room's floor, ceiling and walls are boxes of two triangles a face, whose
/// corners lie on the walls' outer faces. Baked at those vertices alone, the corners see the sky
/// and the sun, and interpolation lights the room as if outdoors: 16.7 times the direct
/// reference's mean at 64x48 (measured by hand). With the receivers' long edges split towards the
/// derived max_edge (half the smallest object's extent), the mean is 1.34 times the reference's
/// (1.30 once every edge is within it); the rest is light the corners still bring in along the
/// walls' feet. The test splits at most 4,096 vertices (the default is 16,384) to bake in
/// seconds on lavapipe.
#[test]
fn prt_splits_a_rooms_long_edges_and_keeps_the_sky_outside() {
    let dir = temp_path("prt-refine");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let generated = penumbra::scene::generate::generate(1, 8);
    assert_eq!(generated.theme.name(), "sun");
    let methods = generated
        .text
        .lines()
        .find(|l| l.starts_with("methods = "))
        .unwrap()
        .to_string();
    let write = |name: &str, decl: &str| {
        let path = dir.join(name);
        std::fs::write(&path, generated.text.replace(&methods, &format!("methods = [{decl}]"))).unwrap();
        path
    };
    let split = write("split.toml", r#"{ name = "prt", refine_budget = 4096 }"#);
    let as_made = write("as_made.toml", r#"{ name = "prt", max_edge = 0 }"#);
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let reference = dir.join("reference.exr");
    ok(&penumbra(&[
        "reference",
        &s(&split),
        "--size",
        "32x24",
        "--direct-only",
        "--spp",
        "256",
        "-o",
        &s(&reference),
    ]));
    let capture = |scene: &std::path::Path, exr: &str| {
        let exr = dir.join(exr);
        // A cache of its own: a bake left by an earlier run must not stand in for this one.
        let cache = dir.join(format!("cache-{}", scene.file_stem().unwrap().to_string_lossy()));
        let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args([
                "capture",
                &s(scene),
                "--size",
                "32x24",
                "--supersample",
                "2",
                "--exr",
                &s(&exr),
            ])
            .args(["--device", &device])
            .env("PENUMBRA_VALIDATION", "1")
            .env("PENUMBRA_CACHE", &cache)
            .output()
            .expect("run penumbra");
        ok(&o);
        (
            mean_ratio(&exr, &reference),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (ratio_as_made, _) = capture(&as_made, "as_made.exr");
    let (ratio_split, said) = capture(&split, "split.exr");
    println!("mean ratio: {ratio_as_made:.3} at the meshes' own vertices, {ratio_split:.3} split\n{said}");
    assert!(ratio_as_made > 5.0, "{ratio_as_made}");
    assert!((0.8..=1.6).contains(&ratio_split), "{ratio_split}");
    assert!(
        said.contains("prt: max_edge = 0.36 (half the 0.720 m of object"),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
