//! `chart --camera N` and `report --camera N`: each camera of the scene's assets is measured
//! through, and cached, on its own.

use std::path::{Path, PathBuf};

use base64::Engine as _;

use crate::support as common;

use common::{ok, penumbra};

use penumbra::scene::{Scene, SceneOverrides};
use penumbra::util::image_io::HdrImage;

/// Sun irradiance (W/m²) and the two ground halves' albedos: a Lambertian plane facing the sun
/// has radiance albedo · E / π.
const IRRADIANCE: f32 = 2.0;
const DARK: f32 = 0.2;
const LIGHT: f32 = 0.8;

/// A glTF carrying two cameras 2 m above the ground looking straight down, camera 0 over the
/// dark half (x = −5) and camera 1 over the light half (x = +5), both with a 0.5 rad vertical
/// field (±0.51 m seen at 2 m), and a small quad far off to the side (an asset needs triangles).
fn two_camera_gltf(dir: &Path) -> PathBuf {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let mut bytes = Vec::new();
    for p in [
        [-1.0f32, 0.0, -1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
    ] {
        bytes.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    for _ in 0..4 {
        bytes.extend([0.0f32, 1.0, 0.0].iter().flat_map(|c| c.to_le_bytes()));
    }
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    // Rotated −90° about x: the camera's −z (its view) points down.
    let down = [-h, 0.0, 0.0, h];
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"mesh": 0, "translation": [100.0, 0.0, 0.0]},
            {"camera": 0, "translation": [-5.0, 2.0, 0.0], "rotation": down},
            {"camera": 0, "translation": [5.0, 2.0, 0.0], "rotation": down}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.05}}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "buffers": [{"byteLength": bytes.len(), "uri": uri}]
    });
    let path = dir.join("two_cameras.gltf");
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

/// The scene: the ground's x < 0 half dark, x > 0 half light, under a sun straight above; its
/// own camera looks down on the seam; the asset brings the two cameras.
fn two_camera_scene(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    two_camera_gltf(dir);
    let scene = dir.join("two_cameras.toml");
    std::fs::write(
        &scene,
        format!(
            "methods = [\"forward\"]\n\
             [camera]\nposition = [0, 3, 0.01]\ntarget = [0, 0, 0]\nfov_y_deg = 40\n\
             [[materials]]\nname = \"dark\"\nalbedo = {DARK}\n\
             [[materials]]\nname = \"light\"\nalbedo = {LIGHT}\n\
             [[objects]]\nmesh = \"quad\"\nmaterial = \"dark\"\ncorner = [-20, 0, 20]\nedge_u = [20, 0, 0]\nedge_v = [0, 0, -40]\n\
             [[objects]]\nmesh = \"quad\"\nmaterial = \"light\"\ncorner = [0, 0, 20]\nedge_u = [20, 0, 0]\nedge_v = [0, 0, -40]\n\
             [[objects]]\nname = \"views\"\nmesh = \"asset\"\npath = \"two_cameras.gltf\"\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = {IRRADIANCE}\n"
        ),
    )
    .unwrap();
    scene
}

/// The reference means (not the standard-error images) in the cache, by file name.
fn cached_references(cache: &Path) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(cache)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    found.retain(|p| {
        let name = p.file_name().unwrap().to_string_lossy();
        name.starts_with("reference-") && name.ends_with(".exr") && !name.ends_with(".stderr.exr")
    });
    found.sort();
    found
}

