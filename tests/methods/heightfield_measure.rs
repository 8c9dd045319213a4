//! Measurements of the height-field methods (the height-field thesis) and the generator of the committed teddy
//! relief. The measurements are long and `#[ignore]`d; run them one at a time with
//! `cargo test --release --test methods -- --ignored --nocapture heightfield_measure::<name>`; each prints
//! its table and writes it under `target/heightfield-measure/`.

use std::fmt::Write as _;

use penumbra::backend::Gpu;
use penumbra::commands::profile::summarise;
use penumbra::lighting::heightfield::measure::{self, brute_cost_at, temporal_stability, Point};
use penumbra::lighting::heightfield::standalone::Standalone;
use penumbra::scene::{MethodDecl, Scene};

/// The teddy bear of the seed's static scenes, as a bas-relief: ellipsoids (centre, radii,
/// height) in [-1, 1]², heights their upper surfaces, max-combined, in [0, 1].
pub fn teddy(res: u32) -> Vec<f32> {
    // (cx, cy, rx, ry, top) with y pointing to +z (the image's rows).
    const BLOBS: [(f32, f32, f32, f32, f32); 11] = [
        (0.0, 0.12, 0.42, 0.5, 0.75),    // body
        (0.0, -0.5, 0.3, 0.28, 0.85),    // head
        (-0.26, -0.74, 0.12, 0.12, 0.6), // ears
        (0.26, -0.74, 0.12, 0.12, 0.6),
        (0.0, -0.4, 0.11, 0.09, 1.0),   // snout
        (-0.45, 0.0, 0.13, 0.26, 0.55), // arms
        (0.45, 0.0, 0.13, 0.26, 0.55),
        (-0.24, 0.62, 0.17, 0.17, 0.5), // legs
        (0.24, 0.62, 0.17, 0.17, 0.5),
        (-0.1, -0.55, 0.04, 0.04, 0.95), // eyes
        (0.1, -0.55, 0.04, 0.04, 0.95),
    ];
    let mut out = vec![0.0f32; (res * res) as usize];
    for j in 0..res {
        for i in 0..res {
            let x = 2.0 * (i as f32 + 0.5) / res as f32 - 1.0;
            let y = 2.0 * (j as f32 + 0.5) / res as f32 - 1.0;
            let mut h = 0.0f32;
            for (cx, cy, rx, ry, top) in BLOBS {
                let q = 1.0 - ((x - cx) / rx).powi(2) - ((y - cy) / ry).powi(2);
                if q > 0.0 {
                    h = h.max(top * q.sqrt());
                }
            }
            out[(j * res + i) as usize] = h;
        }
    }
    out
}

const TEDDY: &str = "scenes/terrain/teddy.png";

/// Writes `scenes/terrain/teddy.png` (128², 16-bit).
#[test]
#[ignore]
fn generate_teddy_asset() {
    let data: Vec<u16> = teddy(128).iter().map(|v| (v * 65535.0).round() as u16).collect();
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(128, 128, data)
        .unwrap()
        .save(TEDDY)
        .unwrap();
}

/// The committed relief is what `teddy` generates.
#[test]
fn teddy_asset_is_reproducible() {
    let img = image::open(TEDDY).expect("scenes/terrain/teddy.png").to_luma16();
    let want = teddy(128);
    for (p, w) in img.pixels().zip(&want) {
        assert_eq!(p.0[0], (w * 65535.0).round() as u16);
    }
}

fn out_dir() -> std::path::PathBuf {
    let d = std::env::var_os("PENUMBRA_MEASURE_OUT")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/heightfield-measure"));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn record(name: &str, text: &str) {
    println!("{text}");
    std::fs::write(out_dir().join(name), text).unwrap();
}

/// Lavapipe (or PENUMBRA_MEASURE_DEVICE) without validation: timings, not checks.
fn measure_gpu() -> penumbra::backend::GpuDesc {
    penumbra::backend::GpuDesc {
        validation: false,
        device_name: Some(std::env::var("PENUMBRA_MEASURE_DEVICE").unwrap_or_else(|_| "llvmpipe".into())),
        display: None,
    }
}

fn decl(name: &str, params: &[(&str, toml::Value)]) -> MethodDecl {
    MethodDecl {
        name: name.into(),
        line: 0,
        params: params.iter().map(|(k, v)| (k.to_string(), v.clone(), 0)).collect(),
    }
}

const TERRAIN: [&str; 7] = ["cones", "sine", "mountains", "eggtray", "city", "teddy", "sky"];

