//! Stencil shadow volumes where they fail: the analytic occluder (a square of side 2 at height 5
//! under a light at height 10 casts a square of side 4), the camera inside a volume with the
//! near plane cutting it (z-fail right, z-pass visibly wrong), volumes reaching past any finite
//! far plane, more than 255 overlapping volumes, open (non-manifold) occluders, and a spot light
//! (the same shadow, no light outside its cone). Every rendered lit/shadowed mask is compared
//! with a CPU ray cast of the same geometry.

use crate::support as common;
use crate::support::shadow_volumes as sv_common;

use glam::Vec3;
use penumbra::scene::{Camera, Scene};
use sv_common::{compare_masks, hit_plane_y, lit, method, render, render_with_notes, MaskComparison};

const SIZE: (u32, u32) = (128, 128);

/// Ground (y = 0, ±20 m), a light at (0, 10, 0), an occluder given as object text, the camera.
fn analytic_scene(camera: &str, occluder: &str, params: &[&str]) -> String {
    format!(
        r#"{}
{camera}
[[materials]]
name = "grey"
albedo = 0.7

[[objects]]
name = "ground"
mesh = "plane"
size = 40
material = "grey"

{occluder}

[[lights]]
type = "point"
position = [0, 10, 0]
intensity = 100
"#,
        method(&[&["mode = \"physical\"", "animate = false"][..], params].concat())
    )
}

/// An open quad (two triangles, per-triangle volumes) of side 2 at height 5, facing up.
const QUAD: &str = r#"[[objects]]
name = "occluder"
mesh = "quad"
corner = [-1, 5, -1]
edge_u = [0, 0, 2]
edge_v = [2, 0, 0]
material = "grey""#;

/// A closed slab whose top face is the square of side 2 at height 5 (silhouette path).
const SLAB: &str = r#"[[objects]]
name = "occluder"
mesh = "box"
size = [2, 0.25, 2]
translate = [0, 4.875, 0]
material = "grey""#;

const TOP_DOWN: &str = r#"[camera]
position = [0, 25, 0]
target = [0, 0, 0]
up = [0, 0, -1]
fov_y_deg = 20"#;

/// CPU verdict for the analytic scene: the first hit of the pixel's ray among the occluder's
/// top (|x|, |z| ≤ 1 at y = 5, lit) and the ground (lit unless |x|, |z| ≤ 2 for the light at
/// height 10). `None` off the ground.
fn analytic_lit(cam: &Camera, px: f32, py: f32, size: (u32, u32)) -> Option<bool> {
    if let Some((p, _)) = hit_plane_y(cam, px, py, size, 5.0) {
        if p.x.abs() <= 1.0 && p.z.abs() <= 1.0 {
            return Some(true);
        }
    }
    let (p, _) = hit_plane_y(cam, px, py, size, 0.0)?;
    if p.x.abs() > 19.0 || p.z.abs() > 19.0 {
        return None;
    }
    Some(!(p.x.abs() <= 2.0 && p.z.abs() <= 2.0))
}