/// Mean radiance over pixels and channels.
fn mean(image: &HdrImage) -> f64 {
    let sum: f64 = image.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum();
    sum / (3 * image.pixels.len()) as f64
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

const SIZE: (u32, u32) = (16, 16);
/// Exactly 16 spp (`--reference-noise 0`), so a cached reference is always taken as it is.
const SWEEP: [&str; 8] = [
    "--size",
    "16x16",
    "--reference-spp",
    "16",
    "--reference-noise",
    "0",
    "--frames",
    "1",
];

/// Each camera of a two-camera glTF gets its own reference, table and metrics in one cache:
/// camera 0 sees the dark half (reference radiance 0.2 · 2/π), camera 1 the light half
/// (0.8 · 2/π), the second camera's chart renders its own reference rather than reusing the
/// first's, the scene's own camera keeps the key it always had, the CSV, the stdout and the
/// report page name the camera, `capture --max-error` reads the chosen camera's table, and a
/// camera the scene lacks is one error line from `chart` and `report`.
#[test]
fn chart_and_report_measure_and_cache_each_camera_on_its_own() {
    let dir = common::temp_path("camera-chart");
    let scene = two_camera_scene(&dir);
    let scene_arg = scene.to_str().unwrap();
    let cache = dir.join("cache");
    let cache_arg = cache.to_str().unwrap();
    let chart = |camera: Option<&str>| {
        let (png, csv) = (
            dir.join(format!("chart-{camera:?}.png")),
            dir.join(format!("chart-{camera:?}.csv")),
        );
        let mut args = vec!["chart", scene_arg, "--cache-dir", cache_arg];
        args.extend(SWEEP);
        let (png_arg, csv_arg) = (png.to_str().unwrap(), csv.to_str().unwrap());
        args.extend(["-o", png_arg, "--csv", csv_arg]);
        if let Some(n) = camera {
            args.extend(["--camera", n]);
        }
        let o = penumbra(&args);
        let stdout = ok(&o);
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        (stdout, stderr, std::fs::read_to_string(&csv).unwrap())
    };
    let expected = |albedo: f32| f64::from(albedo * IRRADIANCE / std::f32::consts::PI);

    // Camera 0, into an empty cache.
    let (out0, err0, csv0) = chart(Some("0"));
    assert!(err0.contains("rendering the reference"), "{err0}");
    assert!(out0.contains(", camera 0"), "stdout names the camera: {out0}");
    assert_eq!(column(&csv0, "camera"), ["0"], "{csv0}");
    let refs = cached_references(&cache);
    assert_eq!(refs.len(), 1, "{refs:?}");
    let dark = mean(&HdrImage::read_exr(&refs[0]).unwrap());
    assert!(
        (dark / expected(DARK) - 1.0).abs() < 0.02,
        "camera 0's reference: {dark}"
    );

    // Camera 1, same cache: its own reference, not camera 0's.
    let (out1, err1, csv1) = chart(Some("1"));
    assert!(
        err1.contains("rendering the reference"),
        "camera 1 must not reuse camera 0's reference: {err1}"
    );
    assert!(out1.contains(", camera 1"), "{out1}");
    assert_eq!(column(&csv1, "camera"), ["1"], "{csv1}");
    let after = cached_references(&cache);
    assert_eq!(after.len(), 2, "one reference per camera: {after:?}");
    let new: Vec<&PathBuf> = after.iter().filter(|p| !refs.contains(p)).collect();
    let light = mean(&HdrImage::read_exr(new[0]).unwrap());
    assert!(
        (light / expected(LIGHT) - 1.0).abs() < 0.02,
        "camera 1's reference: {light}"
    );
    println!(
        "reference means: camera 0 {dark:.5} (expected {:.5}), camera 1 {light:.5} (expected {:.5})",
        expected(DARK),
        expected(LIGHT)
    );
    // Each camera's image judged against its own reference: forward is exact for a sunlit
    // plane, where against the other camera's reference the relative MSE would be about 5.6
    // ((0.51 − 0.13)² / (0.13² + 0.01)).
    for table in [&csv0, &csv1] {
        let rel: f64 = column(table, "rel_mse")[0].parse().unwrap();
        assert!(rel < 1e-3, "forward against its camera's reference: {rel}\n{table}");
    }

    // The chart tables `capture --max-error` reads are each camera's own, and the scene's own
    // camera keeps the key it had before cameras could be chosen (the parsed scene unchanged).
    let table_of = |camera: Option<usize>| {
        let mut s = Scene::from_file(&scene).unwrap();
        let overrides = SceneOverrides {
            camera,
            ..Default::default()
        };
        overrides.apply(&mut s).unwrap();
        penumbra::commands::chart::cached_table(&s, SIZE, &cache)
    };
    assert!(table_of(Some(0)).exists() && table_of(Some(1)).exists());
    assert_ne!(table_of(Some(0)), table_of(Some(1)));
    assert!(!table_of(None).exists());
    let (out, err, csv) = chart(None);
    assert!(err.contains("rendering the reference"), "{err}");
    assert!(!out.contains(", camera"), "{out}");
    assert_eq!(column(&csv, "camera"), ["scene"], "{csv}");
    assert!(table_of(None).exists());
    assert_eq!(cached_references(&cache).len(), 3);

    // capture --max-error through camera 1 reads camera 1's table.
    let shot = dir.join("shot.png");
    let o = ok(&penumbra(&[
        "capture",
        scene_arg,
        "--size",
        "16x16",
        "--camera",
        "1",
        "--max-error",
        "0.01",
        "--cache-dir",
        cache_arg,
        "-o",
        shot.to_str().unwrap(),
    ]));
    assert!(o.contains("picked `forward`"), "{o}");
    let o = penumbra(&[
        "capture",
        scene_arg,
        "--size",
        "8x8",
        "--camera",
        "1",
        "--max-error",
        "0.01",
        "--cache-dir",
        cache_arg,
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--camera 1 --size 8x8"), "says what to run: {e}");

    // The report through camera 1: camera 1's cached reference, and the page names the camera.
    let report = dir.join("report");
    let mut args = vec![
        "report",
        scene_arg,
        "--cache-dir",
        cache_arg,
        "--camera",
        "1",
        "-o",
        report.to_str().unwrap(),
    ];
    args.extend(SWEEP);
    let o = penumbra(&args);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("rendering the reference"), "camera 1's is cached: {err}");
    let page = std::fs::read_to_string(report.join("two_cameras.html")).unwrap();
    assert!(
        page.contains("camera: camera 1 of the scene&#39;s assets (--camera 1)"),
        "the page names the camera"
    );
    let index = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(index.contains("two_cameras.toml, camera 1"), "{index}");
    let table = std::fs::read_to_string(report.join("two_cameras").join("chart.csv")).unwrap();
    assert_eq!(column(&table, "camera"), ["1"]);
    assert_eq!(
        column(&table, "rel_mse"),
        column(&csv1, "rel_mse"),
        "the same reference as chart's"
    );

    // A camera the scene lacks: one line, from either command.
    let lacks = "two_cameras.toml: cameras: --camera 2 asked for, the scene's assets carry 2 (--camera 0 to 1)";
    let o = penumbra(&["chart", scene_arg, "--camera", "2", "--cache-dir", cache_arg]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains(lacks), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    let o = penumbra(&["report", scene_arg, "--camera", "2", "-o", report.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains(lacks), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
}
