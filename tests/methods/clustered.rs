//! Clustered shading on the GPU: its image against the forward method's and the closed form with
//! each light cut off at its range, the assignment read back (a light out of range is nowhere, a
//! moved light moves, the GPU's lists match the CPU's twin), overflow counted, and bad parameters
//! refused.

use crate::support as common;

use glam::Vec3;
use penumbra::backend::Gpu;
use penumbra::environment::EnvironmentMap;
use penumbra::gpu_scene::SceneGpu;
use penumbra::graph::{RenderGraph, ResourceStates};
use penumbra::lighting::brdf::{shade, Surface};
use penumbra::lighting::clustered::assign::{assign_cpu, Assignment, LightVolume};
use penumbra::lighting::clustered::config::Config;
use penumbra::lighting::clustered::Clustered;
use penumbra::lighting::Terms;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::{Light, Scene};
use penumbra::util::image_io::HdrImage;

const W: u32 = 64;
const H: u32 = 48;

use crate::support::rng::Lcg as Rng;

impl Rng {
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next_f32()
    }
}

/// `points` point and `spots` spot lights low over the floor, each with a finite `radius` of
/// 1.5–4 m, coloured intensities of 0.5–3 W/sr; spots aim roughly down with 20–60° cones.
fn lights(points: usize, spots: usize, seed: u64) -> String {
    let mut rng = Rng(seed);
    let mut out = String::new();
    for _ in 0..points {
        let (x, y, z) = (rng.range(-9.0, 9.0), rng.range(0.3, 1.2), rng.range(-10.0, 6.0));
        let i = [rng.range(0.5, 3.0), rng.range(0.5, 3.0), rng.range(0.5, 3.0)];
        let r = rng.range(1.5, 4.0);
        out += &format!(
            "[[lights]]\ntype = \"point\"\nposition = [{x}, {y}, {z}]\nintensity = [{}, {}, {}]\nradius = {r}\n\n",
            i[0], i[1], i[2]
        );
    }
    for _ in 0..spots {
        let (x, y, z) = (rng.range(-9.0, 9.0), rng.range(0.8, 2.0), rng.range(-10.0, 6.0));
        let d = [rng.range(-0.4, 0.4), -1.0, rng.range(-0.4, 0.4)];
        let i = rng.range(2.0, 8.0);
        let outer = rng.range(20.0, 60.0);
        let r = rng.range(2.0, 5.0);
        out += &format!(
            "[[lights]]\ntype = \"spot\"\nposition = [{x}, {y}, {z}]\ndirection = [{}, {}, {}]\nintensity = {i}\nouter_deg = {outer}\ninner_deg = {}\nradius = {r}\n\n",
            d[0],
            d[1],
            d[2],
            0.7 * outer
        );
    }
    out
}

/// A 24 m floor, diffuse with a specular lobe, seen obliquely so the slices span 3–20 m.
fn floor_text(methods: &str, lights: &str) -> String {
    format!(
        "methods = [{methods}]\n[camera]\nposition = [0, 7, 9]\ntarget = [0, 0, -2]\nfov_y_deg = 60\n\n\
         [[materials]]\nname = \"floor\"\nalbedo = [0.7, 0.6, 0.5]\nspecular = 0.2\nexponent = 16\n\n\
         [[objects]]\nmesh = \"plane\"\nsize = [24, 24]\nmaterial = \"floor\"\n\n{lights}"
    )
}

fn floor_scene(methods: &str, lights: &str) -> Scene {
    let text = floor_text(methods, lights);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    Scene::from_str(&text, "clustered test", &dir).unwrap_or_else(|e| panic!("{e}"))
}

fn render(scene: &Scene, method: &str) -> HdrImage {
    let mut r =
        Renderer::new(common::test_gpu(), scene.clone(), Some(method), (W, H), 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

/// The scene's lights as the GPU sees them, with their ranges (`radius`).
fn lights_and_ranges(scene: &Scene, gpu: &mut Gpu) -> (Vec<penumbra::gpu_scene::GpuLight>, Vec<f32>) {
    let mut states = ResourceStates::default();
    let environment = EnvironmentMap::of_scene(scene).unwrap();
    let scene_gpu = SceneGpu::upload(gpu, &mut states, scene, &environment).unwrap();
    let ranges = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Point { radius, .. } | Light::Spot { radius, .. } => *radius,
            _ => f32::INFINITY,
        })
        .collect();
    (scene_gpu.lights.clone(), ranges)
}

