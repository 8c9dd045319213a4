//! The stencil shadow volumes over a BSP/PVS world: every caster strategy gives the same image
//! where the seed says it must (and the caster counts it should), the Fig. 8(c) shadow that only
//! the PSCS finds, culling by PVS, radius and a spot light's cone changing draws but not pixels,
//! the rendered shadows against CPU ray casts through the BSP, and `penumbra profile` naming
//! every pass.

use crate::support as common;
use crate::support::shadow_volumes as sv_common;

use glam::{DVec3, Vec3};
use penumbra::lighting::shadow_volumes::Setup;
use penumbra::scene::world_mesh::{self, scene_to_world, WorldLevel};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;
use penumbra::world::level_gen::RoomsParams;
use sv_common::{compare_masks, lit, method, render_scene};

const SIZE: (u32, u32) = (96, 96);

/// The world of scenes/bsp_rooms.toml (uniform material, no entities).
const WORLD: &str = r#"
[[materials]]
name = "wall"
albedo = 0.7

[[objects]]
name = "world"
mesh = "bsp_rooms"
seed = 1
wall_material = "wall"
floor_material = "wall"
ceiling_material = "wall"
pillar_material = "wall"
corridor_material = "wall"
"#;

/// Two lights of scenes/bsp_rooms.toml, in rooms 0 and 1.
const LIGHTS: [&str; 2] = [
    "[[lights]]\nname = \"room 0\"\ntype = \"point\"\nposition = [5.2, 2.7, -8.6]\nintensity = [9, 7, 4.5]\nradius = 8.0\n",
    "[[lights]]\nname = \"room 1\"\ntype = \"point\"\nposition = [20.5, 3.0, -7.0]\nintensity = [3, 5, 11]\nradius = 9.0\n",
];

fn rooms(lights: &[usize]) -> String {
    let mut s = WORLD.to_string();
    for &l in lights {
        s += LIGHTS[l];
    }
    s
}

/// Viewpoints in room 0 (two) and room 1.
const CAMERAS: [&str; 3] = [
    "[camera]\nposition = [2.8, 1.7, -4.1]\ntarget = [9.0, 0.8, -9.2]\nfov_y_deg = 70",
    "[camera]\nposition = [11.0, 2.5, -10.0]\ntarget = [3.0, 0.0, -4.0]\nfov_y_deg = 70",
    "[camera]\nposition = [17.5, 1.6, -3.5]\ntarget = [24.0, 0.5, -10.0]\nfov_y_deg = 70",
];

