//! Staniszewski 2005's PRT on whole scenes (digest §5): the raster baker against the ray-cast truth on a
//! floor, a box and a sphere (test 8), the shared-exponent storage on the bunny (test 15), SH keys
//! against the transfer baked at the exact time (test 14), and near/far on the teapot in its box
//! (test 7). Every test prints what it measured; the numbers are in the tests' doc comments.

use crate::support as common;

use glam::Vec3;
use penumbra::backend::Gpu;
use penumbra::environment::EnvironmentMap;
use penumbra::lighting::prt::config::{Config, Coverage, Depth, Mode};
use penumbra::lighting::prt::receivers::{Clip, OccluderRules, Receivers};
use penumbra::lighting::prt::storage::{
    block_words, decode, encode, pack_for_device, round_trip, Grouping, DEVICE_DIM,
};
use penumbra::lighting::prt::{key_blend, key_times, light, raster, raycast, receivers_at, SceneMesh};
use penumbra::scene::{Mesh, Scene};
use penumbra::shaders::ShaderLibrary;
use penumbra::util::progress::Progress;

/// T00 of an unoccluded vertex, √π/2.
const T00: f64 = 0.886227;

fn scenes_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A scene from TOML text (a camera added), paths relative to scenes/.
fn scene(text: &str) -> Scene {
    let text = format!("[camera]\nposition = [0, 2, 4]\ntarget = [0, 0, 0]\n{text}");
    Scene::from_str(&text, "test.toml", &scenes_dir()).unwrap_or_else(|e| panic!("{e}"))
}

fn load(path: &str) -> Scene {
    Scene::from_file(scenes_dir().join(path)).unwrap_or_else(|e| panic!("{e}"))
}

fn meshes(scene: &Scene) -> Vec<Mesh> {
    scene
        .objects
        .iter()
        .map(|o| o.load_mesh(&scenes_dir()).unwrap_or_else(|e| panic!("{e}")))
        .collect()
}

/// The receivers of the listed objects (every object shadows every receiver) at time `t`, and
/// each object's first receiver.
fn receivers(scene: &Scene, meshes: &[Mesh], objects: &[usize], t: f32) -> (Receivers, Vec<usize>) {
    let mut offset = 0u32;
    let mut first = Vec::new();
    let draws: Vec<SceneMesh<'_>> = objects
        .iter()
        .map(|&o| {
            let m = SceneMesh {
                object: Some(o),
                model: scene.objects[o].transform,
                mesh: &meshes[o],
                vertex_offset: offset,
            };
            first.push(offset as usize);
            offset += meshes[o].vertex_count() as u32;
            m
        })
        .collect();
    let (r, _) = receivers_at(scene, &draws, &OccluderRules::default(), t).unwrap_or_else(|e| panic!("{e}"));
    (r, first)
}

/// The receivers `keep` of `r` (same occluder sets).
fn subset(r: &Receivers, keep: &[usize]) -> Receivers {
    Receivers {
        positions: keep.iter().map(|&i| r.positions[i]).collect(),
        normals: keep.iter().map(|&i| r.normals[i]).collect(),
        set: keep.iter().map(|&i| r.set[i]).collect(),
        sets: r.sets.clone(),
    }
}

fn raster_bake(gpu: &mut Gpu, r: &Receivers, c: &Config) -> Vec<f32> {
    let t =
        raster::bake(gpu, &ShaderLibrary::Embedded, r, c, &mut Progress::new("test")).unwrap_or_else(|e| panic!("{e}"));
    common::assert_clean(gpu);
    t
}

fn rays(r: &Receivers, bands: usize, samples: usize, clip: Clip) -> Vec<f32> {
    raycast::bake_cpu(r, bands, samples, clip, &mut Progress::new("test")).unwrap_or_else(|e| panic!("{e}"))
}

fn rms(a: &[f32], b: &[f32]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / a.len().max(1) as f64).sqrt()
}

/// The irradiance Σ T_i L_i (first channel) of every receiver.
fn irradiance(t: &[f32], l: &[Vec3], dim: usize) -> Vec<f64> {
    t.chunks(dim)
        .map(|t| t.iter().zip(l).map(|(t, l)| *t as f64 * l.x as f64).sum())
        .collect()
}

