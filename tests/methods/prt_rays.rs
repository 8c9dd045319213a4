//! The ray-cast PRT transfer on the GPU (src/lighting/prt/raycast.rs, bake_gpu, and
//! glsl/prt/rays.comp) against the CPU's: the same rays in the same fp32 arithmetic over the
//! same BVHs, so the same coefficients but for rounding, on a floor with a box and a disk over
//! it in three occluder sets (one of them empty), and through a BVH deep enough that llvmpipe
//! cuts the walks short and the bake retries with fewer rays per invocation.

use crate::support as common;

use glam::{Mat4, Vec2, Vec3};
use penumbra::backend::Gpu;
use penumbra::lighting::prt::raycast::{bake_cpu, bake_gpu};
use penumbra::lighting::prt::receivers::{gather, Clip, OccluderRules, OccluderSet, Placed, Receivers};
use penumbra::scene::{generators, Mesh};
use penumbra::shaders::ShaderLibrary;
use penumbra::util::progress::Progress;

/// A disk of radius 1 in the xz-plane facing down: a fan around its centre (the spokes turned
/// off the ray directions' azimuths, through which fp32 Moller-Trumbore may let a ray pass).
fn disk(segments: u32) -> Mesh {
    let mut m = Mesh::default();
    m.positions.push(Vec3::ZERO);
    for k in 0..segments {
        let a = std::f32::consts::TAU * (k as f32 + 0.3) / segments as f32;
        m.positions.push(Vec3::new(a.cos(), 0.0, a.sin()));
    }
    m.normals = vec![Vec3::NEG_Y; m.positions.len()];
    for k in 0..segments {
        m.indices.extend([0, 1 + k, 1 + (k + 1) % segments]);
    }
    m
}

/// Floor (121 vertices), box (24) and disk (49): 194 receivers. The floor is shadowed by
/// everything, the box by the floor and the disk, the disk by nothing.
fn scene() -> Receivers {
    let floor = generators::plane(Vec2::splat(4.0), 10);
    let cube = generators::cuboid(Vec3::new(0.8, 0.6, 0.8), 1);
    let lid = disk(48);
    let placed = [
        Placed {
            object: 0,
            model: Mat4::IDENTITY,
            mesh: &floor,
        },
        Placed {
            object: 1,
            model: Mat4::from_translation(Vec3::new(0.55, 0.35, -0.45)),
            mesh: &cube,
        },
        Placed {
            object: 2,
            model: Mat4::from_translation(Vec3::new(-0.35, 1.1, 0.25)) * Mat4::from_scale(Vec3::splat(0.7)),
            mesh: &lid,
        },
    ];
    let rules = OccluderRules {
        rules: vec![(1, vec![0, 2]), (2, vec![])],
    };
    gather(&placed, &rules).unwrap_or_else(|e| panic!("{e}"))
}

fn cpu(r: &Receivers, bands: usize, samples: usize, clip: Clip) -> Vec<f32> {
    bake_cpu(r, bands, samples, clip, &mut Progress::new("test")).unwrap_or_else(|e| panic!("{e}"))
}

