//! A bounded, deterministic fuzz run over everything a user hands penumbra: scene files, OBJ
//! meshes, images (height PNGs, environment HDR/EXR, EXR for `compare`) and `compare`'s image
//! pairs. Inputs are the shipped scenes and assets plus `tests/fuzz_corpus/`, mutated (bit flips,
//! interesting bytes and tokens, deletions, duplications, splices, truncations) by a seeded
//! generator. Every input must give a value or one error line naming the file, never a panic.
//!
//! `FUZZ_ITERATIONS=N cargo test --test commands -- --ignored fuzz::` runs a longer campaign; `FUZZ_SEED=S`
//! (default 0) shifts every target's seed, so a campaign can explore inputs the suite's run
//! never makes.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use penumbra::environment::EnvironmentMap;
use penumbra::metrics::{compare, CompareOptions};
use penumbra::scene::{load_obj, HeightImage, Scene};
use penumbra::util::image_io::HdrImage;

// xorshift64*: a fixed sequence for a fixed seed.
use crate::support::rng::XorShiftStar as Rng;

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

const TOKENS: &[&[u8]] = &[
    b"nan",
    b"inf",
    b"-inf",
    b"1e39",
    b"-1",
    b"0",
    b"4294967296",
    b"[]",
    b"{}",
    b"\"\"",
    b"=",
    b"\n",
    b"[[objects]]\n",
    b"[[lights]]\n",
    b"[[combinations]]\n",
    b"methods = [",
    b"f 1 2 3\n",
    b"v nan 0 0\n",
    b"f -9 0 99\n",
    b"\xff\xfe",
    b"\x00",
    b"#?RADIANCE\n-Y 99999 +X 99999\n",
];

/// One to four mutations of `input`, sometimes spliced with `other`.
fn mutate(input: &[u8], other: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = v.len();
        match rng.below(7) {
            0 if n > 0 => {
                let i = rng.below(n);
                v[i] ^= 1 << rng.below(8);
            }
            1 if n > 0 => {
                let i = rng.below(n);
                v[i] = *[0u8, 0xff, b'\n', b'"', b'[', b']', b'=', b'-', b'.', b'e', b'9', b' ']
                    .get(rng.below(12))
                    .unwrap();
            }
            2 if n > 0 => {
                let i = rng.below(n);
                let len = 1 + rng.below((n - i).min(64));
                v.drain(i..i + len);
            }
            3 if n > 0 => {
                let i = rng.below(n);
                let len = 1 + rng.below((n - i).min(64));
                let chunk = v[i..i + len].to_vec();
                let at = rng.below(n);
                v.splice(at..at, chunk);
            }
            4 => {
                let t = TOKENS[rng.below(TOKENS.len())];
                let at = rng.below(n + 1);
                v.splice(at..at, t.iter().copied());
            }
            5 if !other.is_empty() => {
                let cut = rng.below(n + 1);
                let from = rng.below(other.len());
                v.truncate(cut);
                v.extend_from_slice(&other[from..other.len().min(from + 256)]);
            }
            _ => v.truncate(rng.below(n + 1)),
        }
    }
    v
}

/// What one target saw.
#[derive(Default, Debug)]
struct Stats {
    executions: usize,
    accepted: usize,
    rejected: usize,
}

fn iterations(default: usize) -> usize {
    std::env::var("FUZZ_ITERATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The seed of target `k`: k, shifted by `FUZZ_SEED` (xorshift needs a nonzero state).
fn seed(k: u64) -> u64 {
    let shift: u64 = std::env::var("FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    (k.wrapping_add(shift.wrapping_mul(0x9e37_79b9_7f4a_7c15))).max(1)
}

fn corpus(paths: &[&str]) -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    paths
        .iter()
        .map(|p| std::fs::read(root.join(p)).unwrap_or_else(|e| panic!("{p}: {e}")))
        .collect()
}

fn shipped_scenes() -> Vec<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = vec![std::fs::read(root.join("src/scene/default.toml")).unwrap()];
    for e in std::fs::read_dir(root.join("scenes")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            out.push(std::fs::read(p).unwrap());
        }
    }
    out
}