/// Cost of every pass (the height-field thesis Table 6.6 layout) at 256², 512² and 1024² on the cones scene
/// (environment + one sphere light), pyramid at the thesis's settings (ls = 4, lo = 4, nφ = 32,
/// 4 bands) and brute force (1-texel steps; 0.5 at 256²).
#[test]
#[ignore]
fn cost_by_resolution() {
    let scene = Scene::from_file("scenes/terrain_cones.toml").unwrap();
    let mut text = String::from("| resolution | method | height update | pyramid (bounds) | environment | light 1 | accumulate | total compute |\n|---|---|---|---|---|---|---|---|\n");
    let configs: Vec<(u32, MethodDecl)> = vec![
        (256, decl("heightfield_pyramid", &[("resolution", 256.into())])),
        (
            256,
            decl(
                "heightfield_bruteforce",
                &[("resolution", 256.into()), ("march_step", 0.5.into())],
            ),
        ),
        (512, decl("heightfield_pyramid", &[("resolution", 512.into())])),
        (
            512,
            decl(
                "heightfield_bruteforce",
                &[("resolution", 512.into()), ("march_step", 1.0.into())],
            ),
        ),
        (1024, decl("heightfield_pyramid", &[("resolution", 1024.into())])),
    ];
    let frames: usize = std::env::var("HF_MEASURE_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    for (res, d) in configs {
        let mut h = Standalone::new(Gpu::new(&measure_gpu()).unwrap(), &scene, &d).unwrap();
        h.profile(0.0, 1).unwrap(); // warm-up
        let stats = summarise(&h.profile(0.0, frames).unwrap());
        let get =
            |pred: &dyn Fn(&str) -> bool| stats.iter().filter(|p| pred(&p.name)).map(|p| p.median_ms).sum::<f64>();
        let pyr = get(&|n| n.starts_with("hf pyramid") || n == "hf bounds");
        let total = get(&|n| n.starts_with("hf "));
        let row = format!(
            "| {res}² | {} | {:.1} | {pyr:.1} | {:.1} | {:.1} | {:.1} | {total:.1} |\n",
            d.name,
            get(&|n| n == "hf height update"),
            get(&|n| n == "hf environment" || n.starts_with("hf environment SH")),
            get(&|n| n == "hf light 1"),
            get(&|n| n == "hf accumulate"),
        );
        print!("{row}");
        text += &row;
        if let Some(t) = measure::table_6_6(&stats) {
            println!("{t}");
        }
    }
    let dev = Gpu::new(&measure_gpu()).unwrap().caps().name.clone();
    record(
        "cost_by_resolution.md",
        &format!("{dev}, ms per frame (medians of {frames} frames after one warm-up):\n\n{text}"),
    );
}

