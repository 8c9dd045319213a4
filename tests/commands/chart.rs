//! `penumbra compare`, `penumbra chart` and `capture --max-error` as users run them.

use crate::support as common;

use common::{ok, penumbra};

use penumbra::util::image_io::HdrImage;

/// `penumbra chart SCENE OPTIONS...` writing its reference cache, PNG and CSV to the given paths.
fn chart(
    scene: &str,
    options: &[&str],
    cache: &std::path::Path,
    png: &std::path::Path,
    csv: &std::path::Path,
) -> std::process::Output {
    let mut args = vec!["chart", scene];
    args.extend_from_slice(options);
    args.extend([
        "--cache-dir",
        cache.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    penumbra(&args)
}

/// `penumbra capture SCENE --size SIZE --max-error BOUND` reading the chart cache `cache`,
/// writing `out` when given.
fn capture_max_error(
    scene: &str,
    size: &str,
    bound: &str,
    cache: &std::path::Path,
    out: Option<&std::path::Path>,
) -> std::process::Output {
    let mut args = vec![
        "capture",
        scene,
        "--size",
        size,
        "--max-error",
        bound,
        "--cache-dir",
        cache.to_str().unwrap(),
    ];
    if let Some(out) = out {
        args.extend(["-o", out.to_str().unwrap()]);
    }
    penumbra(&args)
}

#[test]
fn compare_prints_known_metrics_and_writes_a_diff_image() {
    let (a, b, diff) = (
        common::temp_path("cmp-test.exr"),
        common::temp_path("cmp-ref.exr"),
        common::temp_path("cmp-diff.png"),
    );
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
    let out = ok(&penumbra(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
        "--diff",
        diff.to_str().unwrap(),
    ]));
    let json: String = out
        .lines()
        .take_while(|l| !l.starts_with("wrote"))
        .collect::<Vec<_>>()
        .join("\n");
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
    let options = ["--size", "32x32", "--reference-spp", "16", "--frames", "3"];
    let first = chart(scene, &options, &cache, &png, &csv);
    ok(&first);
    assert!(String::from_utf8_lossy(&first.stderr).contains("rendering the reference"));
    let table = std::fs::read_to_string(&csv).unwrap();
    let rows = penumbra::commands::chart::parse_csv(&table).unwrap();
    assert_eq!(rows.len(), 1);
    assert_eq!(
        (rows[0].method.as_str(), rows[0].config.as_str()),
        ("forward", "forward")
    );
    assert!(rows[0].frame_ms > 0.0 && rows[0].rel_mse > 0.0 && rows[0].rel_mse.is_finite());
    let header = table.lines().next().unwrap();
    for col in [
        "frame_ms",
        "pass:forward_ms",
        "rmse",
        "rel_mse",
        "mean_bias",
        "p99_abs_error",
        "max_abs_error",
        "flip",
    ] {
        assert!(header.split(',').any(|h| h == col), "missing column {col}: {header}");
    }
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (1600, 820));

    // Second run: the reference comes from the cache, and the error is the same.
    let second = chart(scene, &options, &cache, &png, &csv);
    ok(&second);
    assert!(!String::from_utf8_lossy(&second.stderr).contains("rendering the reference"));
    let again = penumbra::commands::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    assert_eq!(again[0].rel_mse, rows[0].rel_mse);

    // --max-error picks from these measurements, or says none qualifies and names the closest.
    let out = common::temp_path("max-error.png");
    let loose = format!("{}", rows[0].rel_mse * 2.0);
    let o = ok(&capture_max_error(scene, "32x32", &loose, &cache, Some(&out)));
    assert!(o.contains("picked `forward`"), "{o}");
    assert!(out.exists());
    let tight = format!("{}", rows[0].rel_mse / 2.0);
    let o = capture_max_error(scene, "32x32", &tight, &cache, Some(&out));
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("no configuration reaches the bound") && e.contains("closest is `forward`"),
        "{e}"
    );
    // Without chart data for that size it says what to run.
    let o = capture_max_error(scene, "16x16", "0.1", &cache, None);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("run `penumbra chart"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// An asset alone declares no method: `chart --method` measures one it names, and `capture
/// --max-error` then picks from that chart, as for a scene file's own methods.
#[test]
fn chart_and_max_error_take_a_method_an_asset_does_not_declare() {
    let dir = common::temp_path("chart-asset");
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("tent.obj");
    std::fs::write(
        &obj,
        "v -2 0 -2\nv -2 0 2\nv 2 0 2\nv 2 0 -2\nv -0.5 0.8 0\nv 0.5 0.8 0\nv 0 0.8 0.5\nf 1 2 3 4\nf 5 7 6\n",
    )
    .unwrap();
    let (cache, png, csv) = (dir.join("cache"), dir.join("chart.png"), dir.join("chart.csv"));
    let options = [
        "--size",
        "24x16",
        "--reference-spp",
        "8",
        "--frames",
        "2",
        "--method",
        "clustered",
    ];
    ok(&chart(obj.to_str().unwrap(), &options, &cache, &png, &csv));
    let rows = penumbra::commands::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    assert!(
        !rows.is_empty() && rows.iter().all(|r| r.method == "clustered"),
        "{rows:?}"
    );
    let loose = format!("{}", rows.iter().map(|r| r.rel_mse).fold(0.0, f64::max) * 2.0);
    let out = dir.join("picked.png");
    let o = ok(&capture_max_error(
        obj.to_str().unwrap(),
        "24x16",
        &loose,
        &cache,
        Some(&out),
    ));
    assert!(o.contains("picked `clustered"), "{o}");
    assert!(out.exists());
}

/// `penumbra chart` on the textured the Ca3D-Engine thesis level: every point of the shadow-volume sweep is
/// measured against the direct-lighting reference, which now applies the level's albedo, normal
/// and specular maps as the method does; the physical mode is the accurate one.
#[test]
fn chart_measures_the_textured_shadow_volume_level() {
    let cache = common::temp_path("sv-chart-cache");
    let csv = common::temp_path("sv-chart.csv");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bsp_rooms.toml");
    let png = common::temp_path("sv-chart.png");
    let options = [
        "--method",
        "shadow_volumes",
        "--size",
        "64x64",
        "--reference-spp",
        "16",
        "--frames",
        "1",
        "--supersample",
        "4",
    ];
    let stdout = ok(&chart(scene, &options, &cache, &png, &csv));
    assert!(stdout.contains("supersampled 4x4"), "{stdout}");
    let rows = penumbra::commands::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let configs: Vec<&str> = rows.iter().map(|r| r.config.as_str()).collect();
    assert_eq!(rows.len(), 16, "{configs:?}");
    for want in [
        "faithful pscs",
        "physical naive casters",
        "physical pvs-only casters",
        "physical pscs z-fail",
        "physical pscs z-pass",
        "physical pscs default maps",
        "physical pscs PVS off",
        "faithful pscs default maps PVS off",
    ] {
        assert!(
            configs.iter().any(|c| c.ends_with(want)),
            "{want} missing from {configs:?}"
        );
    }
    let err = |c: &str| rows.iter().find(|r| r.config.ends_with(c)).map(|r| r.rel_mse).unwrap();
    println!(
        "relative MSE: faithful {:.4}, physical {:.4}",
        err("faithful pscs"),
        err("physical pscs")
    );
    // At 64² the texture detail the raster point-samples and the reference box-filters dominates
    // the physical mode's error (0.024 here, 0.012 at 128²; 2.4e-4 with the method's image
    // rendered at 512² and box-filtered to 128²).
    assert!(err("physical pscs") < 0.05 && 3.0 * err("physical pscs") < err("faithful pscs"));
    // Caster strategies, material paths and z-fail beside the default counting draw the same
    // image (to rounding).
    for c in [
        "physical naive casters",
        "physical pscs default maps",
        "physical pscs z-fail",
    ] {
        assert!(
            (err(c) / err("physical pscs") - 1.0).abs() < 1e-3,
            "{c}: {} vs {}",
            err(c),
            err("physical pscs")
        );
    }
    let table = std::fs::read_to_string(&csv).unwrap();
    assert!(
        table.lines().skip(1).all(|l| l.contains(",direct; sobol; 16 spp,4,")),
        "{table}"
    );
    // Like for like: the method rendered at 256² and box-filtered to 64² averages its pixels'
    // footprints as the reference does, and most of the pixel centres' error is gone (aliased
    // texture detail); the CSV keeps both.
    let (centre, ss, noise) = (
        column(&table, "rel_mse"),
        column(&table, "ss_rel_mse"),
        column(&table, "ref_noise_rel_mse"),
    );
    let i = rows.iter().position(|r| r.config.ends_with("physical pscs")).unwrap();
    let (centre, ss, noise): (f64, f64, f64) = (
        centre[i].parse().unwrap(),
        ss[i].parse().unwrap(),
        noise[i].parse().unwrap(),
    );
    println!("physical pscs, relative MSE: pixel centres {centre:.4}, supersampled 4x4 {ss:.5}, the reference's own noise {noise:.5}");
    assert!(ss < centre / 4.0, "supersampled {ss} vs pixel centres {centre}");
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
    let options = ["--size", "64x64", "--reference-spp", "64", "--frames", "1"];
    ok(&chart(scene, &options, &cache, &png, &csv));
    let rows = penumbra::commands::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let err = |c: &str| rows.iter().find(|r| r.config.ends_with(c)).map(|r| r.rel_mse).unwrap();
    println!(
        "spot level, relative MSE: faithful {:.4}, physical {:.4}",
        err("faithful pscs"),
        err("physical pscs")
    );
    assert!(err("physical pscs") < 0.01 && 3.0 * err("physical pscs") < err("faithful pscs"));
    for c in [
        "physical naive casters",
        "physical pvs-only casters",
        "physical pscs PVS off",
    ] {
        assert!(
            (err(c) / err("physical pscs") - 1.0).abs() < 1e-3,
            "{c}: {} vs {}",
            err(c),
            err("physical pscs")
        );
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
    let (cache, csv, png) = (
        common::temp_path("hf-chart-cache"),
        common::temp_path("hf-chart.csv"),
        common::temp_path("hf-chart.png"),
    );
    let options = [
        "--size",
        "32x32",
        "--reference-spp",
        "16",
        "--frames",
        "6",
        // Any frame outruns this budget: each configuration is timed over the minimum, 3.
        "--timing-budget",
        "1e-6",
    ];
    ok(&chart(scene.to_str().unwrap(), &options, &cache, &png, &csv));
    let rows = penumbra::commands::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
    let count = |m: &str| rows.iter().filter(|r| r.method == m).count();
    assert_eq!((count("heightfield_pyramid"), count("heightfield_bruteforce")), (14, 7));
    let timed = column(&std::fs::read_to_string(&csv).unwrap(), "frames_timed");
    assert!(
        timed.len() == 21 && timed.iter().all(|t| t == "3"),
        "frames timed under a spent budget: {timed:?}"
    );
    let err = |c: &str| {
        rows.iter()
            .find(|r| r.config == c)
            .map(|r| r.rel_mse)
            .unwrap_or_else(|| panic!("{c} missing"))
    };
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
    assert!(
        table.lines().skip(1).all(|l| l.contains(",direct; sobol; 16 spp,")),
        "{table}"
    );
}

/// A CSV column by header name, one string per row.
fn column(table: &str, name: &str) -> Vec<String> {
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let i = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name}: {header:?}"));
    table
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(i).unwrap_or("").to_string())
        .collect()
}