/// Runs `target` on `n` mutations of the corpus; a panic fails with the input that caused it
/// (saved next to the test's temp files so it can become a regression test).
fn run(
    name: &str,
    seed: u64,
    n: usize,
    corpus: &[Vec<u8>],
    mut target: impl FnMut(&[u8]) -> Result<(), String>,
) -> Stats {
    let mut rng = Rng(seed);
    let mut stats = Stats::default();
    for i in 0..n {
        let a = &corpus[rng.below(corpus.len())];
        let b = &corpus[rng.below(corpus.len())];
        let input = if i < corpus.len() {
            corpus[i].clone()
        } else {
            mutate(a, b, &mut rng)
        };
        match catch_unwind(AssertUnwindSafe(|| target(&input))) {
            Ok(Ok(())) => stats.accepted += 1,
            Ok(Err(msg)) => {
                assert!(
                    !msg.contains('\n') && !msg.is_empty(),
                    "{name}: the error is not one line: {msg:?}"
                );
                stats.rejected += 1;
            }
            Err(_) => {
                let crash = std::env::temp_dir().join(format!("penumbra-fuzz-{name}-{i}.bin"));
                std::fs::write(&crash, &input).unwrap();
                panic!("{name}: input {i} (seed {seed}) panicked; saved to {}", crash.display());
            }
        }
        stats.executions += 1;
    }
    eprintln!("fuzz {name}: {stats:?}");
    stats
}

fn scratch(name: &str) -> PathBuf {
    crate::support::temp_path(&format!("fuzz-{name}"))
}

fn scene_target(input: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(input);
    match Scene::from_str(
        &text,
        "fuzz.toml",
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").as_path(),
    ) {
        Ok(scene) => {
            // What a command does next: the lighting layer's checks, and the meshes.
            penumbra::lighting::registry::configurations(&scene).map_err(|e| e.to_string())?;
            for o in scene.objects.iter().take(4) {
                if !matches!(
                    o.mesh,
                    penumbra::scene::MeshSource::World { .. } | penumbra::scene::MeshSource::Heightfield(_)
                ) {
                    o.load_mesh(Path::new(".")).map_err(|e| e.to_string())?;
                }
            }
            Ok(())
        }
        Err(e) => {
            let e = e.to_string();
            assert!(e.starts_with("fuzz.toml"), "a scene error must name the file: {e}");
            Err(e)
        }
    }
}

fn obj_target(input: &[u8], path: &Path) -> Result<(), String> {
    std::fs::write(path, input).unwrap();
    match load_obj(path) {
        Ok(mesh) => {
            assert!(
                mesh.positions.iter().all(|p| p.is_finite()),
                "a mesh with non-finite positions was accepted"
            );
            assert!(
                mesh.indices.iter().all(|&i| (i as usize) < mesh.positions.len()),
                "an index out of range was accepted"
            );
            Ok(())
        }
        Err(e) => {
            let e = e.to_string();
            assert!(
                e.contains(&path.display().to_string()),
                "an OBJ error must name the file: {e}"
            );
            Err(e)
        }
    }
}

fn image_target(input: &[u8], dir: &Path) -> Result<(), String> {
    // The loaders pick the decoder by extension, as for a user's file: name it by its magic.
    let ext = if input.starts_with(b"\x89PNG") {
        "png"
    } else if input.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        "exr"
    } else if input.starts_with(b"#?") {
        "hdr"
    } else {
        ["png", "exr", "hdr"][input.len() % 3]
    };
    let path = &dir.with_extension(ext);
    std::fs::write(path, input).unwrap();
    let file = path.display().to_string();
    let mut errors = Vec::new();
    match HeightImage::load(path) {
        Ok(h) => assert!(h.values.iter().all(|v| v.is_finite())),
        Err(e) => errors.push(e.to_string()),
    }
    match EnvironmentMap::load(path, 1.0, "fuzz.toml") {
        Ok(m) => assert!(
            m.texels
                .iter()
                .all(|t| t[..3].iter().all(|c| c.is_finite() && *c >= 0.0)),
            "a non-finite or negative environment texel was accepted"
        ),
        Err(e) => errors.push(e.to_string()),
    }
    if let Err(e) = HdrImage::read_exr(path) {
        errors.push(e.to_string());
    }
    for e in &errors {
        assert!(e.contains(&file), "an image error must name the file: {e}");
    }
    // Accepted when any consumer took it (a PNG is no environment map, an HDR no height image).
    if errors.len() < 3 {
        Ok(())
    } else {
        Err(errors[0].clone())
    }
}