/// The light of a scene's environment and directional lights, 4 bands.
fn light_of(s: &Scene) -> Vec<Vec3> {
    let env = EnvironmentMap::of_scene(s).unwrap_or_else(|e| panic!("{e}"));
    light::project(s, &env, 4).unwrap_or_else(|e| panic!("{e}"))
}

/// Errors of a bake against the truth: per coefficient (RMS, max), overall RMS, and per light
/// the relative RMS error of the irradiance (RMS of the difference over RMS of the truth).
struct Errors {
    per_coefficient: Vec<(f64, f64)>,
    rms: f64,
    irradiance: Vec<f64>,
}

fn errors(bake: &[f32], truth: &[f32], dim: usize, lights: &[Vec<Vec3>]) -> Errors {
    let n = truth.len() / dim;
    let per_coefficient = (0..dim)
        .map(|i| {
            let d: Vec<f64> = (0..n)
                .map(|k| (bake[k * dim + i] - truth[k * dim + i]) as f64)
                .collect();
            (
                (d.iter().map(|x| x * x).sum::<f64>() / n as f64).sqrt(),
                d.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            )
        })
        .collect();
    let irradiance = lights
        .iter()
        .map(|l| {
            let (e, t) = (irradiance(bake, l, dim), irradiance(truth, l, dim));
            let diff = e.iter().zip(&t).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
            (diff / t.iter().map(|b| b * b).sum::<f64>()).sqrt()
        })
        .collect();
    Errors {
        per_coefficient,
        rms: rms(bake, truth),
        irradiance,
    }
}

fn report(label: &str, e: &Errors) {
    println!(
        "{label}: RMS {:.5} ({:.2} % of T00); irradiance relative RMS error: constant {:.2} %, sun {:.2} %, sky.hdr {:.2} %",
        e.rms,
        100.0 * e.rms / T00,
        100.0 * e.irradiance[0],
        100.0 * e.irradiance[1],
        100.0 * e.irradiance[2]
    );
    let line: Vec<String> = e
        .per_coefficient
        .iter()
        .enumerate()
        .map(|(i, (r, m))| format!("{i}: {r:.4}/{m:.3}"))
        .collect();
    println!("  per coefficient RMS/max: {}", line.join("  "));
}