/// Whether the ray meets the box, and if so whether it enters through the top (+y) face.
fn hit_box(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> Option<bool> {
    let (mut t0, mut t1, mut axis) = (0.0f32, f32::INFINITY, 3);
    for a in 0..3 {
        let (n, f) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        let (n, f) = (n.min(f), n.max(f));
        if n > t0 {
            t0 = n;
            axis = a;
        }
        t1 = t1.min(f);
    }
    (t0 <= t1 && axis < 3).then_some(axis == 1 && d.y < 0.0)
}

fn check(c: &MaskComparison, what: &str) {
    println!("{what}: {c:?}");
    assert!(c.iou >= 0.99, "{what}: IoU {} < 0.99 ({c:?})", c.iou);
    assert_eq!(
        c.interior_mismatches, 0,
        "{what}: mismatches away from the shadow's edge ({c:?})"
    );
}

#[test]
fn analytic_occluder_casts_the_square_of_side_4() {
    for (name, occluder) in [
        ("open quad (per-triangle volumes)", QUAD),
        ("closed slab (silhouettes)", SLAB),
    ] {
        for camera in [
            TOP_DOWN,
            "[camera]\nposition = [7, 14, 9]\ntarget = [0, 0, 0]\nfov_y_deg = 35",
        ] {
            let (img, scene) = render(&analytic_scene(camera, occluder, &[]), SIZE);
            let c = compare_masks(
                SIZE.0,
                SIZE.1,
                |x, y| lit(&img, x, y, 1e-6),
                |px, py| {
                    if occluder == SLAB {
                        // The slab's sides face away from the light: a ray that meets the slab is
                        // lit only on its top.
                        let (o, d) = scene.camera.ray(px, py, SIZE.0, SIZE.1);
                        if let Some(top) = hit_box(o, d, Vec3::new(-1.0, 4.75, -1.0), Vec3::new(1.0, 5.0, 1.0)) {
                            return Some(top);
                        }
                    }
                    analytic_lit(&scene.camera, px, py, SIZE)
                },
            );
            check(&c, name);
            assert!(c.cpu_shadow > 500, "the shadow is in view");
        }
    }
}

/// The occluder above the view, its shadow in it: casters are chosen by the light, not by what
/// the camera sees, and with the caps out of view the sides alone count the shadow right.
#[test]
fn an_occluder_out_of_view_still_casts() {
    let camera = "[camera]\nposition = [0, 3, 9]\ntarget = [0, 0, 0]\nfov_y_deg = 30";
    for (name, occluder) in [("open quad", QUAD), ("closed slab", SLAB)] {
        let (img, scene) = render(&analytic_scene(camera, occluder, &[]), SIZE);
        let c = compare_masks(
            SIZE.0,
            SIZE.1,
            |x, y| lit(&img, x, y, 1e-6),
            |px, py| {
                let (o, d) = scene.camera.ray(px, py, SIZE.0, SIZE.1);
                assert!(
                    hit_box(o, d, Vec3::new(-1.0, 4.75, -1.0), Vec3::new(1.0, 5.0, 1.0)).is_none(),
                    "the occluder is out of view"
                );
                analytic_lit(&scene.camera, px, py, SIZE)
            },
        );
        check(&c, name);
        assert!(c.cpu_shadow > 1000, "the shadow is in view: {c:?}");
    }
}

/// The side of the shadow, measured on the rendered image: ground pixels in shadow (not hidden
/// by the occluder) plus the occluder's own pixels, as area on the ground, is 16 m².
#[test]
fn shadow_area_is_16_square_metres() {
    let (img, scene) = render(&analytic_scene(TOP_DOWN, QUAD, &[]), SIZE);
    let mut area = 0.0f64;
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            // Ground area of the pixel (its footprint on y = 0), counted when unlit or occluder.
            let corners: Vec<Vec3> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                .iter()
                .map(|&(dx, dy)| {
                    hit_plane_y(&scene.camera, x as f32 + dx, y as f32 + dy, SIZE, 0.0)
                        .unwrap()
                        .0
                })
                .collect();
            let a = 0.5
                * ((corners[1] - corners[0]).cross(corners[2] - corners[0]).length()
                    + (corners[2] - corners[0]).cross(corners[3] - corners[0]).length());
            let on_occluder = hit_plane_y(&scene.camera, x as f32 + 0.5, y as f32 + 0.5, SIZE, 5.0)
                .is_some_and(|(p, _)| p.x.abs() <= 1.0 && p.z.abs() <= 1.0);
            if on_occluder || !lit(&img, x, y, 1e-6) {
                area += f64::from(a);
            }
        }
    }
    // One pixel's ground footprint is about 0.07 m wide: the perimeter of 16 m allows ±1.2 m².
    assert!(
        (area - 16.0).abs() < 1.2,
        "shadow area {area} m² (side {})",
        area.sqrt()
    );
}

