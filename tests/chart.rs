//! `penumbra compare`, `penumbra chart` and `capture --max-error` as users run them.

mod common;

use common::{ok, penumbra};

use penumbra::image_io::HdrImage;

#[test]
fn compare_prints_known_metrics_and_writes_a_diff_image() {
    let (a, b, diff) = (common::temp_path("cmp-test.exr"), common::temp_path("cmp-ref.exr"), common::temp_path("cmp-diff.png"));
    let mut reference = HdrImage::new(8, 4);
    for (i, p) in reference.pixels.iter_mut().enumerate() {
        let v = if i % 2 == 0 { 0.2 } else { 1.0 };
        *p = [v, v, v, 1.0];
    }
    let mut test = reference.clone();
    for p in &mut test.pixels {
        for c in &mut p[..3] {
            *c += 0.1;
        }
    }
    test.write_exr(&a).unwrap();
    reference.write_exr(&b).unwrap();
    let out = ok(&penumbra(&["compare", a.to_str().unwrap(), b.to_str().unwrap(), "--json", "--diff", diff.to_str().unwrap()]));
    let json: String = out.lines().take_while(|l| !l.starts_with("wrote")).collect::<Vec<_>>().join("\n");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let near = |k: &str, x: f64| assert!((v[k].as_f64().unwrap() - x).abs() < 1e-6, "{k} = {} (want {x})", v[k]);
    near("rmse", 0.1);
    near("mean_bias", 0.1);
    near("max_abs_error", 0.1);
    // Half the pixels at 0.2, half at 1.0: mean of 0.01/(r²+0.01).
    near("rel_mse", 0.5 * (0.01 / 0.05 + 0.01 / 1.01));
    assert!(v["flip_mean"].as_f64().unwrap() > 0.0);
    let d = image::open(&diff).unwrap();
    assert_eq!((d.width(), d.height()), (8, 4));
    // Mismatched sizes: one clear line.
    let small = common::temp_path("cmp-small.exr");
    HdrImage::new(2, 2).write_exr(&small).unwrap();
    let o = penumbra(&["compare", small.to_str().unwrap(), b.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("2x2") && e.contains("8x4") && e.lines().count() == 1, "{e}");
}

#[test]
fn chart_measures_the_scene_caches_the_reference_and_drives_max_error() {
    let cache = common::temp_path("chart-cache");
    let (png, csv) = (common::temp_path("chart.png"), common::temp_path("chart.csv"));
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml");
    let args = ["chart", scene, "--size", "32x32", "--reference-spp", "16", "--frames", "3", "--cache-dir", cache.to_str().unwrap(), "-o", png.to_str().unwrap(), "--csv", csv.to_str().unwrap()];
    let first = penumbra(&args);
    ok(&first);
    assert!(String::from_utf8_lossy(&first.stderr).contains("rendering the reference"));
    let table = std::fs::read_to_string(&csv).unwrap();
    let rows = penumbra::chart::parse_csv(&table).unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!((rows[0].method.as_str(), rows[0].config.as_str()), ("forward", "forward"));
    assert!(rows[0].frame_ms > 0.0 && rows[0].rel_mse > 0.0 && rows[0].rel_mse.is_finite());
    let header = table.lines().next().unwrap();
    for col in ["frame_ms", "pass:forward_ms", "rmse", "rel_mse", "mean_bias", "p99_abs_error", "max_abs_error", "flip"] {
        assert!(header.split(',').any(|h| h == col), "missing column {col}: {header}");
    }
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (1000, 700));

    // Second run: the reference comes from the cache, and the error is the same.
    let second = penumbra(&args);
    ok(&second);
    assert!(!String::from_utf8_lossy(&second.stderr).contains("rendering the reference"));
    let again = penumbra::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    assert_eq!(again[0].rel_mse, rows[0].rel_mse);

    // --max-error picks from these measurements, or says none qualifies and names the closest.
    let out = common::temp_path("max-error.png");
    let loose = format!("{}", rows[0].rel_mse * 2.0);
    let o = ok(&penumbra(&["capture", scene, "--size", "32x32", "--max-error", &loose, "--cache-dir", cache.to_str().unwrap(), "-o", out.to_str().unwrap()]));
    assert!(o.contains("picked `forward`"), "{o}");
    assert!(out.exists());
    let tight = format!("{}", rows[0].rel_mse / 2.0);
    let o = penumbra(&["capture", scene, "--size", "32x32", "--max-error", &tight, "--cache-dir", cache.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("no configuration reaches the bound") && e.contains("closest is `forward`"), "{e}");
    // Without chart data for that size it says what to run.
    let o = penumbra(&["capture", scene, "--size", "16x16", "--max-error", "0.1", "--cache-dir", cache.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("run `penumbra chart"), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `penumbra chart` on the textured seed 000 level: every point of the shadow-volume sweep is
/// measured against the direct-lighting reference, which now applies the level's albedo, normal
/// and specular maps as the method does; the physical mode is the accurate one.
#[test]
fn chart_measures_the_textured_shadow_volume_level() {
    let cache = common::temp_path("sv-chart-cache");
    let csv = common::temp_path("sv-chart.csv");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bsp_rooms.toml");
    let png = common::temp_path("sv-chart.png");
    let args = [
        "chart",
        scene,
        "--method",
        "shadow_volumes",
        "--size",
        "64x64",
        "--reference-spp",
        "16",
        "--frames",
        "1",
        "--cache-dir",
        cache.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ];
    ok(&penumbra(&args));
    let rows = penumbra::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let configs: Vec<&str> = rows.iter().map(|r| r.config.as_str()).collect();
    assert_eq!(rows.len(), 14, "{configs:?}");
    for want in
        ["faithful pscs", "physical naive casters", "physical pvs-only casters", "physical pscs z-pass", "physical pscs default maps", "physical pscs PVS off", "faithful pscs default maps PVS off"]
    {
        assert!(configs.iter().any(|c| c.ends_with(want)), "{want} missing from {configs:?}");
    }
    let err = |c: &str| rows.iter().find(|r| r.config.ends_with(c)).map(|r| r.rel_mse).unwrap();
    println!("relative MSE: faithful {:.4}, physical {:.4}", err("faithful pscs"), err("physical pscs"));
    // At 64² the texture detail the raster point-samples and the reference box-filters dominates
    // the physical mode's error (0.024 here, 0.012 at 128²; 2.4e-4 with the method's image
    // rendered at 512² and box-filtered to 128²).
    assert!(err("physical pscs") < 0.05 && 3.0 * err("physical pscs") < err("faithful pscs"));
    // Caster strategies and material paths draw the same image (to rounding).
    for c in ["physical naive casters", "physical pscs default maps"] {
        assert!((err(c) / err("physical pscs") - 1.0).abs() < 1e-3, "{c}: {} vs {}", err(c), err("physical pscs"));
    }
    let table = std::fs::read_to_string(&csv).unwrap();
    assert!(table.lines().skip(1).all(|l| l.contains(",direct; 16 spp,")), "{table}");
}

/// `penumbra chart` on the spot-light level (scenes/bsp_spot.toml): the direct reference
/// applies the forward method's spot falloff (glsl/common/lights.glsl) as the shadow-volume
/// method does, so the physical mode is as close to it as with point lights, the faithful one
/// is not, and every caster strategy draws the same image.
#[test]
fn chart_measures_the_spot_light_level() {
    let cache = common::temp_path("sv-spot-chart-cache");
    let csv = common::temp_path("sv-spot-chart.csv");
    let png = common::temp_path("sv-spot-chart.png");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bsp_spot.toml");
    let args = ["chart", scene, "--size", "64x64", "--reference-spp", "64", "--frames", "1", "--cache-dir", cache.to_str().unwrap(), "-o", png.to_str().unwrap(), "--csv", csv.to_str().unwrap()];
    ok(&penumbra(&args));
    let rows = penumbra::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let err = |c: &str| rows.iter().find(|r| r.config.ends_with(c)).map(|r| r.rel_mse).unwrap();
    println!("spot level, relative MSE: faithful {:.4}, physical {:.4}", err("faithful pscs"), err("physical pscs"));
    assert!(err("physical pscs") < 0.01 && 3.0 * err("physical pscs") < err("faithful pscs"));
    for c in ["physical naive casters", "physical pvs-only casters", "physical pscs PVS off"] {
        assert!((err(c) / err("physical pscs") - 1.0).abs() < 1e-3, "{c}: {} vs {}", err(c), err("physical pscs"));
    }
}

/// `penumbra chart` on a height field: both methods' sweeps against the direct-light reference,
/// and the trends the sweep is there to show — the faithful planar light distance (a light close
/// above the field becomes a hemisphere) and 2 bands are far worse than the corrected 4-band
/// default, and fewer directions are no better.
#[test]
fn chart_measures_the_height_field_methods() {
    let scene = common::temp_path("hf-chart.toml");
    std::fs::write(
        &scene,
        r#"methods = [{ name = "heightfield_pyramid" }, { name = "heightfield_bruteforce", march_step = 0.5 }]
[camera]
position = [0, 6, 5]
target = [0, 0, 0]
[[materials]]
name = "ground"
albedo = 0.7
[[objects]]
mesh = "heightfield"
material = "ground"
size = 8
resolution = 32
generator = "sine"
wavelength = 2
height = 0.6
[[lights]]
type = "sphere"
center = [0, 0.9, 0]
radius = 0.2
radiance = 30
[environment]
type = "constant"
radiance = 0.3
"#,
    )
    .unwrap();
    let (cache, csv, png) = (common::temp_path("hf-chart-cache"), common::temp_path("hf-chart.csv"), common::temp_path("hf-chart.png"));
    let args = [
        "chart",
        scene.to_str().unwrap(),
        "--size",
        "32x32",
        "--reference-spp",
        "16",
        "--frames",
        "1",
        "--cache-dir",
        cache.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ];
    ok(&penumbra(&args));
    let rows = penumbra::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let count = |m: &str| rows.iter().filter(|r| r.method == m).count();
    assert_eq!((count("heightfield_pyramid"), count("heightfield_bruteforce")), (14, 7));
    let err = |c: &str| rows.iter().find(|r| r.config == c).map(|r| r.rel_mse).unwrap_or_else(|| panic!("{c} missing"));
    let default = err("pyramid nphi=32 ls=4 lo=4 bands=4 corrected");
    println!(
        "relative MSE: pyramid {default:.4}, nφ = 4 {:.4}, faithful {:.4}, 2 bands {:.4}, brute {:.4}",
        err("pyramid nphi=4 ls=4 lo=4 bands=4 corrected"),
        err("pyramid nphi=32 ls=4 lo=4 bands=4 faithful"),
        err("pyramid nphi=32 ls=4 lo=4 bands=2 corrected"),
        err("brute nphi=32 step=0.5 bands=4 corrected")
    );
    assert!(default < 0.05, "{default}");
    assert!(err("pyramid nphi=32 ls=4 lo=4 bands=4 faithful") > 3.0 * default);
    assert!(err("brute nphi=32 step=0.5 bands=4 faithful") > 3.0 * err("brute nphi=32 step=0.5 bands=4 corrected"));
    assert!(err("pyramid nphi=32 ls=4 lo=4 bands=2 corrected") > 1.5 * default);
    assert!(err("pyramid nphi=4 ls=4 lo=4 bands=4 corrected") >= default);
    let table = std::fs::read_to_string(&csv).unwrap();
    assert!(table.lines().skip(1).all(|l| l.contains(",direct; 16 spp,")), "{table}");
}