/// The chart asks the reference for the error its metrics need: the reference renders (from
/// 32 spp on) until the relative MSE its noise adds is at most `--reference-noise` of the
/// smallest relative MSE it judges, and its noise's 99th-percentile error at most the square
/// root of that fraction of the smallest p99 it judges, and the CSV gives, beside every metric, the reference's own
/// error; the closed-form ones are checked here against the cached standard-error image by
/// hand.
#[test]
fn chart_asks_the_reference_for_the_error_its_metrics_need_and_reports_its_noise() {
    let cache = common::temp_path("chart-noise-cache");
    let (png, csv) = (
        common::temp_path("chart-noise.png"),
        common::temp_path("chart-noise.csv"),
    );
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml");
    let cap = 2048;
    let options = [
        "--size",
        "24x24",
        "--reference-spp",
        "2048",
        "--reference-noise",
        "0.1",
        "--frames",
        "1",
    ];
    let stdout = ok(&chart(scene, &options, &cache, &png, &csv));
    assert!(stdout.contains("[the reference's own error"), "{stdout}");
    let table = std::fs::read_to_string(&csv).unwrap();
    let num = |name: &str| -> f64 {
        column(&table, name)[0]
            .parse()
            .unwrap_or_else(|_| panic!("{name} is not a number: {table}"))
    };
    for m in ["rmse", "rel_mse", "mean_bias", "p99_abs_error", "max_abs_error", "flip"] {
        let v = num(&format!("ref_noise_{m}"));
        assert!(v.is_finite() && v > 0.0, "ref_noise_{m} = {v}");
        assert_eq!(column(&table, &format!("ss_{m}"))[0], "", "no supersampling asked for");
    }
    assert_eq!(column(&table, "supersample")[0], "1");
    // The spp the reference took, from its label (`16 bounces; N spp`).
    let label = &column(&table, "reference")[0];
    let spp: u32 = label
        .rsplit("; ")
        .next()
        .and_then(|t| t.strip_suffix(" spp"))
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{label}"));
    let (rel_mse, noise) = (num("rel_mse"), num("ref_noise_rel_mse"));
    println!("reference {label}: its noise adds {noise:.3e} to a relative MSE of {rel_mse:.3e}");
    // At the 32 spp minimum the noise was 6.6e-3 of 4.8e-2: more samples were needed.
    assert!((33..cap).contains(&spp), "stopped at {spp} of at most {cap}");
    assert!(noise <= 0.1 * rel_mse, "{noise} > 0.1 × {rel_mse}");
    // And the 99th percentile: the noise's at most √0.1 of the method's.
    let (p99, noise_p99) = (num("p99_abs_error"), num("ref_noise_p99_abs_error"));
    println!("p99: the noise's {noise_p99:.3e} against the method's {p99:.3e}");
    assert!(noise_p99 <= 0.1f64.sqrt() * p99, "{noise_p99} > √0.1 × {p99}");

    // By hand from the cached mean and standard error.
    let cached: Vec<std::path::PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".stderr.exr"))
        .collect();
    assert_eq!(cached.len(), 1, "{cached:?}");
    let se = HdrImage::read_exr(&cached[0]).unwrap();
    let mean = HdrImage::read_exr(&std::path::PathBuf::from(
        cached[0].to_string_lossy().replace(".stderr.exr", ".exr"),
    ))
    .unwrap();
    let (mut sum_sq, mut sum_rel) = (0.0f64, 0.0f64);
    for (m, s) in mean.pixels.iter().zip(&se.pixels) {
        for c in 0..3 {
            let (m, s) = (m[c] as f64, s[c] as f64);
            sum_sq += s * s;
            sum_rel += s * s / (m * m + 0.01);
        }
    }
    let n = 3.0 * mean.pixels.len() as f64;
    let close = |name: &str, want: f64| {
        assert!(
            (num(name) - want).abs() <= 1e-9 * want,
            "{name}: {} vs {want} by hand",
            num(name)
        )
    };
    close("ref_noise_rel_mse", sum_rel / n);
    close("ref_noise_rmse", (sum_sq / n).sqrt());
    close("ref_noise_mean_bias", sum_sq.sqrt() / n);
    // The simulated ones: an exact image's p99 error lies near the typical |noise|, below the max.
    assert!(
        num("ref_noise_p99_abs_error") <= num("ref_noise_max_abs_error")
            && num("ref_noise_p99_abs_error") > 0.5 * num("ref_noise_rmse")
    );
}