/// Frame-to-frame change of the shading under a slowly moving cone (a quarter texel per frame)
/// for lo ∈ {0, 2, 4}, and the brute force (0.25-texel steps) for the change the motion itself
/// causes.
#[test]
#[ignore]
fn stability_against_lo() {
    let scene = Scene::from_file("scenes/terrain_cone_moving.toml").unwrap();
    // The cone moves at 0.02 rad/s on a 1.5 m circle: 0.03 m/s; a quarter texel (8/128 m) per
    // frame is dt = 0.52 s.
    let dt = 0.25 * 8.0 / 128.0 / 0.03;
    let frames: usize = std::env::var("HF_MEASURE_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(24);
    let mut text = format!("temporal stability, {frames} frames, the cone moving 0.25 texel per frame; |Δ| of the shading luminance per texel (unit: the shading image, exit radiance over albedo)\n\n| method | mean |Δ| | p99 |Δ| | mean |Δ²| | p99 |Δ²| |\n|---|---|---|---|---|\n");
    let mut configs: Vec<(String, MethodDecl)> = [0.0f64, 2.0, 4.0]
        .iter()
        .map(|lo| {
            (
                format!("pyramid lo = {lo}"),
                decl("heightfield_pyramid", &[("lo", (*lo).into())]),
            )
        })
        .collect();
    configs.push((
        "brute force, 0.25-texel steps".into(),
        decl("heightfield_bruteforce", &[("march_step", 0.25.into())]),
    ));
    for (label, d) in configs {
        let s = temporal_stability(&measure_gpu(), &scene, &d, frames, dt as f32).unwrap();
        let row = format!(
            "| {label} | {:.3e} | {:.3e} | {:.3e} | {:.3e} |\n",
            s.mean, s.p99, s.mean_second, s.p99_second
        );
        print!("{row}");
        text += &row;
    }
    record("stability.md", &text);
}

/// `penumbra chart` on every terrain scene (128×128 image, the chart's reference at 1024 spp),
/// then, per scene, the pyramid's speed-up over the brute force at equal relative MSE: the brute
/// force's cost at the pyramid configuration's error, interpolated log–log along the brute
/// force's Pareto front, over the pyramid's cost (whole GPU frame).
#[test]
#[ignore]
fn chart_and_speedup_at_equal_error() {
    let spp: u32 = std::env::var("HF_MEASURE_SPP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1024);
    let frames: usize = std::env::var("HF_MEASURE_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let only: Option<String> = std::env::var("HF_MEASURE_SCENE").ok();
    let mut summary = String::from("| scene | pyramid config | rel MSE | frame ms | brute ms at that error | speed-up |\n|---|---|---|---|---|---|\n");
    let mut table66 =
        String::from("| scene | pyramid | env. light | L-light 1 | (thesis defaults, ms) |\n|---|---|---|---|---|\n");
    for name in TERRAIN {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let path = std::path::PathBuf::from(format!("scenes/terrain_{name}.toml"));
        let opts = penumbra::commands::chart::ChartOptions {
            scene: path,
            size: (128, 128),
            frames,
            // Every frame, as this measurement was made.
            timing_budget_s: 0.0,
            bake_limit_s: 0.0,
            reference_spp: spp,
            // Exactly `spp` samples, as this measurement was made.
            reference_noise: 0.0,
            // Independent samples, as this measurement was made.
            reference_sampler: penumbra::reference::Sampler::Independent,
            supersample: 1,
            png: Some(out_dir().join(format!("chart_{name}.png"))),
            csv: Some(out_dir().join(format!("chart_{name}.csv"))),
            cache_dir: out_dir().join("cache"),
            gpu: measure_gpu(),
            methods: Vec::new(),
            frame: 0,
            camera: None,
        };
        let chart = penumbra::commands::chart::run(&opts).unwrap();
        let points = |m: &str| -> Vec<Point> {
            chart
                .rows
                .iter()
                .filter(|r| r.method == m)
                .map(|r| Point {
                    method: r.method.clone(),
                    config: r.config.clone(),
                    ms: r.frame_ms,
                    error: r.metrics.rel_mse,
                })
                .collect()
        };
        let (pyr, brute) = (points("heightfield_pyramid"), points("heightfield_bruteforce"));
        for p in &pyr {
            let b = brute_cost_at(&brute, p.error);
            let (bs, sp) = match b {
                Some(b) => (format!("{b:.1}"), format!("{:.1}×", b / p.ms)),
                None => ("outside the brute force's range".into(), "—".into()),
            };
            let _ = writeln!(
                summary,
                "| {name} | {} | {:.5} | {:.1} | {bs} | {sp} |",
                p.config, p.error, p.ms
            );
        }
        if let Some(r) = chart.rows.iter().find(|r| r.method == "heightfield_pyramid") {
            let get =
                |pred: &dyn Fn(&str) -> bool| r.passes.iter().filter(|(n, _)| pred(n)).map(|(_, ms)| ms).sum::<f64>();
            let _ = writeln!(
                table66,
                "| {name} | {:.1} | {:.1} | {:.1} | {} |",
                get(&|n| n.starts_with("hf pyramid")),
                get(&|n| n == "hf environment" || n.starts_with("hf environment SH")),
                get(&|n| n == "hf light 1"),
                r.config
            );
        }
        for r in &chart.rows {
            println!(
                "{name}: {:<44} {:>9.1} ms  rel MSE {:.5}  FLIP {:.4}",
                r.config, r.frame_ms, r.metrics.rel_mse, r.metrics.flip_mean
            );
        }
        record(
            &format!("speedup_{}.md", only.as_deref().unwrap_or("all")),
            &format!("{summary}\n{table66}"),
        );
    }
}

/// Speed-up at equal horizon error, at 256² (`HF_MEASURE_RESOLUTIONS=256,512,1024` for more;
/// `HF_MEASURE_512=1` adds 512²): every texel's
/// horizon in every direction of the mountains and city fields; the truth is the brute force at
/// 0.125-texel steps; the error is the mean |Δ| in degrees; the cost is the GPU time of the
/// horizons alone (the horizon kernel plus the pyramid or bounds it reads), since the
/// visibility and product work after it is the same for both. The brute force's cost at
/// the pyramid's error is interpolated log–log between its march steps.
#[test]
#[ignore]
fn speedup_at_equal_horizon_error() {
    let mut resolutions = crate::support::env_list("HF_MEASURE_RESOLUTIONS", &[256u32]);
    if std::env::var("HF_MEASURE_512").is_ok() && !resolutions.contains(&512) {
        resolutions.push(512);
    }
    let mut text = String::from("| field | resolution | configuration | horizon MAE (°) | bias (°) | horizon ms (kernel + pyramid/bounds) |\n|---|---|---|---|---|---|\n");
    let mut summary = String::new();
    for name in ["mountains", "city"] {
        let scene = Scene::from_file(format!("scenes/terrain_{name}.toml")).unwrap();
        for &res in &resolutions {
            // The cost of the horizons alone: the horizon kernel ("hf horizons", every direction
            // of every texel, nothing else) plus what it needs built first (the pyramid's levels,
            // the brute force's bounds); medians over 3 frames after one warm-up.
            let run = |d: &MethodDecl| -> (Vec<f32>, f64) {
                let mut h = Standalone::new(Gpu::new(&measure_gpu()).unwrap(), &scene, d).unwrap();
                let horizons = h.horizons(0.0, None).unwrap();
                let mut costs: Vec<f64> = (0..3)
                    .map(|_| {
                        let (_, timings) = h.horizons_timed(0.0, None).unwrap();
                        timings
                            .iter()
                            .filter(|p| {
                                p.name == "hf horizons" || p.name.starts_with("hf pyramid") || p.name == "hf bounds"
                            })
                            .map(|p| p.ms)
                            .sum()
                    })
                    .collect();
                costs.sort_by(f64::total_cmp);
                (horizons, costs[1])
            };
            let r = |v: u32| ("resolution", toml::Value::from(v as i64));
            let (truth, truth_ms) = run(&decl("heightfield_bruteforce", &[r(res), ("march_step", 0.125.into())]));
            let err = |h: &[f32]| -> (f64, f64) {
                let n = h.len() as f64;
                let d: Vec<f64> = h.iter().zip(&truth).map(|(a, b)| (a - b).to_degrees() as f64).collect();
                (d.iter().map(|x| x.abs()).sum::<f64>() / n, d.iter().sum::<f64>() / n)
            };
            let _ = writeln!(
                text,
                "| {name} | {res}² | brute force, 0.125-texel steps (truth) | 0 | 0 | {truth_ms:.1} |"
            );
            let (pyr, pyr_ms) = run(&decl("heightfield_pyramid", &[r(res)]));
            let (pyr_mae, pyr_bias) = err(&pyr);
            let _ = writeln!(
                text,
                "| {name} | {res}² | pyramid ls = 4, lo = 4 | {pyr_mae:.3} | {pyr_bias:.3} | {pyr_ms:.1} |"
            );
            let mut brute = Vec::new();
            for step in [16.0f64, 8.0, 4.0, 2.0, 1.0, 0.5] {
                let (b, ms) = run(&decl("heightfield_bruteforce", &[r(res), ("march_step", step.into())]));
                let (mae, bias) = err(&b);
                let _ = writeln!(
                    text,
                    "| {name} | {res}² | brute force, {step}-texel steps | {mae:.3} | {bias:.3} | {ms:.1} |"
                );
                brute.push(Point {
                    method: "brute".into(),
                    config: format!("{step}"),
                    ms,
                    error: mae,
                });
            }
            let line = match brute_cost_at(&brute, pyr_mae) {
                Some(b) => format!("{name} {res}²: pyramid MAE {pyr_mae:.3}° in {pyr_ms:.1} ms; brute force at that error {b:.1} ms: speed-up {:.2}×\n", b / pyr_ms),
                None => {
                    let cheapest = &brute[0];
                    if pyr_mae >= cheapest.error {
                        format!("{name} {res}²: pyramid MAE {pyr_mae:.3}° in {pyr_ms:.1} ms; the brute force's cheapest run ({}-texel steps) is already more accurate ({:.3}°) in {:.1} ms: speed-up ≤ {:.2}×\n", cheapest.config, cheapest.error, cheapest.ms, cheapest.ms / pyr_ms)
                    } else {
                        format!("{name} {res}²: pyramid MAE {pyr_mae:.3}° in {pyr_ms:.1} ms; more accurate than every brute-force run measured\n")
                    }
                }
            };
            print!("{line}");
            summary += &line;
            record("speedup_horizon.md", &format!("{text}\n{summary}"));
        }
    }
}