/// Test 8: on a floor (21² vertices), a box (3² cells a face) standing on it and a floating
/// sphere (24 × 12), 862 receivers and 1,436 triangles, every object shadowing every receiver,
/// the corrected raster baker at 32² (orthographic disk, radial depth, exact weights and
/// coverage) against the ray-cast truth with 16,384 stratified rays a receiver.
///
/// * Corrected: RMS 0.0021 (0.24 % of T00), every coefficient's RMS ≤ 0.0032 and max ≤ 0.017;
///   irradiance off by 0.28 % (constant sky), 0.48 % (a sun), 0.37 % (terrain/sky.hdr), RMS
///   relative. Asserted: every coefficient's RMS ≤ 2 % of T00 (the digest's bound) and ≤ 0.6 %
///   (a regression bound: with the coverage rays shifted half a pixel, 0.0124 = 1.4 % of T00,
///   which the 2 % lets through; with the weights taken at the pixel centres only, 0.0072).
/// * The document's path (orthographic, planar, the 8-bit cosine texture, projected coverage,
///   the colour-coded sphere's directions): RMS 0.126 (14.2 % of T00), irradiance 3.9 %, 15.8 %,
///   20.1 % (with exact directions instead of the sphere: 0.111, 12.6 %; 3.9 %, 17.4 %, 16.6 %).
///   Asserted: RMS ≥ 10 × the corrected path's, and worse irradiance under every light.
/// * Corrected with projected coverage (the pure-raster baker): RMS 0.0083 (0.94 % of T00), the
///   worst coefficient's RMS 0.0142 (T00: 1.60 % of T00), max 0.151; irradiance 1.9 %, 1.9 %,
///   2.7 %; RMS by object: floor 0.0109, box 0.0073, the floating sphere 0.0026. Where surfaces
///   meet, the adjoining surface's triangles near a vertex span wide angles, and their edges
///   project to arcs (the rim itself for an edge in the tangent plane) that the straight lines
///   between projected corners cut short. Asserted: every coefficient's RMS ≤ 2 % of T00, the
///   same target. (Before visibility.vert clipped each triangle to the hemisphere in 3D: worst
///   coefficient 0.0157, box 0.0151. Before radial depth discarded the triangles in a vertex's
///   tangent plane, whose corner at the vertex projects to the tile's centre and drew a wedge to
///   the horizon: RMS 0.237.)
#[test]
fn raster_matches_the_ray_cast_truth() {
    let objects = "[[materials]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n\
        [[objects]]\nname = \"floor\"\nmesh = \"plane\"\nsize = 4\nsubdivisions = 20\nmaterial = \"m\"\n\
        [[objects]]\nname = \"box\"\nmesh = \"box\"\nsize = [0.8, 0.6, 0.8]\nsubdivisions = 3\ntranslate = [0.6, 0.3, -0.3]\nmaterial = \"m\"\n\
        [[objects]]\nname = \"sphere\"\nmesh = \"sphere\"\nradius = 0.45\nsegments = 24\nrings = 12\ntranslate = [-0.5, 0.8, 0.3]\nmaterial = \"m\"\n";
    let s = scene(objects);
    let m = meshes(&s);
    let (r, first) = receivers(&s, &m, &[0, 1, 2], 0.0);
    println!(
        "{} receivers, {} occluder triangles",
        r.len(),
        r.sets[0].triangles.len()
    );
    let lights = [
        "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n",
        "[[lights]]\ntype = \"directional\"\ndirection = [0.5, -0.6, 0.35]\nirradiance = [3, 3, 3]\n",
        "[environment]\ntype = \"image\"\npath = \"terrain/sky.hdr\"\n",
    ]
    .map(|l| light_of(&scene(l)));
    let start = std::time::Instant::now();
    let truth = rays(&r, 4, 16384, Clip::default());
    println!("ray-cast truth (16,384 rays): {:.1} s", start.elapsed().as_secs_f64());

    let mut gpu = common::test_gpu();
    let corrected = Config {
        tile: 32,
        batch: 1024,
        ..Config::defaults(Mode::Corrected)
    };
    let bakes = [
        (
            "corrected (orthographic, radial, exact weights, exact coverage)",
            corrected.clone(),
        ),
        (
            "corrected with projected coverage",
            Config {
                coverage: Coverage::Projected,
                ..corrected.clone()
            },
        ),
        (
            "faithful (orthographic, planar, legacy weights, projected coverage, sphere directions)",
            Config {
                tile: 32,
                batch: 1024,
                ..Config::defaults(Mode::Faithful)
            },
        ),
    ];
    let mut measured = Vec::new();
    for (label, config) in bakes {
        let start = std::time::Instant::now();
        let t = raster_bake(&mut gpu, &r, &config);
        let e = errors(&t, &truth, 16, &lights);
        report(&format!("{label}, {:.1} s", start.elapsed().as_secs_f64()), &e);
        let per_object: Vec<String> = ["floor", "box", "sphere"]
            .iter()
            .enumerate()
            .map(|(o, name)| {
                let range = first[o] * 16..first.get(o + 1).map_or(t.len(), |f| f * 16);
                format!("{name} {:.4}", rms(&t[range.clone()], &truth[range]))
            })
            .collect();
        println!("  RMS by object: {}", per_object.join(", "));
        measured.push(e);
    }
    let (c, p, f) = (&measured[0], &measured[1], &measured[2]);

    let worst = c.per_coefficient.iter().map(|e| e.0).fold(0.0, f64::max);
    assert!(
        worst <= 0.02 * T00,
        "corrected: a coefficient's RMS error is {worst} > 2 % of T00"
    );
    // The digest's 2 % lets a half-pixel shift of the coverage rays through (measured 0.0124);
    // measured here 0.0032: held to 0.6 % of T00 as a regression bound.
    assert!(
        worst <= 0.006 * T00,
        "corrected: a coefficient's RMS error is {worst} > 0.6 % of T00 (measured 0.0032)"
    );
    let projected = p.per_coefficient.iter().map(|e| e.0).fold(0.0, f64::max);
    assert!(
        projected <= 0.02 * T00,
        "corrected with projected coverage: a coefficient's RMS error is {projected} > 2 % of T00 (measured 0.0142)"
    );
    assert!(
        f.rms >= 10.0 * c.rms,
        "the faithful path should be clearly worse: RMS {} against {}",
        f.rms,
        c.rms
    );
    assert!(
        f.irradiance.iter().zip(&c.irradiance).all(|(f, c)| f > c),
        "the faithful path's irradiance should be worse: {:?} against {:?}",
        f.irradiance,
        c.irradiance
    );
}