/// `capture --supersample N` writes an image of `--size` (the N× render box-filtered down), and
/// refuses a render over the limit with one line before anything is allocated.
#[test]
fn capture_supersamples_to_the_asked_size_and_refuses_huge_factors() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml");
    let (exr, plain) = (common::temp_path("ss-capture.exr"), common::temp_path("ss-plain.exr"));
    ok(&penumbra(&[
        "capture",
        scene,
        "--size",
        "12x8",
        "--supersample",
        "3",
        "--exr",
        exr.to_str().unwrap(),
    ]));
    ok(&penumbra(&[
        "capture",
        scene,
        "--size",
        "12x8",
        "--exr",
        plain.to_str().unwrap(),
    ]));
    let (ss, centre) = (HdrImage::read_exr(&exr).unwrap(), HdrImage::read_exr(&plain).unwrap());
    assert_eq!((ss.width, ss.height), (12, 8));
    assert_ne!(ss.pixels, centre.pixels, "supersampling changes the image");
    for (args, want) in [
        (&["--size", "640x360", "--supersample", "16"][..], "limit"),
        (&["--size", "8x8", "--supersample", "0"][..], "from 1 to 16"),
    ] {
        let mut all = vec!["capture", scene];
        all.extend_from_slice(args);
        let o = penumbra(&all);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && e.contains("--supersample") && e.contains(want) && e.lines().count() == 1,
            "{args:?}: {e}"
        );
    }
}