/// The camera below the occluder, inside its shadow volume, looking at the ground: the near
/// plane cuts the volume. z-fail gets the mask right; z-pass inverts it.
#[test]
fn camera_inside_a_volume_z_fail_is_right_and_z_pass_is_wrong() {
    let camera = "[camera]\nposition = [0.3, 2.0, 0.2]\ntarget = [2.5, 0.0, 1.8]\nfov_y_deg = 80\nnear = 0.05";
    let cam_pos = Vec3::new(0.3, 2.0, 0.2);
    // Inside the frustum from the light over the slab's top: half-size 1 · (10 − 2) / 5 = 1.6 at y = 2.
    assert!(cam_pos.x.abs() < 1.6 && cam_pos.z.abs() < 1.6);
    let mut results = Vec::new();
    for stencil in ["zfail", "zpass"] {
        let (img, scene) = render(
            &analytic_scene(camera, SLAB, &[&format!("stencil = \"{stencil}\"")]),
            SIZE,
        );
        let c = compare_masks(
            SIZE.0,
            SIZE.1,
            |x, y| lit(&img, x, y, 1e-6),
            |px, py| analytic_lit(&scene.camera, px, py, SIZE),
        );
        println!("{stencil}: {c:?}");
        results.push(c);
    }
    check(&results[0], "z-fail, camera in the volume");
    assert!(
        results[0].cpu_shadow > 1000 && results[0].pixels - results[0].cpu_shadow > 1000,
        "both shadow and light in view"
    );
    assert!(
        results[1].mismatches * 2 > results[1].pixels,
        "z-pass must be visibly wrong: {:?}",
        results[1]
    );
}

/// Z-pass where it is exact: with the camera outside every volume, the default counting draws
/// the volumes by z-pass, without caps, and gives the z-fail image bit for bit; with the camera
/// inside one (the near plane cutting it), that occluder by z-fail and the rest by z-pass,
/// entity by entity, with or without a second occluder in view.
#[test]
fn z_pass_is_taken_exactly_where_the_near_plane_cuts_no_volume() {
    let inside = "[camera]\nposition = [0.3, 2.0, 0.2]\ntarget = [2.5, 0.0, 1.8]\nfov_y_deg = 80\nnear = 0.05";
    let outside = "[camera]\nposition = [7, 14, 9]\ntarget = [0, 0, 0]\nfov_y_deg = 35";
    // Its shadow falls in the inside camera's view, and its volume misses that camera.
    let post = "[[objects]]\nname = \"post\"\nmesh = \"box\"\nsize = [0.5, 2, 0.5]\ntranslate = [3, 1, 2.5]\nmaterial = \"grey\"";
    let two = |occluder: &str| format!("{occluder}\n\n{post}");
    for (camera, way, occluders) in [
        (outside, "1 by z-pass alone; ", [QUAD.to_string(), SLAB.to_string()]),
        // The ground casts too (below itself), by z-pass: the light takes both ways.
        (
            inside,
            "0 by z-pass alone, 1 by both",
            [QUAD.to_string(), SLAB.to_string()],
        ),
        (inside, "0 by z-pass alone, 1 by both", [two(QUAD), two(SLAB)]),
    ] {
        for (name, occluder) in ["open quad", "closed slab"].into_iter().zip(&occluders) {
            let scene = |params: &[&str]| {
                Scene::from_str(
                    &analytic_scene(camera, occluder, params),
                    "<test>",
                    std::path::Path::new("."),
                )
                .unwrap()
            };
            let (chosen, notes) = render_with_notes(scene(&[]), SIZE);
            let (zfail, _) = render_with_notes(scene(&["stencil = \"zfail\""]), SIZE);
            assert!(notes.len() == 1 && notes[0].contains(way), "{name}: {notes:?}");
            assert!(chosen.pixels == zfail.pixels, "{name}: the image differs from z-fail's");
        }
    }
}