/// The bunny of scenes/prt_bunny_cow.toml standing on its floor (the cow left out; 9,205
/// occluder triangles): 256 of its vertices, evenly picked, against the ray-cast truth with
/// 16,384 rays a vertex, with corrected weights at 32².
fn curved_mesh_errors(coverage: &[Coverage]) -> Vec<f64> {
    let s = load("prt_bunny_cow.toml");
    let m = meshes(&s);
    let object = |name: &str| s.objects.iter().position(|o| o.name == name).unwrap();
    let (floor, bunny) = (object("floor"), object("bunny"));
    let (all, first) = receivers(&s, &m, &[floor, bunny], 0.0);
    let count = all.len() - first[1];
    let keep: Vec<usize> = (0..256).map(|k| first[1] + k * count / 256).collect();
    let r = subset(&all, &keep);
    let truth = rays(&r, 4, 16384, Clip::default());
    let lights = [
        "[environment]\ntype = \"constant\"\nradiance = [1, 1, 1]\n",
        "[[lights]]\ntype = \"directional\"\ndirection = [0.5, -0.6, 0.35]\nirradiance = [3, 3, 3]\n",
        "[environment]\ntype = \"image\"\npath = \"terrain/sky.hdr\"\n",
    ]
    .map(|l| light_of(&scene(l)));
    println!(
        "{} bunny receivers, {} occluder triangles",
        r.len(),
        r.sets[0].triangles.len()
    );
    let mut gpu = common::test_gpu();
    coverage
        .iter()
        .map(|&coverage| {
            let config = Config {
                tile: 32,
                batch: 1024,
                coverage,
                ..Config::defaults(Mode::Corrected)
            };
            let e = errors(&raster_bake(&mut gpu, &r, &config), &truth, 16, &lights);
            report(&format!("{coverage:?} coverage"), &e);
            e.per_coefficient.iter().map(|e| e.0).fold(0.0, f64::max)
        })
        .collect()
}

/// The raster baker on a curved mesh (`curved_mesh_errors`). Exact coverage: worst
/// coefficient's RMS 0.0036 (0.41 % of T00), all together 0.0026; asserted within the 2 %
/// target. Projected coverage: worst 0.0714 (T10, 8.1 % of T00), all together 0.0395 (4.45 %),
/// irradiance 11.5 %, 11.2 %, 8.5 %: it misses the target (`projected_coverage_on_a_curved_mesh_meets_the_target`,
/// ignored). Asserted at 0.08 as a regression bound: without the clipping to the hemisphere
/// in visibility.vert (a triangle crossing the tangent plane drawn from its mirrored corner)
/// it was 0.123 (RMS 0.059).
#[test]
fn raster_on_a_curved_mesh() {
    let worst = curved_mesh_errors(&[Coverage::Exact, Coverage::Projected]);
    assert!(
        worst[0] <= 0.02 * T00,
        "exact coverage: a coefficient's RMS error is {} > 2 % of T00",
        worst[0]
    );
    assert!(
        worst[1] <= 0.08,
        "projected coverage: a coefficient's RMS error is {} > 0.08 (measured 0.0714)",
        worst[1]
    );
}

/// Known failure: projected coverage misses the 2 % target on the bunny (measured 0.0714 =
/// 8.1 % of T00 on its worst coefficient). Close to a vertex of a bumpy mesh, triangles span
/// wide angles, and their edges, arcs in the tile, are drawn as straight lines between the
/// projected corners; exact coverage, which tests each pixel's ray, meets it.
#[test]
#[ignore]
fn projected_coverage_on_a_curved_mesh_meets_the_target() {
    let worst = curved_mesh_errors(&[Coverage::Projected])[0];
    assert!(
        worst <= 0.02 * T00,
        "projected coverage: a coefficient's RMS error is {worst} > 2 % of T00"
    );
}

