//! CaSHL's visibility bits on the GPU (src/lighting/sh_lightmap/gpu.rs) against the CPU's
//! (transfer::visibility_cpu): the same bits but for a tiny share of rays that the last bit of
//! fp32 arithmetic decides (measured: rays into the open box's corner edges, through the seam
//! of two walls; grazing directions, fp32 against fp64 direction tests), the same transfer
//! within noise, and on its own the open box's view factor (tests.rs in the module, test E).

use crate::support as common;

use glam::DVec3;
use penumbra::backend::Gpu;
use penumbra::lighting::lightmap::patches::{Patches, Triangle};
use penumbra::lighting::lightmap::solve::{self, Mode, Occluders};
use penumbra::lighting::sh_lightmap::gpu::visibility_gpu;
use penumbra::lighting::sh_lightmap::samples::SampleSet;
use penumbra::lighting::sh_lightmap::transfer::{self, Settings};
use penumbra::sh;
use penumbra::shaders::ShaderLibrary;
use penumbra::util::progress::Progress;

/// A quad `o + s·u + t·v` (s, t ∈ [0, 1]) as two triangles facing `u × v`.
fn quad(o: DVec3, u: DVec3, v: DVec3, object: usize, albedo: f64) -> [Triangle; 2] {
    let t = |p| Triangle {
        p,
        object,
        albedo: DVec3::splat(albedo),
        emission: DVec3::ZERO,
        sky: false,
        part: 0,
    };
    [t([o, o + u, o + u + v]), t([o, o + u + v, o + v])]
}

/// The open box of tests.rs: floor w = 2 centred on a patch centre, walls h = 1, no lid.
fn open_box(albedo: f64) -> Vec<Triangle> {
    let (lo, w, h) = (DVec3::new(-0.875, 0.0, -0.875), 2.0, 1.0);
    let (x, y, z) = (DVec3::X * w, DVec3::Y * h, DVec3::Z * w);
    let mut tris = quad(lo, z, x, 0, albedo).to_vec();
    tris.extend(quad(lo, y, z, 1, albedo));
    tris.extend(quad(lo + x, z, y, 2, albedo));
    tris.extend(quad(lo, x, y, 3, albedo));
    tris.extend(quad(lo + z, y, x, 4, albedo));
    let centre = lo + (x + z) * 0.5 + y * 0.5;
    for t in &mut tris {
        if t.normal().dot(centre - t.p[0]) < 0.0 {
            t.p.swap(1, 2);
        }
    }
    tris
}

/// The open box with a sky surface over half its opening (a lid at y = 1.5 over x < 0.125,
/// facing down) and a grey panel leaning inside it, which shades part of the floor and the
/// walls and is patched too.
fn box_with_sky() -> Vec<Triangle> {
    let mut tris = open_box(0.5);
    let panel = quad(
        DVec3::new(-0.5, 0.3, -0.5),
        DVec3::new(0.0, 0.2, 0.8),
        DVec3::new(0.8, 0.0, 0.0),
        5,
        0.5,
    );
    tris.extend(panel);
    let mut lid = quad(
        DVec3::new(-1.2, 1.5, -1.2),
        DVec3::new(1.325, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 2.4),
        6,
        0.0,
    );
    for t in &mut lid {
        t.sky = true;
    }
    tris.extend(lid);
    tris
}