/// A light 100 m up, a 1 m slab 1 m below it, the camera 330 m away: the volume is extruded to
/// infinity and its far cap sits at depth 1. With depth clamp and with the infinite projection
/// alone (the far cap nudged inside), the 100 m shadow on the ground is right.
#[test]
fn volumes_reach_past_any_finite_far_plane() {
    let scene_text = |clamp: bool| {
        format!(
            r#"{}
[camera]
position = [0, 300, 140]
target = [0, 0, 0]
fov_y_deg = 40

[[materials]]
name = "grey"
albedo = 0.7

[[objects]]
mesh = "plane"
size = 400
material = "grey"

[[objects]]
mesh = "box"
size = [1, 0.2, 1]
translate = [0, 98.9, 0]
material = "grey"

[[lights]]
type = "point"
position = [0, 100, 0]
intensity = 20000
"#,
            method(&["mode = \"physical\"", &format!("depth_clamp = {clamp}")])
        )
    };
    for clamp in [true, false] {
        let (img, scene) = render(&scene_text(clamp), SIZE);
        let c = compare_masks(
            SIZE.0,
            SIZE.1,
            |x, y| lit(&img, x, y, 1e-9),
            |px, py| {
                if let Some((p, _)) = hit_plane_y(&scene.camera, px, py, SIZE, 99.0) {
                    if p.x.abs() <= 0.6 && p.z.abs() <= 0.6 {
                        return None;
                    }
                }
                let (p, _) = hit_plane_y(&scene.camera, px, py, SIZE, 0.0)?;
                if p.x.abs() > 199.0 || p.z.abs() > 199.0 {
                    return None;
                }
                // Top of the slab at 99: shadow half-size 0.5 · 100 / 1 = 50.
                Some(!(p.x.abs() <= 50.0 && p.z.abs() <= 50.0))
            },
        );
        check(&c, &format!("far shadow, depth clamp {clamp}"));
        assert!(c.cpu_shadow > 2000);
    }
}

/// 300 open quads stacked between heights 5 and 6, each sized so its shadow is the same square
/// of side 4: 300 volumes (one per quad: its two triangles share their inner edge, which has no
/// sides) overlap under the stack. With wrapping increments the count (300 ≡ 44 mod 256) stays
/// non-zero inside and returns to 0 outside; with saturating ones (`stencil_wrap = false`) it
/// does not under z-fail: outside, the sides behind the ground (decrements, drawn first) stop at
/// 0 and the far caps then count to 255. (The default counting takes z-pass here, the camera
/// being outside every volume, so the negative control asks for z-fail.)
#[test]
fn more_than_255_overlapping_volumes() {
    let dir = common::temp_path("sv-stack");
    std::fs::create_dir_all(&dir).unwrap();
    let mut obj = String::new();
    for k in 0..300 {
        let h = 5.0 + k as f32 / 300.0;
        let s = 2.0 * (10.0 - h) / 10.0;
        obj += &format!(
            "v {} {h} {}\nv {} {h} {}\nv {} {h} {}\nv {} {h} {}\n",
            -s, -s, -s, s, s, s, s, -s
        );
        let b = 4 * k + 1;
        obj += &format!("f {} {} {} {}\n", b, b + 1, b + 2, b + 3);
    }
    std::fs::write(dir.join("stack.obj"), obj).unwrap();
    let stack = "[[objects]]\nname = \"stack\"\nmesh = \"obj\"\npath = \"stack.obj\"\nmaterial = \"grey\"";
    let mut stats = Vec::new();
    for wrap in [true, false] {
        let stencil = if wrap { "auto" } else { "zfail" };
        let text = analytic_scene(
            TOP_DOWN,
            stack,
            &[&format!("stencil_wrap = {wrap}"), &format!("stencil = \"{stencil}\"")],
        );
        let (img, scene) = sv_common::render_in(&text, &dir, SIZE);
        let c = compare_masks(
            SIZE.0,
            SIZE.1,
            |x, y| lit(&img, x, y, 1e-6),
            |px, py| {
                // The top quad (height 6 − 1/300, half-size 0.8) hides the rest of the stack.
                if let Some((p, _)) = hit_plane_y(&scene.camera, px, py, SIZE, 5.0) {
                    if p.x.abs() <= 1.0 && p.z.abs() <= 1.0 {
                        return None;
                    }
                }
                analytic_lit(&scene.camera, px, py, SIZE)
            },
        );
        println!("wrap {wrap}: {c:?}");
        stats.push(c);
    }
    check(&stats[0], "300 overlapping volumes, wrapping stencil");
    assert!(stats[0].cpu_shadow > 500);
    // Negative control: saturating increments lose the count and darken the lit ground.
    assert!(
        stats[1].interior_mismatches > 1000,
        "saturating stencil should fail here: {:?}",
        stats[1]
    );
}