/// The first `clustered` method's assignment for the scene's camera at W × H, read back, with the
/// method (its block and light volumes) for the CPU twin.
fn assignment(scene: &Scene) -> (Assignment, Clustered) {
    let mut f = common::MethodFixture::new(scene);
    let decl = scene
        .methods
        .iter()
        .find(|d| d.name == "clustered")
        .expect("a clustered method")
        .clone();
    let mut method = Clustered::new(&mut f.context(scene, Terms::BASE_DIRECT), &decl).unwrap_or_else(|e| panic!("{e}"));
    let view_proj = scene.camera.view_projection(W as f32 / H as f32).to_cols_array();
    method.plan(&view_proj, &f.scene_gpu.lights, W, H).unwrap();
    let frame = f.gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    method.add_assignment_passes(&mut graph);
    graph.output_buffer(method.counts);
    graph.output_buffer(method.indices);
    graph
        .run_and_wait(&f.gpu, frame, &mut f.states, "clustered test")
        .unwrap();
    let a = method.read_assignment(&mut f.gpu).unwrap();
    common::assert_clean(&f.gpu);
    (a, method)
}

/// Where pixel (i, j)'s centre ray meets the floor, at least `margin` inside its edges.
fn hit_floor(scene: &Scene, i: u32, j: u32, margin: f32) -> Option<Vec3> {
    let (o, d) = scene.camera.pixel_center_ray(i, j, W, H);
    if d.y >= 0.0 {
        return None;
    }
    let p = o + d * (-o.y / d.y);
    (p.x.abs() < 12.0 - margin && p.z.abs() < 12.0 - margin).then_some(p)
}

fn close(a: Vec3, b: Vec3, rel: f32, abs: f32) -> bool {
    (0..3).all(|c| (a[c] - b[c]).abs() <= rel * a[c].abs().max(b[c].abs()) + abs)
}

/// 64 point and 32 spot lights with finite ranges, and a sun: at every floor pixel the clustered image is
/// the closed form summed over the lights within their range, and the forward image is the
/// closed form over every light; so clustered = forward − (the lights beyond their range), pixel
/// by pixel. Pixels within 0.2% of some light's range are left out (there the cut-off is decided
/// by rounding of the interpolated position); they must be a minority.
#[test]
fn matches_forward_within_each_lights_range() {
    // A dim sun too: a directional light reaches every cluster.
    let sun = "[[lights]]\ntype = \"directional\"\ndirection = [0.3, -1, 0.2]\nirradiance = 0.05\n\n";
    let scene = floor_scene("\"clustered\", \"forward\"", &format!("{}{sun}", lights(64, 32, 7)));
    let clustered = render(&scene, "clustered");
    let forward = render(&scene, "forward");
    let mut gpu = common::test_gpu();
    let (lights, ranges) = lights_and_ranges(&scene, &mut gpu);
    let surface = Surface {
        albedo: Vec3::new(0.7, 0.6, 0.5),
        specular: Vec3::splat(0.2),
        exponent: 16.0,
        emission: Vec3::ZERO,
    };
    let eye = scene.camera.position;
    let (mut checked, mut edge, mut cut_somewhere) = (0, 0, 0);
    for j in 0..H {
        for i in 0..W {
            let Some(p) = hit_floor(&scene, i, j, 0.5) else {
                continue;
            };
            let dist = |k: usize| (Vec3::from_slice(&lights[k].position[..3]) - p).length();
            if (0..lights.len()).any(|k| (dist(k) - ranges[k]).abs() < 0.002 * ranges[k]) {
                edge += 1;
                continue;
            }
            checked += 1;
            let within: Vec<_> = (0..lights.len())
                .filter(|&k| dist(k) <= ranges[k])
                .map(|k| lights[k])
                .collect();
            let windowed = shade(p, Vec3::Y, eye, &surface, &within, Vec3::ZERO);
            let full = shade(p, Vec3::Y, eye, &surface, &lights, Vec3::ZERO);
            let (c, f) = (
                Vec3::from_slice(&clustered.get(i, j)[..3]),
                Vec3::from_slice(&forward.get(i, j)[..3]),
            );
            assert!(
                close(c, windowed, 2e-3, 1e-5),
                "pixel ({i},{j}) at {p}: clustered {c} vs the sum within range {windowed}"
            );
            assert!(
                close(f, full, 2e-3, 1e-5),
                "pixel ({i},{j}) at {p}: forward {f} vs the sum over all lights {full}"
            );
            let tail = full - windowed;
            assert!(
                close(c, f - tail, 2e-3, 1e-4),
                "pixel ({i},{j}): clustered {c} vs forward {f} less the lights beyond range {tail}"
            );
            if tail.max_element() > 1e-3 * full.max_element() {
                cut_somewhere += 1;
            }
        }
    }
    assert!(
        checked > (W * H / 2) as usize && edge < checked / 3,
        "{checked} pixels checked, {edge} on a range's edge"
    );
    // The ranges cut real light somewhere, or the test would not tell a cut-off from none.
    assert!(
        cut_somewhere > checked / 10,
        "{cut_somewhere} of {checked} pixels lose light beyond a range"
    );
}