/// Test 15: the transfer of the low-poly bunny (3,009 vertices) on the floor of
/// scenes/prt_bunny_cow.toml (1,681 vertices; the cow left out), ray-cast with 1,024 rays, 4
/// bands, through the shared-exponent storage grouped by band (coefficient i of four consecutive
/// vertices, the document's choice) and by vertex (four coefficients of one vertex).
///
/// * Grouping by band wins on RMS, as the document says, but narrowly on the bunny alone
///   (measured RMS 1.08e-3 against 1.17e-3) and clearly with the floor (1.25e-3 against
///   1.75e-3); the largest errors are alike (7.7e-3 to 7.8e-3), the sizes too (5 bytes per 4
///   coefficients, 31 % of fp32).
/// * The bound: storage.rs states every value comes back within 2⁻⁷ of its group's largest
///   magnitude, but a group whose largest magnitude m is within 1/256 below a power of two 2^k
///   (m·128/2^k > 127.5) takes the next exponent, whose half step 2^(k−7) is m/127.5 at worst:
///   measured 0.0078157 > 1/128 = 0.0078125 on the floor + bunny grouped by vertex (floor T10 ≈
///   0.998). The tight bound of this encoding, 1/127.5, is asserted.
#[test]
fn shared_exponent_storage_on_the_bunny() {
    let s = load("prt_bunny_cow.toml");
    let m = meshes(&s);
    let object = |name: &str| s.objects.iter().position(|o| o.name == name).unwrap();
    let (floor, bunny) = (object("floor"), object("bunny"));
    let (r, first) = receivers(&s, &m, &[floor, bunny], 0.0);
    let start = std::time::Instant::now();
    let t = rays(&r, 4, 1024, Clip::default());
    println!(
        "{} receivers ({} bunny), ray cast {:.1} s",
        r.len(),
        m[bunny].vertex_count(),
        start.elapsed().as_secs_f64()
    );
    for (label, values) in [("bunny", &t[first[1] * 16..]), ("floor + bunny", &t[..])] {
        let band = round_trip(values, 16, Grouping::ByBand);
        let vertex = round_trip(values, 16, Grouping::ByVertex);
        for (g, e) in [("by band", &band), ("by vertex", &vertex)] {
            println!(
                "{label}, {g}: max {:.2e}, RMS {:.2e}, max/group max {:.7} (1/128 = {:.7}), {} bytes (fp32 {})",
                e.max_abs,
                e.rms,
                e.max_over_group,
                1.0 / 128.0,
                e.bytes,
                values.len() * 4
            );
            assert!(
                e.max_over_group <= 1.0 / 127.5 + 1e-7,
                "{label} {g}: {} over the bound of an 8-bit shared exponent",
                e.max_over_group
            );
            assert!(
                e.bytes * 4 <= values.len() * 5 + 4 * 16 * 5,
                "{label} {g}: {} bytes for {} coefficients",
                e.bytes,
                values.len()
            );
        }
        assert!(
            band.rms < vertex.rms,
            "{label}: grouping by band (RMS {}) should beat grouping by vertex (RMS {})",
            band.rms,
            vertex.rms
        );
    }
}

/// Coefficient `i` of vertex `v` in key `k` read from the device words as glsl/prt/shade.vert
/// addresses them.
fn device_value(words: &[u32], per_key: usize, grouping: Grouping, k: usize, v: usize, i: usize) -> f32 {
    let byte = |w: u32, b: usize| (w >> (8 * b)) as u8;
    let key = &words[k * per_key..(k + 1) * per_key];
    let (m, e) = match grouping {
        Grouping::ByVertex => {
            let block = &key[v * 5..v * 5 + 5];
            (byte(block[i / 4], i % 4), byte(block[4], i / 4))
        }
        Grouping::ByBand => {
            let block = &key[(v / 4) * 20..(v / 4) * 20 + 20];
            (byte(block[i], v % 4), byte(block[16 + i / 4], i % 4))
        }
    };
    (m as i8) as f32 * 2f32.powi(e as i32 - 135)
}