const POINT_LIGHT: &str = "type = \"point\"\nposition = [0, 10, 0]\nintensity = 100";

/// A sun travelling along (0.3, -1, 0.2) over the analytic occluders: the ground is dark
/// exactly where a ray toward the sun meets the occluder (the square of side 2 moved along
/// the direction, not enlarged: the volumes are parallel), seen from above, obliquely, and from
/// inside the volume under the occluder (z-fail with the volumes' far ends at one point at
/// infinity). Lit ground reads the closed form ρ/π · E · cos θ.
#[test]
fn a_sun_casts_the_occluder_moved_along_its_direction() {
    let travel = Vec3::new(0.3, -1.0, 0.2).normalize();
    let sun = "type = \"directional\"\nname = \"sun\"\ndirection = [0.3, -1, 0.2]\nirradiance = 3";
    let inside = "[camera]\nposition = [1.0, 1.5, 0.6]\ntarget = [4.0, 0.0, 2.0]\nfov_y_deg = 80\nnear = 0.05";
    // The camera stands in the occluder's shadow.
    let eye = Vec3::new(1.0, 1.5, 0.6);
    let t = (5.0 - eye.y) / -travel.y;
    let above = eye - travel * t;
    assert!(
        above.x.abs() < 1.0 && above.z.abs() < 1.0,
        "the camera is under the occluder: {above}"
    );
    let closed_form = 0.7 / std::f32::consts::PI * 3.0 * -travel.y;
    for (name, occluder, thickness) in [
        ("open quad (two-sided, sides on its border only)", QUAD, 0.0),
        ("closed slab (silhouettes)", SLAB, 0.25),
    ] {
        let (lo, hi) = (Vec3::new(-1.0, 5.0 - thickness, -1.0), Vec3::new(1.0, 5.0, 1.0));
        // From straight above, pixel centres lie on the quad's diagonal: an inner edge, which
        // has no side faces to count one way or the other.
        for camera in [
            TOP_DOWN,
            "[camera]\nposition = [7, 14, 9]\ntarget = [0, 0, 0]\nfov_y_deg = 35",
            inside,
        ] {
            let (img, scene) = render(&analytic_scene(camera, occluder, &[]).replace(POINT_LIGHT, sun), SIZE);
            let c = compare_masks(
                SIZE.0,
                SIZE.1,
                |x, y| lit(&img, x, y, 1e-6),
                |px, py| {
                    let (o, d) = scene.camera.ray(px, py, SIZE.0, SIZE.1);
                    if let Some(top) = hit_box(o, d, lo, hi) {
                        // Only the top faces the sun.
                        return Some(top);
                    }
                    let (p, _) = hit_plane_y(&scene.camera, px, py, SIZE, 0.0)?;
                    if p.x.abs() > 19.0 || p.z.abs() > 19.0 {
                        return None;
                    }
                    Some(hit_box(p, -travel, lo, hi).is_none())
                },
            );
            check(&c, &format!("{name}, {}", camera.lines().nth(1).unwrap_or("")));
            assert!(c.cpu_shadow > 300, "the shadow is in view ({c:?})");
            // Lit ground away from the shadow: the closed form.
            let mut worst = 0.0f32;
            for y in 0..SIZE.1 {
                for x in 0..SIZE.0 {
                    let Some((p, _)) = hit_plane_y(&scene.camera, x as f32 + 0.5, y as f32 + 0.5, SIZE, 0.0) else {
                        continue;
                    };
                    let (o, d) = scene.camera.ray(x as f32 + 0.5, y as f32 + 0.5, SIZE.0, SIZE.1);
                    let clear = p - travel * ((5.0 - p.y) / -travel.y);
                    if hit_box(o, d, lo, hi).is_none()
                        && p.x.abs() < 19.0
                        && p.z.abs() < 19.0
                        && (clear.x.abs() > 1.2 || clear.z.abs() > 1.2)
                    {
                        worst = worst.max((img.get(x, y)[0] / closed_form - 1.0).abs());
                    }
                }
            }
            assert!(
                worst < 1e-4,
                "lit ground against ρ/π·E·cos θ: worst relative error {worst}"
            );
        }
    }
}