/// The assignment read back: equal to the CPU twin's (but for clusters whose box a sphere
/// barely touches: rounding); a light beyond the view is in no cluster and changes neither the
/// other lists nor the image; moving a light moves it to other clusters; and clusters hold far
/// fewer lights than the scene has.
#[test]
fn assignment_follows_the_lights() {
    let base = lights(32, 16, 11);
    let scene = floor_scene("\"clustered\"", &base);
    let (a, method) = assignment(&scene);
    let cpu = assign_cpu(&method.block, &method.volumes);
    let differing = a
        .counts
        .iter()
        .zip(&cpu)
        .filter(|(g, c)| **g as usize != c.len())
        .count();
    assert!(
        differing * 200 <= a.counts.len(),
        "{differing} of {} clusters differ from the CPU's assignment",
        a.counts.len()
    );
    let total: u64 = a.counts.iter().map(|&n| n as u64).sum();
    let mean = total as f64 / a.counts.len() as f64;
    assert!(
        total > 0 && mean < 48.0 / 8.0,
        "mean {mean:.2} lights per cluster of 48"
    );
    assert_eq!(a.overflowed_clusters(), 0);

    // Far off to the side and beyond the slices' far end: within reach of no cluster.
    let far = "[[lights]]\ntype = \"point\"\nposition = [60, 1, -40]\nintensity = 5\nradius = 3\n";
    let with_far = floor_scene("\"clustered\"", &format!("{base}{far}"));
    let (b, _) = assignment(&with_far);
    assert_eq!(
        a.counts, b.counts,
        "a light out of every cluster's reach changed the counts"
    );
    assert_eq!(a.lights, b.lights);
    assert!(b.clusters_of(48).is_empty());
    let (img_a, img_b) = (render(&scene, "clustered"), render(&with_far, "clustered"));
    assert!(
        img_a.pixels == img_b.pixels,
        "a light out of every cluster's reach changed the image"
    );

    // Light 0 moved 4 m along x, toward the middle.
    let mut moved = scene.clone();
    if let Light::Point { position, .. } = &mut moved.lights[0] {
        position.x -= 4.0f32.copysign(position.x);
    } else {
        panic!("light 0 is a point light");
    }
    let (m, _) = assignment(&moved);
    let (before, after) = (a.clusters_of(0), m.clusters_of(0));
    assert!(
        !before.is_empty() && !after.is_empty() && before != after,
        "light 0's clusters: {before:?} then {after:?}"
    );
    for k in 1..48u32 {
        assert_eq!(a.clusters_of(k), m.clusters_of(k), "light {k} did not move");
    }
}