/// `chart --frame N` judges each configuration's frame N against the reference traced at frame
/// N: under a sun that `[light_motion]` turns 60° by frame 2 (1800°/s), `forward` on an open
/// plane (exact there) scores the reference's own noise at frame 2, where judging its frame 2
/// against the scene as written (frame 0: irradiance twice as high) would be off by a factor 2.
/// The table `capture --max-error` reads stays frame 0's.
#[test]
fn chart_judges_the_asked_frame_against_the_reference_at_that_frame() {
    let dir = common::temp_path("chart-frame");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("turning_sun.toml");
    std::fs::write(
        &scene,
        "methods = [\"forward\"]\n\
         [camera]\nposition = [0, 3, 0.01]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
         [[materials]]\nname = \"grey\"\nalbedo = 0.5\n\
         [[objects]]\nmesh = \"quad\"\nmaterial = \"grey\"\ncorner = [-20, 0, 20]\nedge_u = [40, 0, 0]\nedge_v = [0, 0, -40]\n\
         [[lights]]\ntype = \"directional\"\nname = \"sun\"\ndirection = [0, -1, 0]\nirradiance = 2\n\
         [light_motion]\nlight = \"sun\"\naxis = [0, 0, 1]\ndeg_per_s = 1800\n",
    )
    .unwrap();
    let rel_mse = |frame: &str| {
        let (png, csv) = (
            dir.join(format!("chart{frame}.png")),
            dir.join(format!("chart{frame}.csv")),
        );
        let cache = dir.join("cache");
        let options = [
            "--size",
            "16x16",
            "--reference-spp",
            "64",
            "--frames",
            "1",
            "--frame",
            frame,
        ];
        let stdout = ok(&chart(scene.to_str().unwrap(), &options, &cache, &png, &csv));
        assert_eq!(
            stdout.contains(&format!(", frame {frame}")),
            frame != "0",
            "the comparison names the frame: {stdout}"
        );
        let rows = penumbra::commands::chart::parse_csv(&std::fs::read_to_string(&csv).unwrap()).unwrap();
        rows[0].rel_mse
    };
    let cached_tables = || -> Vec<String> {
        let mut found: Vec<String> = std::fs::read_dir(dir.join("cache"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                name.starts_with("chart-") && name.ends_with(".csv")
            })
            .map(|p| std::fs::read_to_string(p).unwrap())
            .collect();
        found.sort();
        found
    };
    let at_0 = rel_mse("0");
    let frame_0_table = std::fs::read_to_string(dir.join("chart0.csv")).unwrap();
    assert_eq!(
        cached_tables(),
        std::slice::from_ref(&frame_0_table),
        "frame 0's table is cached"
    );
    let at_2 = rel_mse("2");
    println!("forward against the reference: frame 0 {at_0:.2e}, frame 2 {at_2:.2e}");
    // Frame 2 against frame 0 would be (0.5 − 1)² / 1 = 0.25 relative MSE.
    assert!(at_0 < 1e-3 && at_2 < 1e-3, "frame 0 {at_0}, frame 2 {at_2}");
    // `capture --max-error` renders the scene as written: frame 2's chart leaves its table alone.
    assert_eq!(
        cached_tables(),
        [frame_0_table],
        "the cached table for capture --max-error is still frame 0's"
    );
}