/// The physical mode unless `params` names a mode.
fn scene(camera: &str, world: &str, params: &[&str]) -> Scene {
    let mode: &[&str] = if params.iter().any(|p| p.starts_with("mode")) {
        &[]
    } else {
        &["mode = \"physical\""]
    };
    let text = format!(
        "{}\n{camera}\n{world}",
        method(&[mode, &["animate = false"], params].concat())
    );
    Scene::from_str(&text, "<test>", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

fn differing(a: &HdrImage, b: &HdrImage) -> usize {
    a.pixels.iter().zip(&b.pixels).filter(|(x, y)| x != y).count()
}

#[test]
fn caster_strategies_agree_on_generated_rooms() {
    const STRATEGIES: [&str; 3] = ["naive", "pvs", "pscs"];
    for radius_culling in [false, true] {
        let mut totals = [0usize; 3];
        for camera in CAMERAS {
            let mut images = Vec::new();
            for casters in STRATEGIES {
                let s = scene(
                    camera,
                    &rooms(&[0, 1]),
                    &[
                        &format!("casters = \"{casters}\""),
                        &format!("radius_culling = {radius_culling}"),
                    ],
                );
                let plan = Setup::new(&s, &s.methods[0]).unwrap().plan(s.camera.position, 0.0);
                let i = STRATEGIES.iter().position(|c| *c == casters).unwrap_or(0);
                totals[i] += plan.lights.iter().map(|l| l.caster_faces.len()).sum::<usize>();
                images.push((render_scene(s, SIZE), plan));
            }
            let (naive, pvs, pscs) = (&images[0], &images[1], &images[2]);
            // Back-facing casters: the strategies' volumes agree wherever the PSCS is complete.
            assert_eq!(
                differing(&naive.0, &pscs.0),
                0,
                "naive and PVS+PSCS casters must give bit-identical images"
            );
            // The PVS alone may miss casters (Fig. 8(c)): it can only add light, never remove it.
            let brighter = naive
                .0
                .pixels
                .iter()
                .zip(&pvs.0.pixels)
                .filter(|(n, p)| n != p)
                .inspect(|(n, p)| {
                    assert!(
                        (0..3).all(|c| p[c] >= n[c]),
                        "PVS-only casters darkened a pixel: {n:?} -> {p:?}"
                    )
                })
                .count();
            println!("radius culling {radius_culling}: PVS-only casters leave {brighter} shadowed pixels lit");
            for ((n, p), c) in naive.1.lights.iter().zip(&pvs.1.lights).zip(&pscs.1.lights) {
                assert!(n.caster_faces.len() >= c.caster_faces.len() && c.caster_faces.len() >= p.caster_faces.len());
                assert!(
                    p.caster_faces.iter().all(|f| c.caster_faces.contains(f))
                        && c.caster_faces.iter().all(|f| n.caster_faces.contains(f))
                );
            }
        }
        println!("radius culling {radius_culling}: casters summed over cameras and drawn lights, naive / pvs / pscs: {totals:?}");
        // The counts of this level and these lights: a regression check on the caster selection.
        // Within radii of 8 and 9 m the radius alone already confines the casters to what the
        // lights' PVS holds; without radius culling the PVS halves them and the PSCS adds back
        // the back faces behind lit walls.
        if radius_culling {
            assert_eq!(totals, [138, 138, 138]);
        } else {
            assert_eq!(totals, [633, 297, 363]);
        }
    }
}

/// The rendered lit mask of the naive strategy against ray casts through the BSP: a pixel of a
/// face lit by the light (front-facing, within the radius) is lit iff the segment to the light
/// is unobstructed.
#[test]
fn world_shadows_match_bsp_ray_casts() {
    let w = world_mesh::compiled(&WorldLevel::Rooms {
        seed: 1,
        params: RoomsParams::default(),
    })
    .unwrap();
    for (camera, light) in [(CAMERAS[0], 0usize), (CAMERAS[2], 1)] {
        let s = scene(camera, &rooms(&[light]), &["casters = \"naive\""]);
        assert_eq!(s.lights.len(), 1);
        let (lpos, radius) = match &s.lights[0] {
            penumbra::scene::Light::Point { position, radius, .. } => (scene_to_world(*position), f64::from(*radius)),
            _ => unreachable!(),
        };
        let img = render_scene(s.clone(), SIZE);
        let cam = s.camera.clone();
        let c = compare_masks(
            SIZE.0,
            SIZE.1,
            |x, y| lit(&img, x, y, 0.0),
            |px, py| {
                let (o, d) = cam.ray(px, py, SIZE.0, SIZE.1);
                let hit = w.cast_ray(scene_to_world(o), scene_to_world(d), 1e3)?;
                let face = &w.faces[hit.face? as usize];
                let to_light = lpos - hit.point;
                // Judge only points that face the light clearly and lie clearly inside its radius.
                if face.polygon.plane.normal.dot(to_light.normalize()) < 0.05 || to_light.length() > radius - 0.05 {
                    return None;
                }
                Some(!w.occluded(lpos, hit.point + face.polygon.plane.normal * 1e-6))
            },
        );
        println!("light {light}: {c:?}");
        assert!(c.pixels > 2000 && c.cpu_shadow > 30, "{c:?}");
        assert!(c.iou >= 0.98, "{c:?}");
        assert!(c.interior_mismatches * 1000 <= c.pixels, "{c:?}");
    }
}

/// The seed's Fig. 8(c): the pillar's back face lies in a leaf the light's leaf cannot see, yet
/// it shadows the back wall in leaves it can. Without the PSCS that shadow is missing.
#[test]
fn fig8c_shadow_is_missing_without_the_pscs_and_present_with_it() {
    let case = WorldLevel::Fig8c.fig8c().unwrap();
    let light = world_mesh::world_to_scene(case.light);
    // Look at the receiver point on the back wall (world y = 10) from inside the room.
    let target = world_mesh::world_to_scene(case.receiver_point);
    let eye = world_mesh::world_to_scene(DVec3::new(case.receiver_point.x + 1.5, 7.5, 2.2));
    let text_for = |casters: &str| {
        format!(
            r#"{}
[camera]
position = [{}, {}, {}]
target = [{}, {}, {}]
fov_y_deg = 40

[[objects]]
name = "room"
mesh = "bsp_fig8c"

[[lights]]
type = "point"
position = [{}, {}, {}]
intensity = 10
radius = 30
"#,
            method(&["mode = \"physical\"", &format!("casters = \"{casters}\"")]),
            eye.x,
            eye.y,
            eye.z,
            target.x,
            target.y,
            target.z,
            light.x,
            light.y,
            light.z
        )
    };
    let mut images = Vec::new();
    for casters in ["pvs", "pscs", "naive"] {
        let s = Scene::from_str(&text_for(casters), "<test>", std::path::Path::new(".")).unwrap();
        let plan = Setup::new(&s, &s.methods[0]).unwrap().plan(s.camera.position, 0.0);
        println!("{casters}: {} casters", plan.lights[0].caster_faces.len());
        images.push((render_scene(s.clone(), SIZE), s));
    }
    // The receiver point projects to the image centre (the camera looks at it).
    let (cx, cy) = (SIZE.0 / 2, SIZE.1 / 2);
    let around = |img: &HdrImage| {
        (cy - 1..=cy)
            .flat_map(|y| (cx - 1..=cx).map(move |x| (x, y)))
            .all(|(x, y)| !lit(img, x, y, 0.0))
    };
    assert!(
        !around(&images[0].0),
        "with PVS-only casters the receiver is (wrongly) lit"
    );
    assert!(around(&images[1].0), "with the PSCS the receiver is in shadow");
    assert!(around(&images[2].0), "brute force agrees");
    assert_eq!(
        differing(&images[1].0, &images[2].0),
        0,
        "PSCS and brute force give the same image"
    );
    let missing = differing(&images[0].0, &images[1].0);
    println!("PVS-only casters miss a shadow of {missing} pixels");
    assert!(missing > 10, "the missing shadow covers {missing} pixels");
}

/// Culling by the camera's PVS and by the lights' radii draws less, and changes no pixel.
#[test]
fn pvs_and_radius_culling_change_draws_not_pixels() {
    let with_entity = format!("{}\n[[objects]]\nname = \"crate\"\nmesh = \"box\"\nsize = 0.7\ntranslate = [7.0, 0.36, -8.0]\nmaterial = \"wall\"\n", rooms(&[0, 1]));
    let mut images = Vec::new();
    let mut draws = Vec::new();
    for params in [
        vec!["mode = \"faithful\""],
        vec!["mode = \"faithful\"", "pvs = false"],
        vec!["mode = \"faithful\"", "radius_culling = false"],
    ] {
        let s = scene(CAMERAS[0], &with_entity, &params);
        let plan = Setup::new(&s, &s.methods[0]).unwrap().plan(s.camera.position, 0.0);
        let receivers: usize = plan.lights.iter().map(|l| l.receiver_faces.len()).sum();
        let casters: usize = plan.lights.iter().map(|l| l.caster_faces.len()).sum();
        println!(
            "{params:?}: {} faces drawn, {} lights, {receivers} receivers, {casters} casters",
            plan.visible_faces.len(),
            plan.lights.len()
        );
        draws.push((plan.visible_faces.len(), receivers, casters));
        images.push(render_scene(s, SIZE));
    }
    assert_eq!(differing(&images[0], &images[1]), 0, "PVS culling changed pixels");
    assert_eq!(differing(&images[0], &images[2]), 0, "radius culling changed pixels");
    assert!(draws[0].0 < draws[1].0, "the camera's PVS culls faces: {draws:?}");
    assert!(
        draws[0].1 < draws[2].1 && draws[0].2 < draws[2].2,
        "radii cull receivers and casters: {draws:?}"
    );
}

/// Spot lights cull by their cone too (with `radius_culling`): receivers and casters wholly
/// beyond the outer angle are not drawn, and no pixel changes — against the same spot drawn
/// without culling, while the same lights as point lights draw more.
#[test]
fn spot_cone_culling_changes_draws_not_pixels() {
    let crate_obj = "[[objects]]\nname = \"crate\"\nmesh = \"box\"\nsize = 0.7\ntranslate = [7.0, 0.36, -8.0]\nmaterial = \"wall\"\n";
    // One spot on the crate, one on a far wall away from it.
    let spots = "[[lights]]\ntype = \"spot\"\nposition = [5.2, 2.7, -8.6]\ntarget = [7.0, 0.0, -8.0]\nintensity = [9, 7, 4.5]\ninner_deg = 25\nouter_deg = 35\nradius = 8.0\n\
                 [[lights]]\ntype = \"spot\"\nposition = [8.0, 2.2, -5.0]\ntarget = [3.0, 1.0, -4.0]\nintensity = [2, 4, 9]\ninner_deg = 20\nouter_deg = 30\nradius = 8.0\n";
    let points = "[[lights]]\ntype = \"point\"\nposition = [5.2, 2.7, -8.6]\nintensity = [9, 7, 4.5]\nradius = 8.0\n\
                  [[lights]]\ntype = \"point\"\nposition = [8.0, 2.2, -5.0]\nintensity = [2, 4, 9]\nradius = 8.0\n";
    let mut images = Vec::new();
    let mut draws = Vec::new();
    for (lights, params) in [
        (spots, vec!["mode = \"faithful\""]),
        (spots, vec!["mode = \"faithful\"", "radius_culling = false"]),
        (points, vec!["mode = \"faithful\""]),
    ] {
        let s = scene(CAMERAS[1], &format!("{WORLD}{crate_obj}{lights}"), &params);
        let plan = Setup::new(&s, &s.methods[0]).unwrap().plan(s.camera.position, 0.0);
        let count = |f: &dyn Fn(&penumbra::lighting::shadow_volumes::LightPlan) -> usize| {
            plan.lights.iter().map(f).sum::<usize>()
        };
        let d = (
            count(&|l| l.receiver_faces.len()),
            count(&|l| l.caster_faces.len()),
            count(&|l| l.receiver_entities.len()),
            count(&|l| l.caster_entities.len()),
        );
        println!(
            "{} {params:?}: receivers {}, casters {}, receiving entities {}, casting entities {}",
            if lights == spots { "spots" } else { "points" },
            d.0,
            d.1,
            d.2,
            d.3
        );
        draws.push(d);
        if lights == spots {
            images.push(render_scene(s, SIZE));
        }
    }
    let lit_pixels = images[0].pixels.iter().filter(|p| p[0] > 0.05).count();
    println!("{lit_pixels} pixels above 0.05");
    assert!(lit_pixels > 500, "the spots light the view");
    assert_eq!(differing(&images[0], &images[1]), 0, "cone culling changed pixels");
    let (culled, points) = (draws[0], draws[2]);
    assert!(
        culled.0 < points.0 && culled.1 < points.1,
        "the cones cull receivers and casters: {draws:?}"
    );
    assert!(
        culled.3 < points.3,
        "the spot aimed away does not extrude the crate: {draws:?}"
    );
    assert!(
        culled.0 < draws[1].0 && culled.1 < draws[1].1,
        "without culling the spots draw as much as the points: {draws:?}"
    );
}

/// `penumbra profile` on the test level lists the ambient pass, each drawn light's volume and
/// lighting passes and the silhouette compute pass.
#[test]
fn profile_breaks_out_every_pass() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bsp_rooms.toml");
    let opts = penumbra::commands::capture::CaptureOptions {
        scene: Some(path),
        png: None,
        exr: None,
        size: (64, 48),
        frames: 1,
        method: None,
        exposure: 1.0,
        gpu: common::test_gpu_desc(),
        config: None,
        supersample: 1,
        overrides: Default::default(),
    };
    let report = penumbra::commands::profile::run(&opts, 2).unwrap();
    let names: Vec<&str> = report.passes.iter().map(|p| p.name.as_str()).collect();
    println!("{}", report.table());
    for want in [
        "frame",
        "light 0 silhouettes",
        "ambient",
        "light 0 volumes",
        "light 0 lighting",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    let _ = Vec3::ZERO;
}

/// The textured level over several frames: the entities move (the silhouettes are recomputed
/// every frame), the first frame is the placement every other renderer sees (t = 0), and the
/// validation layer (with synchronization validation) has nothing to say across frames.
#[test]
fn entities_move_between_frames_without_validation_messages() {
    use penumbra::renderer::{FrameOutput, Renderer};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bsp_rooms.toml");
    let render_frames = |animate: bool, frames: usize| {
        let mut scene = Scene::from_file(&path).unwrap();
        scene.methods[0]
            .params
            .push(("animate".into(), toml::Value::Boolean(animate), 0));
        let mut r = Renderer::new(common::test_gpu(), scene, None, (80, 48), 2).unwrap();
        let cam = r.scene.camera.clone();
        let images: Vec<HdrImage> = (0..frames)
            .map(|_| r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap())
            .collect();
        common::assert_clean(&r.gpu);
        images
    };
    let moving = render_frames(true, 30);
    let still = render_frames(false, 1);
    assert_eq!(differing(&moving[0], &still[0]), 0, "frame 0 is the t = 0 pose");
    let moved = differing(&moving[0], &moving[29]);
    assert!(
        moved > 20,
        "half a second later the ball and crate have moved ({moved} pixels differ)"
    );
}

/// A frame with more passes than the timestamp pool holds (for each of 600 lights, its
/// silhouette passes, volumes and light mask: about 4,000, for 2,048 timed) still reports the
/// whole frame's time: the inner passes beyond the pool go untimed, never the frame around them.
#[test]
fn profile_times_the_frame_when_passes_outnumber_the_queries() {
    let text = r#"
methods = [{ name = "shadow_volumes", mode = "physical", animate = false }]
materials = [{ name = "grey", albedo = 0.5, specular = 0 }]
objects = [
    { name = "floor", mesh = "plane", size = 8, material = "grey" },
    { name = "crate", mesh = "box", size = 1, translate = [0, 0.6, 0], material = "grey" },
]
[camera]
position = [0, 6, 8]
target = [0, 0, 0]
[[light_arrays]]
name = "rig"
type = "point"
grid = [20, 1, 30]
min = [-4, 3, -4]
max = [4, 3, 4]
intensity = 0.01
"#;
    let dir = common::test_files::TestDir::new("queries");
    let path = dir.join("many_passes.toml");
    std::fs::write(&path, text).unwrap();
    let opts = penumbra::commands::capture::CaptureOptions {
        scene: Some(path),
        png: None,
        exr: None,
        size: (16, 16),
        frames: 1,
        method: None,
        exposure: 1.0,
        gpu: common::test_gpu_desc(),
        config: None,
        supersample: 1,
        overrides: Default::default(),
    };
    let report = penumbra::commands::profile::run(&opts, 1).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let names: Vec<&str> = report.passes.iter().map(|p| p.name.as_str()).collect();
    let volumes = names.iter().filter(|n| n.ends_with(" volumes")).count();
    println!("{} passes timed, {volumes} volume passes", names.len());
    assert!(
        volumes > 100 && volumes < 600,
        "the pool times some volume passes but not all 600 ({volumes})"
    );
    let frame = report
        .passes
        .iter()
        .find(|p| p.name == "frame")
        .expect("the frame's time is kept");
    let sum: f64 = report
        .passes
        .iter()
        .filter(|p| p.name.starts_with("light "))
        .map(|p| p.median_ms)
        .sum();
    assert!(
        frame.median_ms > sum,
        "the frame ({} ms) covers more than the timed light passes ({sum} ms)",
        frame.median_ms
    );
}

/// A sun in a BSP world is refused before anything is built, in one line naming the light: the
/// world's caster selection (the light's PVS and PSCS) starts from a light's position.
#[test]
fn a_sun_in_a_bsp_world_is_refused_in_one_line() {
    let sun = "[[lights]]\nname = \"noon\"\ntype = \"directional\"\ndirection = [0.2, -1, 0.1]\nirradiance = 2\n";
    let s = scene(CAMERAS[0], &(rooms(&[0]) + sun), &[]);
    let err = match Setup::new(&s, &s.methods[0]) {
        Ok(_) => panic!("a sun in a BSP world must be refused"),
        Err(e) => e.to_string(),
    };
    println!("{err}");
    assert!(
        err.contains("lights[1] (noon)")
            && err.contains("BSP world")
            && err.contains("position")
            && !err.contains('\n'),
        "{err}"
    );
}