/// Bands of 24 slices and more than one slice per invocation (64): 2,300 lights over 160
/// slices, assigned through the masks of bands of slices, equal the CPU twin's exhaustive test of every
/// light against every cluster (but for rounding at a box's face), in light order. The same run
/// shows what the spot cones save: fewer light-cluster pairs than the bounding spheres alone give.
#[test]
fn the_assignment_is_exhaustive_across_bands_and_slices() {
    let decl = "{ name = \"clustered\", tiles = [6, 4], slices = 160, max_per_cluster = 1024 }";
    let scene = floor_scene(decl, &lights(1300, 1000, 23));
    let (a, method) = assignment(&scene);
    let cpu = assign_cpu(&method.block, &method.volumes);
    assert_eq!(a.overflowed_clusters(), 0);
    let differing = a.lights.iter().zip(&cpu).filter(|(g, c)| g != c).count();
    assert!(
        differing * 200 <= a.counts.len(),
        "{differing} of {} clusters differ from the CPU's assignment",
        a.counts.len()
    );
    let deep = a.counts.iter().skip(6 * 4 * 64).filter(|&&n| n > 0).count();
    assert!(deep > 0, "no cluster past slice 64 holds a light");
    let spheres: Vec<_> = method
        .volumes
        .iter()
        .map(|v| LightVolume {
            axis: [0.0, 0.0, 0.0, -1.0],
            ..*v
        })
        .collect();
    let (with_cones, without): (usize, usize) = (
        cpu.iter().map(Vec::len).sum(),
        assign_cpu(&method.block, &spheres).iter().map(Vec::len).sum(),
    );
    assert!(
        with_cones * 100 < without * 98,
        "{with_cones} pairs with the cones against {without} with their spheres"
    );
}

/// Twelve lights whose ranges cover the whole floor in 4 slots: every cluster on the floor
/// overflows and the dropped pairs are counted; with 16 slots nothing overflows.
#[test]
fn overflow_is_counted() {
    let mut text = String::new();
    for k in 0..12 {
        text += &format!(
            "[[lights]]\ntype = \"point\"\nposition = [{}, 1, -2]\nintensity = 1\nradius = 100\n\n",
            k as f32 - 6.0
        );
    }
    let (small, _) = assignment(&floor_scene(
        "{ name = \"clustered\", max_per_cluster = 4, tiles = [8, 6], slices = 8 }",
        &text,
    ));
    assert_eq!(small.counts.iter().max(), Some(&12));
    assert_eq!(
        small.overflowed_clusters(),
        small.counts.len(),
        "every cluster holds all 12 lights: {:?}",
        small.counts
    );
    assert_eq!(small.dropped(), 8 * small.counts.len() as u64);
    assert!(small.lights.iter().all(|l| l.len() == 4));
    let (roomy, _) = assignment(&floor_scene(
        "{ name = \"clustered\", max_per_cluster = 16, tiles = [8, 6], slices = 8 }",
        &text,
    ));
    assert_eq!((roomy.overflowed_clusters(), roomy.dropped()), (0, 0));
    assert!(roomy.lights.iter().all(|l| l.len() == 12));
}