/// Only point, spot and directional lights: an area light is refused with one clear line that
/// names the light and says why.
#[test]
fn other_light_kinds_are_refused_clearly() {
    for (light, kind, why) in [
        ("name = \"panel\"\ntype = \"quad\"\ncorner = [-1, 10, -1]\nedge_u = [2, 0, 0]\nedge_v = [0, 0, 2]\nradiance = 1", "quad", "soft shadows"),
        ("name = \"globe\"\ntype = \"sphere\"\ncenter = [0, 10, 0]\nradius = 0.5\nradiance = 1", "sphere", "soft shadows"),
    ] {
        let text = analytic_scene(TOP_DOWN, QUAD, &[]).replace(POINT_LIGHT, light);
        let scene = penumbra::scene::Scene::from_str(&text, "<test>", std::path::Path::new(".")).unwrap();
        let name = scene.lights[0].name().to_string();
        let err = match penumbra::renderer::Renderer::new(common::test_gpu(), scene, None, SIZE, 1) {
            Ok(_) => panic!("a {kind} light must be refused"),
            Err(e) => e.to_string(),
        };
        println!("{err}");
        assert!(err.contains("point, spot and directional lights only") && err.contains(&format!("({name})")) && err.contains(kind) && err.contains(why) && !err.contains('\n'), "{err}");
    }
}

/// A spot light straight down over the analytic occluder: the shadow is the point light's square
/// of side 4 (the volumes are a point light's), the ground is lit only inside the outer cone
/// (30°: 5.77 m from the axis) and exactly dark beyond it.
#[test]
fn spot_light_casts_the_same_square_and_nothing_outside_its_cone() {
    let camera = "[camera]\nposition = [0, 25, 0]\ntarget = [0, 0, 0]\nup = [0, 0, -1]\nfov_y_deg = 40";
    let spot = "type = \"spot\"\nposition = [0, 10, 0]\ndirection = [0, -1, 0]\nintensity = 100\ninner_deg = 20\nouter_deg = 30";
    let (outer, inner) = (30f32.to_radians(), 20f32.to_radians());
    let (point_img, _) = render(&analytic_scene(camera, QUAD, &[]), SIZE);
    let (img, scene) = render(&analytic_scene(camera, QUAD, &[]).replace(POINT_LIGHT, spot), SIZE);
    // The angle from the axis of the ground point under continuous pixel (px, py).
    let ground_angle =
        |px: f32, py: f32| hit_plane_y(&scene.camera, px, py, SIZE, 0.0).map(|(p, _)| (p.x.hypot(p.z) / 10.0).atan());
    let c = compare_masks(
        SIZE.0,
        SIZE.1,
        |x, y| lit(&img, x, y, 1e-6),
        |px, py| {
            let lit = analytic_lit(&scene.camera, px, py, SIZE)?;
            // The occluder's top is well inside the inner cone.
            let on_top = hit_plane_y(&scene.camera, px, py, SIZE, 5.0)
                .is_some_and(|(p, _)| p.x.abs() <= 1.0 && p.z.abs() <= 1.0);
            Some(lit && (on_top || ground_angle(px, py)? < outer))
        },
    );
    check(&c, "spot light");
    // Inside the inner cone the spot is the point light, shadow included, pixel for pixel.
    let (mut inside, mut same, mut outside, mut dark) = (0, 0, 0, 0);
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let Some(a) = ground_angle(x as f32 + 0.5, y as f32 + 0.5) else {
                continue;
            };
            if a < inner - 0.01 {
                inside += 1;
                same += usize::from(img.get(x, y)[..3] == point_img.get(x, y)[..3]);
            } else if a > outer + 0.01 {
                outside += 1;
                dark += usize::from(img.get(x, y)[..3].iter().all(|&v| v == 0.0));
            }
        }
    }
    println!("inside the inner cone {same} of {inside} pixels equal the point light's; outside the outer cone {dark} of {outside} exactly 0");
    assert!(
        inside > 1000 && outside > 2000,
        "both regions are in view: {inside}, {outside}"
    );
    assert_eq!(same, inside, "inside the inner cone the spot equals the point light");
    assert_eq!(dark, outside, "outside the outer cone nothing is lit");
}