/// The CSV's bake columns: every point of a baking method's sweep reports the time and bytes of
/// its set-up (built, or read back from the cache), a method that bakes nothing reports zero.
#[test]
fn chart_csv_reports_bake_time_and_size_where_a_method_bakes() {
    let scene = common::temp_path("bake-chart.toml");
    std::fs::write(&scene, BAKING_SCENE).unwrap();
    let (cache, csv, png) = (
        common::temp_path("bake-chart-cache"),
        common::temp_path("bake-chart.csv"),
        common::temp_path("bake-chart.png"),
    );
    let options = ["--size", "24x24", "--reference-spp", "4", "--frames", "3"];
    ok(&chart(scene.to_str().unwrap(), &options, &cache, &png, &csv));
    let table = std::fs::read_to_string(&csv).unwrap();
    let (methods, ms, bytes) = (
        column(&table, "method"),
        column(&table, "bake_ms"),
        column(&table, "bake_bytes"),
    );
    assert!(
        methods.iter().any(|m| m == "bsp_lights") && methods.iter().any(|m| m == "forward"),
        "{table}"
    );
    for ((method, text), bytes) in methods.iter().zip(&ms).zip(&bytes) {
        let (ms, bytes): (f64, u64) = (text.parse().unwrap(), bytes.parse().unwrap());
        if method == "forward" {
            assert!(
                ms == 0.0 && !text.starts_with('-') && bytes == 0,
                "forward bakes nothing: {text} ms, {bytes} bytes"
            );
        } else {
            assert!(ms > 0.0 && bytes > 0, "{method}: {ms} ms, {bytes} bytes\n{table}");
        }
    }
    assert!(
        methods.iter().filter(|m| *m == "bsp_lights").count() >= 3,
        "the sweep bakes several segmentations: {table}"
    );
}

