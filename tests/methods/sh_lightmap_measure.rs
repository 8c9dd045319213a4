//! What VQ compression of SH light-maps costs (the Ca3D-Engine thesis §5.6.3): PSNR of bare-SHL
//! shading over 64 random directional lights, compressed against native, and the seed storage
//! model's compression ratio. The target (≥ 10× at ≥ 40 dB, 4 bands) is asserted on the
//! courtyard; `psnr_table` (ignored, long) prints docs/results/lavapipe/sh_lightmap_vq_psnr.csv.

use penumbra::lighting::sh_lightmap::{self, config::Config, measure, Rays};
use penumbra::scene::Scene;
use penumbra::util::progress::Progress;

/// The courtyard's transfers at `patch` metres, `bands` bands, direct only (the bounces change
/// the vectors' spread little and cost most of the bake).
fn bake(patch: f64, bands: usize, samples: usize) -> sh_lightmap::Baked {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::from_file(dir.join("sh_courtyard.toml")).unwrap_or_else(|e| panic!("{e}"));
    let geometry = penumbra::lighting::lightmap::geometry::scene_geometry(&scene, "sh_lightmap").unwrap();
    let mut config = Config::defaults(penumbra::lighting::lightmap::solve::Mode::Corrected);
    config.patch_size = patch;
    config.samples = samples;
    config.transfer.bands = bands;
    config.transfer.bounces = false;
    sh_lightmap::bake(&geometry, None, &config, Rays::Cpu, None, &mut Progress::new("bake"))
        .unwrap()
        .0
}

fn quantized_row(baked: &sh_lightmap::Baked, reps: usize) -> measure::Row {
    let dirs = measure::random_directions(64, 7);
    let t = std::time::Instant::now();
    let q = sh_lightmap::quantize(baked, reps, &mut Progress::new("vq")).unwrap();
    measure::row(baked, &q, &dirs, t.elapsed().as_secs_f64(), reps)
}

#[test]
fn ten_times_smaller_at_40_db_with_4_bands() {
    let baked = bake(0.1, 4, 2500);
    let row = quantized_row(&baked, 1024);
    eprintln!("| bands | reps | texels | PSNR dB | ratio | iterations | unused | VQ s |\n{row}");
    assert!(
        row.texels > 16_000,
        "{} texels: too few for the ratio to mean anything",
        row.texels
    );
    assert!(row.ratio >= 10.0, "compression {:.2}×", row.ratio);
    assert!(row.psnr_db >= 40.0, "PSNR {:.1} dB", row.psnr_db);
    // Fewer representatives cost accuracy: the measure sees the codebook.
    let coarse = quantized_row(&baked, 16);
    assert!(
        coarse.psnr_db < row.psnr_db - 6.0,
        "16 representatives {:.1} dB against 1024's {:.1} dB",
        coarse.psnr_db,
        row.psnr_db
    );
}

#[test]
#[ignore = "measurement: several minutes; prints the PSNR table of docs/methods/sh_lightmap.md"]
fn psnr_table() {
    println!(
        "| bands | reps | texels | PSNR dB | ratio | iterations | unused | VQ s |\n|---|---|---|---|---|---|---|---|"
    );
    for bands in [2, 3, 4, 6, 8] {
        let t = std::time::Instant::now();
        let baked = bake(0.1, bands, 10_000);
        println!(
            "bake, {bands} bands: {:.1} s (CPU rays, direct transfer)",
            t.elapsed().as_secs_f64()
        );
        for reps in [1024, 4096, 16384, 65536] {
            println!("{}", quantized_row(&baked, reps));
        }
    }
}

#[test]
#[ignore = "measurement: a few minutes; the large-map rows of docs/methods/sh_lightmap.md (4 bands, 5 cm, S ≈ 87k texels)"]
fn psnr_large_map() {
    let t = std::time::Instant::now();
    let baked = bake(0.05, 4, 2500);
    println!("bake, 4 bands, 5 cm, 2,500 samples: {:.1} s", t.elapsed().as_secs_f64());
    println!(
        "| bands | reps | texels | PSNR dB | ratio | iterations | unused | VQ s |\n|---|---|---|---|---|---|---|---|"
    );
    for reps in [1024, 4096, 16384, 65536] {
        println!("{}", quantized_row(&baked, reps));
    }
}