fn gpu_bits(gpu: &mut Gpu, p: &Patches, tris: &[Triangle], samples: &SampleSet, mode: Mode) -> Vec<u32> {
    // Every update the bake sends, in order: its rate must count from the rays' start, so the
    // first says none done of them all (after the set-up, before the first chunk).
    let updates = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let seen = updates.clone();
    penumbra::util::progress::observe_this_thread(Some(std::sync::Arc::new(
        move |u: &penumbra::util::progress::Update| seen.lock().unwrap().push((u.done, u.total)),
    )));
    let bits = visibility_gpu(
        gpu,
        &ShaderLibrary::Embedded,
        p,
        tris,
        samples,
        mode,
        &mut Progress::new("test"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    penumbra::util::progress::observe_this_thread(None);
    // (Progress says (0, 0) when it is made, before the work knows its size.)
    let updates: Vec<(u64, u64)> = updates.lock().unwrap().iter().copied().filter(|u| u.1 > 0).collect();
    let total = updates.last().expect("progress updates").1;
    assert!(
        updates.first() == Some(&(0, total)) && updates[1..].iter().all(|u| u.0 > 0),
        "the first update is none done, and only the first: {updates:?}"
    );
    common::assert_clean(gpu);
    bits
}

fn settings(mode: Mode, bands: usize, bounces: bool) -> Settings {
    Settings {
        solve: solve::Settings {
            mode,
            threshold: 1e-4,
            ..solve::Settings::default()
        },
        bands,
        bounces,
        tone: false,
    }
}

/// SH radiance coefficients of a constant sky L₀ = 1.
fn constant_sky(bands: usize) -> Vec<f64> {
    let mut c = vec![0.0; bands * bands];
    c[0] = sh::CONSTANT_ONE_C00;
    c
}

/// The share of bits of the inside patches that differ, and how many bits are set in each.
fn differing(p: &Patches, samples: &SampleSet, a: &[u32], b: &[u32]) -> (f64, u64, u64) {
    let words = samples.len().div_ceil(32);
    let (mut diff, mut all) = (0u64, 0u64);
    for (k, q) in p.patches.iter().enumerate() {
        let row = k * words..(k + 1) * words;
        if q.inside() {
            diff += a[row.clone()]
                .iter()
                .zip(&b[row])
                .map(|(x, y)| (x ^ y).count_ones() as u64)
                .sum::<u64>();
            all += samples.len() as u64;
        } else {
            assert!(
                a[row.clone()].iter().chain(&b[row]).all(|&w| w == 0),
                "border patch {k} has bits"
            );
        }
    }
    let ones = |v: &[u32]| v.iter().map(|w| w.count_ones() as u64).sum::<u64>();
    (diff as f64 / all as f64, ones(a), ones(b))
}

/// The largest difference of shaded transfer under a constant sky, relative to the largest value.
fn shaded_difference(p: &Patches, a: &[f64], b: &[f64], bands: usize) -> f64 {
    let dim = bands * bands;
    let light = constant_sky(bands);
    let inside = (0..p.patches.len()).filter(|&k| p.patches[k].inside());
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for k in inside {
        let (x, y) = (
            transfer::shade(&a[k * dim..(k + 1) * dim], &light),
            transfer::shade(&b[k * dim..(k + 1) * dim], &light),
        );
        worst = worst.max((x - y).abs());
        largest = largest.max(x.abs());
    }
    worst / largest
}

/// GPU against CPU bits, and the transfers baked from each, on `tris` in `mode`.
fn compare(gpu: &mut Gpu, name: &str, tris: &[Triangle], size: f64, mode: Mode) -> (Patches, Vec<u32>) {
    let bands = 4;
    let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
    let p = Patches::build(tris, size);
    let occ = Occluders::new(tris);
    let cpu = transfer::visibility_cpu(&p, &occ, &samples, mode, &mut Progress::new("test"));
    let on_gpu = gpu_bits(gpu, &p, tris, &samples, mode);
    assert_eq!(cpu.len(), on_gpu.len());
    let (share, cpu_ones, gpu_ones) = differing(&p, &samples, &cpu, &on_gpu);
    let s = settings(mode, bands, true);
    let a = transfer::bake(&p, &occ, &samples, &cpu, &s, &mut Progress::new("test"));
    let b = transfer::bake(&p, &occ, &samples, &on_gpu, &s, &mut Progress::new("test"));
    let shaded = shaded_difference(&p, &a.coeffs, &b.coeffs, bands);
    eprintln!("{name} ({mode:?}): {share:.2e} of the bits differ (set: cpu {cpu_ones}, gpu {gpu_ones}); shaded transfer differs by {shaded:.2e} of its largest value");
    assert!(cpu_ones > 0, "{name}: the CPU sees no sky at all");
    assert!(share <= 1e-3, "{name} ({mode:?}): {share} of the bits differ");
    assert!(
        shaded < 1e-3,
        "{name} ({mode:?}): the shaded transfer differs by {shaded}"
    );
    (p, on_gpu)
}

#[test]
fn gpu_visibility_matches_the_cpu_on_the_open_box() {
    let mut gpu = common::test_gpu();
    let tris = open_box(0.5);
    for mode in [Mode::Corrected, Mode::Faithful] {
        compare(&mut gpu, "open box", &tris, 0.25, mode);
    }
}

#[test]
fn gpu_visibility_matches_the_cpu_with_a_sky_surface() {
    let mut gpu = common::test_gpu();
    let tris = box_with_sky();
    let (p, faithful) = compare(&mut gpu, "box with a sky lid", &tris, 0.25, Mode::Faithful);
    let (_, corrected) = compare(&mut gpu, "box with a sky lid", &tris, 0.25, Mode::Corrected);
    // Faithful: only rays that hit the lid count; corrected: the escaping ones too. Both see some
    // sky, and faithful strictly less.
    let ones = |v: &[u32]| v.iter().map(|w| w.count_ones() as u64).sum::<u64>();
    assert!(
        ones(&faithful) > 0 && ones(&faithful) < ones(&corrected),
        "faithful {} corrected {}",
        ones(&faithful),
        ones(&corrected)
    );
    assert!(
        faithful.iter().zip(&corrected).all(|(f, c)| f & !c == 0),
        "a ray reaches the sky in faithful mode only"
    );
    assert!(p.patches.iter().filter(|q| q.inside()).count() > 100);
}

#[test]
fn the_gpu_open_box_floor_sees_the_opening_view_factor() {
    // F = 4·F_corner(1, 1) for w = 2, h = 1 (tests.rs, test E): 0.554126.
    let corner = |a: f64, b: f64| {
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
    };
    let f = 4.0 * corner(1.0, 1.0);
    assert!((f - 0.554126).abs() < 1e-6, "{f}");
    let mut gpu = common::test_gpu();
    let bands = 4;
    let samples = SampleSet::new(10_000, bands).unwrap_or_else(|e| panic!("{e}"));
    let tris = open_box(0.5);
    let p = Patches::build(&tris, 0.25);
    let bits = gpu_bits(&mut gpu, &p, &tris, &samples, Mode::Corrected);
    let k = (0..p.patches.len())
        .filter(|&k| p.patches[k].inside())
        .min_by(|&a, &b| {
            (p.patches[a].centre - DVec3::new(0.125, 0.0, 0.125))
                .length()
                .total_cmp(&(p.patches[b].centre - DVec3::new(0.125, 0.0, 0.125)).length())
        })
        .unwrap_or(0);
    assert!((p.patches[k].centre - DVec3::new(0.125, 0.0, 0.125)).length() < 1e-9);
    // The direct transfer from the GPU bits alone: (1/π)·Σ cos·y·4π/N, shaded with L = 1.
    let direct = transfer::project(&p, &samples, &bits);
    let dim = bands * bands;
    let e = transfer::shade(&direct[k * dim..(k + 1) * dim], &constant_sky(bands)) / std::f64::consts::PI;
    eprintln!("GPU floor-centre view factor {e:.6}, want {f:.6}");
    assert!((e / f - 1.0).abs() < 0.01, "{e} want {f}");
}

/// A floor under 5,000 long slivers that rarely stop a ray but whose boxes all overlap, and a sky
/// lid (so the closest hit decides): a ray walks thousands of BVH nodes, beyond what llvmpipe
/// lets an invocation loop for 32 rays (measured: 4 rays per invocation, 8 lanes a word), so the
/// GPU path has to retry its chunks with more lanes per word to give the CPU's bits.
#[test]
fn gpu_visibility_matches_the_cpu_through_a_deep_bvh() {
    let mut tris = quad(
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(2.0, 0.0, 0.0),
        0,
        0.5,
    )
    .to_vec();
    let mut lid = quad(
        DVec3::new(-3.0, 3.0, -3.0),
        DVec3::new(6.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 6.0),
        1,
        0.0,
    );
    for t in &mut lid {
        t.sky = true;
    }
    tris.extend(lid);
    let mut random = common::xorshift(0x853c_49e6_748f_ea9b);
    for _ in 0..5000 {
        let mut point = || DVec3::new(random() * 4.0 - 2.0, 0.5 + random() * 2.0, random() * 4.0 - 2.0);
        let (a, b) = (point(), point());
        tris.push(Triangle {
            p: [a, b, a + DVec3::new(1e-3, 1e-3, 0.0)],
            object: 2,
            albedo: DVec3::splat(0.5),
            emission: DVec3::ZERO,
            sky: false,
            part: 0,
        });
    }
    let samples = SampleSet::new(2500, 2).unwrap_or_else(|e| panic!("{e}"));
    // Only the floor is patched; everything occludes.
    let p = Patches::build(&tris[..2], 0.5);
    let occ = Occluders::new(&tris);
    let mut gpu = common::test_gpu();
    let cpu = transfer::visibility_cpu(&p, &occ, &samples, Mode::Faithful, &mut Progress::new("test"));
    let on_gpu = gpu_bits(&mut gpu, &p, &tris, &samples, Mode::Faithful);
    let (share, cpu_ones, gpu_ones) = differing(&p, &samples, &cpu, &on_gpu);
    eprintln!("deep BVH: {share:.2e} of the bits differ (set: cpu {cpu_ones}, gpu {gpu_ones})");
    assert!(
        cpu_ones > 0 && share <= 1e-3,
        "{share} of the bits differ (set: cpu {cpu_ones}, gpu {gpu_ones})"
    );
}

/// CPU against GPU visibility rays per second on the open box at patch 0.05 (10,000 samples),
/// median of 3: `cargo test --release --test methods -- --ignored --nocapture sh_lightmap_gpu::`.
/// `PENUMBRA_MEASURE_DEVICE` picks the device (no validation layer); `SH_MEASURE_PATCH` and
/// `SH_MEASURE_SAMPLES` shrink the case.
/// Measured on 2 shared cores: 4,961 patches, 24.8 M rays, 1.4e-6 of the bits differ; CPU
/// 6.5e6 rays/s, llvmpipe (LLVM 15.0.6, 256 bits) 1.3e6 rays/s.
#[test]
#[ignore]
fn measure_visibility_rays_per_second() {
    let mut gpu = common::measure_gpu();
    let name = gpu.caps().name.clone();
    let tris = open_box(0.5);
    let patch = common::env_list("SH_MEASURE_PATCH", &[0.05])[0];
    let count = common::env_list("SH_MEASURE_SAMPLES", &[10_000usize])[0];
    let samples = SampleSet::new(count, 4).unwrap_or_else(|e| panic!("{e}"));
    let p = Patches::build(&tris, patch);
    let occ = Occluders::new(&tris);
    let inside: Vec<_> = p.patches.iter().filter(|q| q.inside()).collect();
    // The rays traced: the (patch, sample) pairs in front of both normals.
    let rays = inside
        .iter()
        .map(|q| {
            samples
                .dirs
                .iter()
                .filter(|d| d.dot(p.charts[q.chart].normal) > 0.0 && d.dot(q.normal) > 0.0)
                .count()
        })
        .sum::<usize>() as f64;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let time = |f: &mut dyn FnMut() -> Vec<u32>| {
        let mut out = Vec::new();
        let s = median(
            (0..3)
                .map(|_| {
                    let t = std::time::Instant::now();
                    out = f();
                    t.elapsed().as_secs_f64()
                })
                .collect(),
        );
        (s, out)
    };
    let (cpu_s, cpu) =
        time(&mut || transfer::visibility_cpu(&p, &occ, &samples, Mode::Corrected, &mut Progress::new("cpu")));
    let (gpu_s, on_gpu) = time(&mut || gpu_bits(&mut gpu, &p, &tris, &samples, Mode::Corrected));
    let (share, _, _) = differing(&p, &samples, &cpu, &on_gpu);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "open box, patch {patch}: {} inside patches, {} samples, {rays:.0} rays; {share:.2e} of the bits differ",
        inside.len(),
        samples.len()
    );
    println!("cpu ({threads} threads): {cpu_s:.2} s, {:.3e} rays/s", rays / cpu_s);
    println!("gpu ({name}): {gpu_s:.2} s, {:.3e} rays/s", rays / gpu_s);
    println!("gpu/cpu rays per second: {:.2}x", cpu_s / gpu_s);
    assert!(share <= 1e-3);
}