/// The device layout holds every group `encode` forms: two keys of seven vertices (a
/// partial by-band block) read back to `decode`'s values, in 5 bytes per 4 coefficients.
#[test]
fn device_layout_holds_the_encoded_groups() {
    let (keys, vertices) = (2, 7);
    let values: Vec<f32> = (0..keys * vertices * DEVICE_DIM)
        .map(|k| ((k * 7919) % 211) as f32 / 100.0 - 1.0)
        .collect();
    for grouping in [Grouping::ByBand, Grouping::ByVertex] {
        let (words, per_key) = pack_for_device(&values, keys, vertices, Some(grouping));
        let blocks = if grouping == Grouping::ByBand { 2 } else { vertices };
        let block = block_words(grouping);
        assert_eq!(
            block * 4 * 4,
            if grouping == Grouping::ByBand { 4 } else { 1 } * DEVICE_DIM * 5
        );
        assert_eq!((words.len(), per_key), (keys * blocks * block, blocks * block));
        for k in 0..keys {
            let key = &values[k * vertices * DEVICE_DIM..(k + 1) * vertices * DEVICE_DIM];
            let want = decode(&encode(key, DEVICE_DIM, grouping), vertices, DEVICE_DIM, grouping).unwrap();
            for v in 0..vertices {
                for i in 0..DEVICE_DIM {
                    let got = device_value(&words, per_key, grouping, k, v, i);
                    assert_eq!(
                        got,
                        want[v * DEVICE_DIM + i],
                        "{grouping:?} key {k} vertex {v} coefficient {i}"
                    );
                    assert!((got - key[v * DEVICE_DIM + i]).abs() <= 1.1 / 127.5);
                }
            }
        }
    }
    let (fp32, per_key) = pack_for_device(&values, keys, vertices, None);
    assert_eq!((fp32.len(), per_key), (values.len(), vertices * DEVICE_DIM));
}

/// Test 14: a sphere bobbing across a floor (0.5 m each way, 2 s) under a bar spinning about
/// world up (180°/s), 284 receivers, loop 2 s, keys baked with the CPU ray caster (1,024 rays)
/// at 5 and 15 keys/s and blended (`key_blend`, the shader's `mix`) at 8 times between keys,
/// against the transfer baked at those times. Measured RMS: 5 keys/s 0.0096 (1.1 % of T00),
/// 15 keys/s 0.0022 (0.24 %). Asserted: 15 keys/s closer than 5; the blend at a key's time is
/// the key (bit for bit at k / rate, within 2e-7 at the key's time rounded to f32, which is
/// what `key_times` holds); the shading of the blend is the blend of the shadings.
#[test]
fn sh_keys_against_the_transfer_at_that_time() {
    let s = scene(
        "[[materials]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n\
        [[objects]]\nname = \"floor\"\nmesh = \"plane\"\nsize = 2\nsubdivisions = 12\nmaterial = \"m\"\n\
        [[objects]]\nname = \"ball\"\nmesh = \"sphere\"\nradius = 0.3\nsegments = 12\nrings = 6\ntranslate = [0, 0.45, 0]\nbob_amplitude = [0.5, 0, 0]\nbob_period_s = 2\nmaterial = \"m\"\n\
        [[objects]]\nname = \"bar\"\nmesh = \"box\"\nsize = [0.8, 0.1, 0.1]\ntranslate = [0.3, 0.9, -0.4]\nspin_deg_per_s = [0, 180, 0]\nmaterial = \"m\"\n",
    );
    let m = meshes(&s);
    let sun = light_of(&scene("[[lights]]\ntype = \"directional\"\ndirection = [0.5, -0.6, 0.35]\nirradiance = [3, 3, 3]\n[environment]\ntype = \"constant\"\nradiance = [0.3, 0.3, 0.3]\n"));
    let (samples, clip) = (1024, Clip::default());
    let bake_at = |t: f32| rays(&receivers(&s, &m, &[0, 1, 2], t).0, 4, samples, clip);
    // Times between keys of both rates (t·5 and t·15 never whole).
    let times: Vec<f64> = (0..8).map(|j| 0.03 + 0.23 * j as f64).collect();
    let truth: Vec<Vec<f32>> = times.iter().map(|&t| bake_at(t as f32)).collect();
    let n = truth[0].len() / 16;
    println!("{n} receivers, {samples} rays");
    let mut errors = Vec::new();
    for rate in [5.0, 15.0] {
        let config = Config {
            key_rate: rate,
            loop_s: 2.0,
            ..Config::defaults(Mode::Corrected)
        };
        let key_t = key_times(&s, &config);
        let keys: Vec<Vec<f32>> = key_t.iter().map(|&t| bake_at(t)).collect();
        let blend = |t: f64| -> Vec<f32> {
            let (a, b, w) = key_blend(t, keys.len() as u32, rate);
            keys[a as usize]
                .iter()
                .zip(&keys[b as usize])
                .map(|(a, b)| a * (1.0 - w) + b * w)
                .collect()
        };
        // At a key's time k / rate the blend is the key itself, which is the transfer at that
        // time; at the key's time rounded to f32 (the clock's, and key_times') the weight of the
        // next key is ~1e-8 and so is the difference.
        let mut at_f32 = 0.0f64;
        for (k, &t) in key_t.iter().enumerate() {
            assert_eq!(
                blend(k as f64 / rate),
                keys[k],
                "{rate} keys/s: the blend at key {k} (t = {t}) is not the key"
            );
            at_f32 = at_f32.max(
                blend(t as f64)
                    .iter()
                    .zip(&keys[k])
                    .map(|(a, b)| (a - b).abs() as f64)
                    .fold(0.0, f64::max),
            );
        }
        println!("{rate} keys/s: at the keys' times the blend is the key; at those times rounded to f32, within {at_f32:.1e}");
        assert!(
            at_f32 <= 1e-6,
            "{rate} keys/s: the blend at a key's f32 time is {at_f32} off the key"
        );
        let rms_each: Vec<f64> = times
            .iter()
            .zip(&truth)
            .map(|(&t, truth)| rms(&blend(t), truth))
            .collect();
        let total = (rms_each.iter().map(|e| e * e).sum::<f64>() / rms_each.len() as f64).sqrt();
        println!(
            "{rate} keys/s ({} keys): RMS error between keys {total:.5} ({:.2} % of T00); per time {:?}",
            keys.len(),
            100.0 * total / T00,
            rms_each.iter().map(|e| format!("{e:.4}")).collect::<Vec<_>>()
        );
        errors.push(total);
        // Linearity: the shading of the blend is the blend of the shadings.
        let (a, b, w) = key_blend(times[3], keys.len() as u32, rate);
        let (ea, eb, e) = (
            irradiance(&keys[a as usize], &sun, 16),
            irradiance(&keys[b as usize], &sun, 16),
            irradiance(&blend(times[3]), &sun, 16),
        );
        for k in 0..n {
            let lerp = ea[k] * (1.0 - w as f64) + eb[k] * w as f64;
            assert!(
                (e[k] - lerp).abs() <= 1e-5 * ea[k].abs().max(eb[k].abs()).max(1e-3),
                "receiver {k}: shading of the blend {} against the blend of the shadings {lerp}",
                e[k]
            );
        }
    }
    assert!(
        errors[1] < errors[0],
        "15 keys/s ({}) should be closer to the per-time truth than 5 keys/s ({})",
        errors[1],
        errors[0]
    );
}