/// `--bake-limit`: a swept point still baking after the limit is stopped and left out, saying
/// why, while the scene's own configuration bakes as long as it takes; the chart finishes.
#[test]
fn chart_leaves_out_swept_points_whose_bakes_pass_the_limit() {
    let scene = common::temp_path("bake-limit.toml");
    std::fs::write(&scene, BAKING_SCENE).unwrap();
    let (cache, csv, png) = (
        common::temp_path("bake-limit-cache"),
        common::temp_path("bake-limit.csv"),
        common::temp_path("bake-limit.png"),
    );
    let options = [
        "--size",
        "24x24",
        "--reference-spp",
        "4",
        "--frames",
        "3",
        "--bake-limit",
        "0.001",
    ];
    let out = chart(scene.to_str().unwrap(), &options, &cache, &png, &csv);
    ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let table = std::fs::read_to_string(&csv).unwrap();
    let (methods, ms) = (column(&table, "method"), column(&table, "bake_ms"));
    let baked: Vec<f64> = (methods.iter().zip(&ms))
        .filter(|(m, _)| *m == "bsp_lights")
        .map(|(_, ms)| ms.parse().unwrap())
        .collect();
    assert!(
        baked.len() == 1 && baked[0] > 0.0,
        "only the declared configuration, baked in full: {table}"
    );
    assert!(
        stderr.matches("left out: its bake").count() >= 2 && stderr.contains("--bake-limit 0.001 s"),
        "{stderr}"
    );
    let refused = chart(scene.to_str().unwrap(), &["--bake-limit=-1"], &cache, &png, &csv);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && err.contains("--bake-limit -1"), "{err}");
}

const BAKING_SCENE: &str = r#"methods = [{ name = "bsp_lights", max_segment_area = 0.5 }, "forward"]
[camera]
position = [0, 3, 4]
target = [0, 0, 0]
[[materials]]
name = "grey"
albedo = 0.6
[[objects]]
name = "floor"
mesh = "quad"
corner = [-2, 0, 2]
edge_u = [4, 0, 0]
edge_v = [0, 0, -4]
material = "grey"
[[objects]]
name = "block"
mesh = "box"
size = [0.6, 0.6, 0.6]
translate = [0, 0.35, 0]
material = "grey"
[[lights]]
type = "spot"
position = [0.5, 2.5, 0.5]
direction = [0, -1, 0]
intensity = 4
inner_deg = 25
outer_deg = 40
"#;