/// Overflow reaches the user: the renderer's warnings after a frame name the method, the
/// clusters and `max_per_cluster` when lights were dropped and say nothing when none were, and
/// `penumbra capture` prints the line on stderr.
#[test]
fn dropped_lights_are_reported_to_the_user() {
    let mut text = String::new();
    for k in 0..12 {
        text += &format!(
            "[[lights]]\ntype = \"point\"\nposition = [{}, 1, -2]\nintensity = 1\nradius = 100\n\n",
            k as f32 - 6.0
        );
    }
    let warnings = |cap: u32| {
        let scene = floor_scene(
            &format!("{{ name = \"clustered\", max_per_cluster = {cap}, tiles = [8, 6], slices = 8 }}"),
            &text,
        );
        let mut r =
            Renderer::new(common::test_gpu(), scene, Some("clustered"), (W, H), 1).unwrap_or_else(|e| panic!("{e}"));
        let cam = r.scene.camera.clone();
        r.render(&cam, FrameOutput::Readback).unwrap();
        let w = r.method_warnings().unwrap();
        common::assert_clean(&r.gpu);
        w
    };
    let small = warnings(4);
    assert_eq!(small.len(), 1, "{small:?}");
    assert!(
        small[0].starts_with("clustered: 384 of 384 clusters")
            && small[0].contains("max_per_cluster = 4 (the fullest 12)")
            && small[0].contains("3072 light-cluster pairs"),
        "{}",
        small[0]
    );
    assert!(warnings(12).is_empty(), "12 slots hold all 12 lights");

    let dir = common::temp_path("clustered-overflow");
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("overflow.toml");
    std::fs::write(
        &scene_path,
        floor_text("{ name = \"clustered\", max_per_cluster = 4 }", &text),
    )
    .unwrap();
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args([
            "capture",
            scene_path.to_str().unwrap(),
            "--size",
            "32x24",
            "--device",
            &device,
            "--validation",
            "-o",
            dir.join("c.png").to_str().unwrap(),
        ])
        .output()
        .expect("run penumbra");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr
            .lines()
            .any(|l| l.starts_with("warning: clustered:") && l.contains("max_per_cluster = 4")),
        "{stderr}"
    );
}

/// Bad parameters: one error naming the scene, the method's entry and the parameter.
#[test]
fn bad_parameters_are_refused() {
    let cases = [
        ("tiles = [0, 9]", "tiles", "[columns, rows]"),
        ("tiles = [16]", "tiles", "[columns, rows]"),
        ("slices = 0", "slices", "depth slice count"),
        ("max_per_cluster = 8193", "max_per_cluster", "from 1 to 8192"),
        ("cutoff = -1", "cutoff", "irradiance > 0"),
        ("cutoff = 0", "cutoff", "irradiance > 0"),
        (
            "tiles = [128, 128], slices = 16, max_per_cluster = 1024",
            "max_per_cluster",
            "MiB",
        ),
        ("tiles = [256, 256]", "tiles", "at most 16384 tiles"),
        ("tiles = [128, 128], slices = 256", "slices", "at most 1048576 clusters"),
    ];
    for (params, param, want) in cases {
        let scene = floor_scene(&format!("{{ name = \"clustered\", {params} }}"), "");
        let decl = &scene.methods[0];
        let e = Config::from_decl(decl, Some(&scene)).expect_err(params).to_string();
        assert!(
            e.contains("clustered test") && e.contains(&format!("methods[0].{param}")) && e.contains(want),
            "{params}: {e}"
        );
        assert_eq!(e.lines().count(), 1, "{e}");
    }
    // Types are checked when the scene loads.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = "methods = [{ name = \"clustered\", slices = \"many\" }]\n[camera]\nposition = [0, 1, 2]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"plane\"\n";
    let e = match Scene::from_str(text, "clustered types", &dir) {
        Ok(scene) => penumbra::lighting::registry::configurations(&scene)
            .expect_err("a string for slices")
            .to_string(),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("clustered types") && e.contains("slices"), "{e}");
}

/// As the direct term over forward's base (under a constant sky, so the base is not black), the
/// clustered pass adds its lights over the base's depth: the same image as clustered alone.
#[test]
fn direct_term_over_another_base() {
    let combination = "[environment]\ntype = \"constant\"\nradiance = 0.3\n\n[[combinations]]\nname = \"mixed\"\nbase = \"forward\"\ndirect = \"clustered\"\n\n";
    let scene = floor_scene(
        "\"clustered\", \"forward\"",
        &format!("{combination}{}", lights(24, 8, 3)),
    );
    let (alone, mixed) = (render(&scene, "clustered"), render(&scene, "mixed"));
    let mut lit = 0;
    for (k, (a, m)) in alone.pixels.iter().zip(&mixed.pixels).enumerate() {
        let (a, m) = (Vec3::from_slice(&a[..3]), Vec3::from_slice(&m[..3]));
        assert!(
            close(a, m, 1e-4, 1e-6),
            "pixel {k}: clustered alone {a}, over forward's base {m}"
        );
        lit += (a.max_element() > 0.0) as usize;
    }
    assert!(lit > alone.pixels.len() / 2, "{lit} lit pixels");
}