/// `compare` of a decoded pair: equal sizes give metrics (finite when the inputs are), others
/// one error line.
fn compare_target(input: &[u8]) -> Result<(), String> {
    let floats: Vec<f32> = input
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let (w, h) = (
        1 + (input.first().copied().unwrap_or(0) % 5) as u32,
        1 + (input.get(1).copied().unwrap_or(0) % 5) as u32,
    );
    let pixel = |i: usize| {
        [
            floats.get(i).copied().unwrap_or(0.5),
            floats.get(i + 1).copied().unwrap_or(0.5),
            floats.get(i + 2).copied().unwrap_or(0.5),
            1.0,
        ]
    };
    let a = HdrImage {
        width: w,
        height: h,
        pixels: (0..(w * h) as usize).map(|i| pixel(3 * i)).collect(),
    };
    let bw = if input.len().is_multiple_of(7) { w + 1 } else { w };
    let b = HdrImage {
        width: bw,
        height: h,
        pixels: (0..(bw * h) as usize).map(|i| pixel(3 * i + 1)).collect(),
    };
    match compare(&a, &b, &CompareOptions::default()) {
        Ok(m) => {
            let finite = a
                .pixels
                .iter()
                .chain(&b.pixels)
                .all(|p| p.iter().all(|c| c.is_finite()));
            if finite {
                assert!(m.rmse.is_finite() && m.rel_mse.is_finite(), "finite inputs gave {m:?}");
            }
            Ok(())
        }
        Err(e) => Err(e.to_string()),
    }
}

fn campaign(scale: usize) -> Vec<(&'static str, Stats)> {
    let mut out = Vec::new();
    out.push((
        "scene",
        run(
            "scene",
            seed(1),
            iterations(1500) * scale,
            &shipped_scenes(),
            scene_target,
        ),
    ));
    let objs = corpus(&["tests/fuzz_corpus/quad.obj", "tests/fuzz_corpus/relative.obj"]);
    let obj_path = scratch("fuzz.obj");
    out.push((
        "obj",
        run("obj", seed(2), iterations(1500) * scale, &objs, |b| {
            obj_target(b, &obj_path)
        }),
    ));
    let images = corpus(&[
        "scenes/terrain/teddy.png",
        "scenes/terrain/sky.hdr",
        "tests/fuzz_corpus/tiny.exr",
        "tests/fuzz_corpus/tiny16.png",
    ]);
    let img_path = scratch("fuzz.img");
    out.push((
        "image",
        run("image", seed(3), iterations(300) * scale, &images, |b| {
            image_target(b, &img_path)
        }),
    ));
    let pairs = vec![vec![3u8, 2, 0, 0, 128, 63, 0, 0, 0, 64], (0..64u8).collect()];
    out.push((
        "compare",
        run("compare", seed(4), iterations(500) * scale, &pairs, compare_target),
    ));
    out
}

#[test]
fn every_input_gives_a_value_or_one_error_line() {
    for (name, s) in campaign(1) {
        // The mutations reach both outcomes, so the run exercises the checks and the paths after.
        assert!(s.accepted > 0 && s.rejected > 0, "{name}: {s:?}");
    }
}

#[test]
#[ignore]
fn long_campaign() {
    campaign(20);
}

/// Property checks of the metrics on random images: identities any implementation must keep.
#[test]
fn metric_identities_hold_on_random_images() {
    let mut rng = Rng(7);
    let mut image = |w: u32, h: u32| HdrImage {
        width: w,
        height: h,
        pixels: (0..w * h)
            .map(|_| {
                [0, 1, 2]
                    .map(|_| (rng.next_u64() % 10_000) as f32 / 1000.0)
                    .into_iter()
                    .chain([1.0])
                    .collect::<Vec<_>>()
                    .try_into()
                    .unwrap()
            })
            .collect(),
    };
    for _ in 0..40 {
        let (a, b) = (image(7, 5), image(7, 5));
        let o = CompareOptions::default();
        let same = compare(&a, &a, &o).unwrap();
        assert_eq!(
            (
                same.rmse,
                same.rel_mse,
                same.mean_bias,
                same.p99_abs_error,
                same.max_abs_error,
                same.flip_mean
            ),
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        );
        let (ab, ba) = (compare(&a, &b, &o).unwrap(), compare(&b, &a, &o).unwrap());
        assert!(
            (ab.rmse - ba.rmse).abs() <= 1e-12 * ab.rmse.max(1.0),
            "RMSE is symmetric"
        );
        assert!((ab.mean_bias + ba.mean_bias).abs() <= 1e-9, "bias is antisymmetric");
        assert!((ab.max_abs_error - ba.max_abs_error).abs() <= 1e-9 && ab.p99_abs_error <= ab.max_abs_error);
        assert!(ab.mean_bias.abs() <= ab.rmse + 1e-12, "|bias| ≤ RMSE");
        assert!((0.0..=1.0).contains(&ab.flip_mean));
        // A constant offset c gives bias c and RMSE |c| exactly (up to rounding).
        let c = 0.25f32;
        let shifted = HdrImage {
            pixels: a.pixels.iter().map(|p| [p[0] + c, p[1] + c, p[2] + c, 1.0]).collect(),
            ..a.clone()
        };
        let m = compare(&shifted, &a, &o).unwrap();
        assert!(
            (m.mean_bias - c as f64).abs() < 1e-5 && (m.rmse - c as f64).abs() < 1e-5,
            "{m:?}"
        );
    }
}