fn gpu_bake(gpu: &mut Gpu, r: &Receivers, bands: usize, samples: usize, clip: Clip) -> Vec<f32> {
    let before = (gpu.live_objects(), gpu.live_frames());
    let t = bake_gpu(
        gpu,
        &ShaderLibrary::Embedded,
        r,
        bands,
        samples,
        clip,
        &mut Progress::new("test"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    common::assert_clean(gpu);
    assert_eq!(
        (gpu.live_objects(), gpu.live_frames()),
        before,
        "the bake leaves nothing behind"
    );
    t
}

/// The largest difference, and where.
fn worst(a: &[f32], b: &[f32]) -> (f32, usize) {
    a.iter()
        .zip(b)
        .enumerate()
        .map(|(i, (x, y))| ((x - y).abs(), i))
        .fold((0.0, 0), |w, d| if d.0 > w.0 { d } else { w })
}

#[test]
fn gpu_transfer_equals_the_cpu_on_floor_box_and_disk() {
    let r = scene();
    assert_eq!(r.len(), 194);
    assert_eq!(r.sets.len(), 3);
    assert!(r.sets.iter().any(|s| s.triangles.is_empty()));
    let mut gpu = common::test_gpu();
    for (bands, samples, clip) in [(4, 1024, Clip::default()), (6, 256, Clip { near: 0.05, far: 1.5 })] {
        let (a, b) = (
            cpu(&r, bands, samples, clip),
            gpu_bake(&mut gpu, &r, bands, samples, clip),
        );
        assert_eq!(a.len(), b.len());
        let (err, at) = worst(&a, &b);
        let dim = bands * bands;
        eprintln!(
            "{bands} bands, N = {samples}, {clip:?}: max |gpu - cpu| {err:.2e} (receiver {}, coefficient {})",
            at / dim,
            at % dim
        );
        assert!(
            err <= 1e-4,
            "receiver {} coefficient {}: cpu {} gpu {}",
            at / dim,
            at % dim,
            a[at],
            b[at]
        );
        // The scene shadows: some floor receivers lose much of their sky, the disk none.
        assert!((0..121).any(|k| a[k * dim] < 0.6), "some floor receiver is shadowed");
        assert!(
            (145..194).all(|k| (a[k * dim] - 0.886227).abs() < 2e-3),
            "the disk's receivers are unshadowed"
        );
    }
}

/// Slivers so many that one ray's walk outlasts llvmpipe's 65,535 loop iterations: even at one
/// ray per invocation the bake must say so, never return what a cut walk found. A cut traversal
/// cannot tell it was cut; the shader's loop sentinels after it must (this fails with both
/// disabled).
#[test]
fn a_walk_too_long_for_the_device_is_an_error_not_a_wrong_transfer() {
    let mut stream = common::xorshift(0x2545_f491_4f6c_dd1d);
    let mut random = move || stream() as f32;
    // Every sliver spans the region, so every box overlaps every ray; few are ever hit.
    let slivers: Vec<[Vec3; 3]> = (0..40_000)
        .map(|_| {
            let a = Vec3::new(-3.0, 0.5 + random() * 2.0, random() * 6.0 - 3.0);
            let b = Vec3::new(3.0, 0.5 + random() * 2.0, random() * 6.0 - 3.0);
            [a, b, a + Vec3::new(0.0, 1e-5, 1e-5)]
        })
        .collect();
    let points = [(glam::DVec3::new(0.0, 0.0, 0.0), glam::DVec3::Y)];
    let r = Receivers {
        sets: vec![OccluderSet {
            objects: vec![0],
            triangles: slivers,
        }],
        ..Receivers::explicit(&points, Vec::new())
    };
    let mut gpu = common::test_gpu();
    if !gpu.caps().name.contains("llvmpipe") {
        return;
    }
    let e = bake_gpu(
        &mut gpu,
        &ShaderLibrary::Embedded,
        &r,
        4,
        16,
        Clip::default(),
        &mut Progress::new("test"),
    )
    .expect_err("a walk longer than the device allows");
    assert!(e.to_string().contains("use the CPU baker"), "{e}");
}

/// A floor under 3,000 long slivers whose boxes all overlap and which rarely stop a ray: a walk
/// visits thousands of nodes, so llvmpipe cuts the first invocations (64 rays each) short and
/// the bake retries with fewer rays per invocation.
#[test]
fn gpu_transfer_equals_the_cpu_through_a_deep_bvh() {
    let mut stream = common::xorshift(0x853c_49e6_748f_ea9b);
    let mut random = move || stream() as f32;
    let mut slivers = Vec::new();
    for _ in 0..3000 {
        let mut point = || Vec3::new(random() * 4.0 - 2.0, 0.5 + random() * 2.0, random() * 4.0 - 2.0);
        let (a, b) = (point(), point());
        slivers.push([a, b, a + Vec3::new(1e-3, 1e-3, 0.0)]);
    }
    let points: Vec<_> = (0..8)
        .map(|k| (glam::DVec3::new(k as f64 * 0.2 - 0.7, 0.0, 0.1), glam::DVec3::Y))
        .collect();
    let r = Receivers {
        sets: vec![OccluderSet {
            objects: vec![0],
            triangles: slivers,
        }],
        ..Receivers::explicit(&points, Vec::new())
    };
    let mut gpu = common::test_gpu();
    let (a, b) = (
        cpu(&r, 4, 256, Clip::default()),
        gpu_bake(&mut gpu, &r, 4, 256, Clip::default()),
    );
    let (err, at) = worst(&a, &b);
    eprintln!(
        "deep BVH: max |gpu - cpu| {err:.2e} (at {at}); T00 of receiver 0: {}",
        a[0]
    );
    assert!(a[0] < 0.88, "the slivers block some rays");
    assert!(err <= 1e-4, "coefficient {at}: cpu {} gpu {}", a[at], b[at]);
}

/// Receivers per second, CPU against GPU, on the floor, box and disk at N = 1024 (4 bands), the
/// median of 3: `cargo test --release --test methods -- --ignored --nocapture prt_rays::`. Measured in
/// the dev profile (opt-level 1) on 2 cores shared with another build: 3,880 receivers, CPU
/// 5,454 receivers/s (5.6e6 rays/s), llvmpipe (LLVM 15.0.6, 256 bits) 1,044 receivers/s.
#[test]
#[ignore]
fn measure_receivers_per_second() {
    let r = scene();
    // The scene's receivers 20 times over (the same rays, enough work to time).
    let mut many = Receivers {
        sets: r.sets.clone(),
        ..Receivers::default()
    };
    for _ in 0..20 {
        many.positions.extend(&r.positions);
        many.normals.extend(&r.normals);
        many.set.extend(&r.set);
    }
    let mut gpu = common::test_gpu();
    let name = gpu.caps().name.clone();
    let median = |f: &mut dyn FnMut() -> Vec<f32>| {
        let mut v: Vec<f64> = (0..3)
            .map(|_| {
                let t = std::time::Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect();
        v.sort_by(f64::total_cmp);
        v[1]
    };
    let clip = Clip::default();
    let cpu_s = median(&mut || cpu(&many, 4, 1024, clip));
    let gpu_s = median(&mut || gpu_bake(&mut gpu, &many, 4, 1024, clip));
    let n = many.len() as f64;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("floor + box + disk, {} receivers, N = 1024, 4 bands", many.len());
    println!("cpu ({threads} threads): {cpu_s:.2} s, {:.0} receivers/s", n / cpu_s);
    println!("gpu ({name}): {gpu_s:.2} s, {:.0} receivers/s", n / gpu_s);
}