/// Test 7, near and far as the document describes them, on the teapot in its open box
/// (scenes/prt_teapot_box.toml, 8,336 occluder triangles), with the document's raster path
/// (planar depth; every 8th teapot vertex, every 4th floor vertex).
///
/// * Near = 0, the blackout: the triangles around a vertex start at depth 0, so near = 0 does
///   not clip them; where the smooth normal leaves them above the tangent plane (the rim under
///   the lid, the knob's base, the spout's mouth) they cover a wedge of the hemisphere reaching
///   the zenith (the corner at the vertex lands in the tile's centre). Measured on 456 teapot
///   vertices: 83 keep less than half their T00 at near 1e-3, the mean T00 falls 0.3420 → 0.2849
///   (the ray-cast truth is 0.3442). A ray starting on the surface blacks out the same way
///   (t_min = 0: the neighbouring triangles meet the ray at its origin): 70 vertices, mean
///   0.2619. (The corrected raster with planar depth: 25 vertices below half the truth at near
///   0, 1 at near 1e-3; not baked here, it takes 18 s.)
/// * A far plane shorter than the box: the walls (1 high) and the teapot beyond depth 0.5 are
///   clipped, so the floor sees sky through them: mean T00 of 157 floor vertices 0.5210 →
///   0.6265 (planar); radial (rays) clips by distance, more of the walls: truth 0.4554 → 0.6783.
#[test]
fn near_and_far_on_the_teapot() {
    let s = load("prt_teapot_box.toml");
    let m = meshes(&s);
    let all: Vec<usize> = (0..s.objects.len()).collect();
    let (r, first) = receivers(&s, &m, &all, 0.0);
    let object = |name: &str| s.objects.iter().position(|o| o.name == name).unwrap();
    let (teapot, floor) = (object("teapot"), object("floor"));
    let pot = subset(
        &r,
        &(first[teapot]..first[teapot] + m[teapot].vertex_count())
            .step_by(8)
            .collect::<Vec<_>>(),
    );
    let fl = subset(
        &r,
        &(first[floor]..first[floor] + m[floor].vertex_count())
            .step_by(4)
            .collect::<Vec<_>>(),
    );
    println!(
        "{} teapot receivers, {} floor receivers, {} occluder triangles",
        pot.len(),
        fl.len(),
        r.sets[0].triangles.len()
    );
    let t00 = |t: Vec<f32>| -> Vec<f64> { t.chunks(16).map(|c| c[0] as f64).collect() };
    let mean = |t: &[f64]| t.iter().sum::<f64>() / t.len() as f64;
    // Receivers whose T00 is less than half of `of`'s.
    let lost = |t: &[f64], of: &[f64]| t.iter().zip(of).filter(|(a, b)| **a < 0.5 * **b).count();
    let mut gpu = common::test_gpu();
    let faithful = Config::defaults(Mode::Faithful);
    assert_eq!(faithful.depth, Depth::Planar);

    let truth = t00(rays(&pot, 4, 1024, Clip::default()));
    let rays0 = t00(rays(
        &pot,
        4,
        1024,
        Clip {
            near: 0.0,
            far: f64::INFINITY,
        },
    ));
    let near0 = t00(raster_bake(
        &mut gpu,
        &pot,
        &Config {
            near: 0.0,
            ..faithful.clone()
        },
    ));
    let near1 = t00(raster_bake(
        &mut gpu,
        &pot,
        &Config {
            near: 1e-3,
            ..faithful.clone()
        },
    ));
    let (dark, dark_rays) = (lost(&near0, &near1), lost(&rays0, &truth));
    println!(
        "teapot mean T00: truth (rays, near 1e-3) {:.4}; rays near 0 {:.4} ({dark_rays} below half the truth)",
        mean(&truth),
        mean(&rays0)
    );
    println!(
        "  raster planar: near 0 {:.4} ({dark} below half of near 1e-3), near 1e-3 {:.4}",
        mean(&near0),
        mean(&near1)
    );
    assert!(
        dark * 10 >= pot.len(),
        "near 0 should black out over 10 % of the teapot's vertices: {dark} of {}",
        pot.len()
    );
    assert!(
        mean(&near0) < 0.9 * mean(&near1),
        "near 0 should darken the teapot: mean T00 {} against {}",
        mean(&near0),
        mean(&near1)
    );
    assert!(
        (mean(&near1) / mean(&truth) - 1.0).abs() < 0.03,
        "near 1e-3 should recover the truth's mean T00: {} against {}",
        mean(&near1),
        mean(&truth)
    );
    assert!(
        dark_rays * 10 >= pot.len() && mean(&rays0) < 0.9 * mean(&truth),
        "rays from the surface (near 0) should black out too: {dark_rays}, mean {}",
        mean(&rays0)
    );

    let floor_truth = t00(rays(&fl, 4, 1024, Clip::default()));
    let floor_rays = t00(rays(&fl, 4, 1024, Clip { near: 1e-3, far: 0.5 }));
    let unbounded = t00(raster_bake(&mut gpu, &fl, &faithful));
    let short = t00(raster_bake(
        &mut gpu,
        &fl,
        &Config {
            far: 0.5,
            ..faithful.clone()
        },
    ));
    println!(
        "floor mean T00: raster planar far ∞ {:.4}, far 0.5 {:.4}; rays (radial) far ∞ {:.4}, far 0.5 {:.4}",
        mean(&unbounded),
        mean(&short),
        mean(&floor_truth),
        mean(&floor_rays)
    );
    assert!(
        mean(&short) > 1.1 * mean(&unbounded),
        "a far plane short of the walls should let sky in: {} against {}",
        mean(&short),
        mean(&unbounded)
    );
    assert!(
        mean(&floor_rays) > 1.3 * mean(&floor_truth),
        "a radial far short of the walls should let sky in: {} against {}",
        mean(&floor_rays),
        mean(&floor_truth)
    );
}
