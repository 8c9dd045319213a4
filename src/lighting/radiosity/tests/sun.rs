//! The sun (digest §5.4): the shadow of a square occluder on a floor against the analytic one,
//! sky surfaces neither lit nor lighting, and the `sky` flag's errors.

use glam::DVec3;

use super::border::bake_text;

use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::{Mode, Occluders, Settings};
use crate::lighting::radiosity::sun;
use crate::scene::Scene;

const SUN: [f64; 3] = [0.35, -1.0, 0.2];

/// A 4 m floor, a 1 m square 0.8 m above it and, unless `sky` is false, a sky ceiling at 5 m.
fn scene(sky: bool) -> String {
    let mut s = format!(
        r#"
methods = ["radiosity"]
[camera]
position = [0, 3, 4]
target = [0, 0, 0]
[[materials]]
name = "grey"
albedo = 0.5
[[materials]]
name = "sky"
albedo = 0.5
emission = [0.3, 0.5, 0.9]
sky = true
[[objects]]
name = "floor"
mesh = "quad"
corner = [-2, 0, -2]
edge_u = [0, 0, 4]
edge_v = [4, 0, 0]
material = "grey"
[[objects]]
name = "blocker"
mesh = "quad"
corner = [-0.37, 0.8, -0.41]
edge_u = [1, 0, 0]
edge_v = [0, 0, 1]
material = "grey"
[[lights]]
type = "directional"
direction = {SUN:?}
irradiance = 3
"#
    );
    if sky {
        s += "[[objects]]\nname = \"sky\"\nmesh = \"quad\"\ncorner = [-10, 5, -10]\nedge_u = [20, 0, 0]\nedge_v = [0, 0, 20]\nmaterial = \"sky\"\n";
    }
    s
}

/// The analytic shadow: the blocker [-0.37, 0.63] × [-0.41, 0.59] at 0.8 m moved along the sun
/// to the floor; its area inside the cell [x0, x0 + s] × [z0, z0 + s].
fn shadow_overlap(x0: f64, z0: f64, s: f64) -> f64 {
    let d = DVec3::from_array(SUN);
    let (sx, sz) = (0.8 * d.x / -d.y, 0.8 * d.z / -d.y);
    let (lo_x, hi_x, lo_z, hi_z) = (-0.37 + sx, 0.63 + sx, -0.41 + sz, 0.59 + sz);
    let ox = (hi_x.min(x0 + s) - lo_x.max(x0)).max(0.0);
    let oz = (hi_z.min(z0 + s) - lo_z.max(z0)).max(0.0);
    ox * oz / (s * s)
}

#[test]
fn a_square_occluder_casts_the_analytic_shadow() {
    let size = 0.05;
    for (sky, mode) in [
        (true, Mode::Faithful),
        (true, Mode::Corrected),
        (false, Mode::Corrected),
        (false, Mode::Faithful),
    ] {
        let text = scene(sky);
        let sc = Scene::from_str(&text, "sun.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
        let geo = crate::lighting::lightmap::geometry::scene_geometry(&sc, "radiosity").unwrap();
        let p = Patches::build(&geo.triangles, size);
        let occ = Occluders::new(&geo.triangles);
        let to_sun = -DVec3::from_array(SUN).normalize();
        let lit = sun::lit_fraction(&p, &occ, to_sun, mode, None).unwrap();
        let floor = p.charts.iter().position(|c| c.object == 0).unwrap();
        let c = &p.charts[floor];
        let (mut inter, mut union, mut shadowed, mut coverage_error) = (0usize, 0usize, 0usize, 0.0f64);
        let mut n = 0;
        for (k, q) in p.patches.iter().enumerate().skip(c.first).take(c.width * c.height) {
            if !q.inside() {
                continue;
            }
            // The cell's corner in world x and z (the floor's u, v frame is axis-aligned).
            let (x0, z0) = (q.centre.x - size / 2.0, q.centre.z - size / 2.0);
            let truth = shadow_overlap(x0, z0, size);
            let (analytic, computed) = (shadow_overlap(q.centre.x, q.centre.z, 1e-9) > 0.5, lit[k] < 0.5);
            inter += usize::from(analytic && computed);
            union += usize::from(analytic || computed);
            shadowed += usize::from(analytic);
            coverage_error += ((1.0 - lit[k]) - truth).abs();
            n += 1;
        }
        let iou = inter as f64 / union as f64;
        eprintln!("sky {sky}, {mode:?}: IoU {iou:.4} ({inter}/{union}, analytic {shadowed} patches), mean |shadow fraction − exact overlap| {:.4}", coverage_error / n as f64);
        assert!(shadowed > 300, "{shadowed}");
        assert!(iou >= 0.98, "sky {sky}, {mode:?}: IoU {iou}");
    }
}

#[test]
fn sky_is_neither_lit_nor_patched_and_rays_must_reach_it() {
    // With a sky ceiling the faithful sun lights the floor; with the ceiling an ordinary surface
    // instead, no ray reaches sky and the faithful floor is dark. The sky chart is one black
    // texel, and its pairs are NONE (3 charts: 6 pairs, all counted).
    let faithful = Settings {
        mode: Mode::Faithful,
        threshold: 1e-2,
        ..Settings::default()
    };
    let b = bake_text(&scene(true), 0.2, &faithful);
    let sky = b.charts_of("sky")[0];
    assert_eq!((b.p.charts[sky].width, b.p.charts[sky].height), (1, 1));
    assert!(
        b.chart_texels(sky).iter().all(|t| t[..3] == [0.0; 3]),
        "sky texels are black"
    );
    let floor_max = |b: &super::border::Baked| {
        b.chart_texels(b.charts_of("floor")[0])
            .iter()
            .map(|t| t[0])
            .fold(0.0f32, f32::max)
    };
    assert!(floor_max(&b) > 0.5, "the sun reaches the floor: {}", floor_max(&b));
    assert_eq!(
        b.report.visibility.2 + b.report.visibility.1 + b.report.visibility.0,
        6,
        "3 charts"
    );
    let closed = scene(true).replace("sky = true", "sky = false");
    assert_eq!(
        floor_max(&bake_text(&closed, 0.2, &faithful)),
        0.0,
        "faithful: no ray reaches sky"
    );
    // Errors name the file and the field.
    let e = match Scene::from_str(
        &scene(true).replace("sky = true", "sky = 1"),
        "sun.toml",
        std::path::Path::new("."),
    ) {
        Ok(_) => panic!("sky = 1 accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("sun.toml") && e.contains("materials[1].sky") && !e.contains('\n'),
        "{e}"
    );
}

/// The sun's and the sky's ray loops stop when the bake is cancelled, returning nothing, and run
/// to the end otherwise.
#[test]
fn the_sun_and_sky_ray_loops_stop_when_cancelled() {
    let text = scene(false) + "[environment]\ntype = \"constant\"\nradiance = 1.0\n";
    let sc = Scene::from_str(&text, "sun.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let geo = crate::lighting::lightmap::geometry::scene_geometry(&sc, "radiosity").unwrap();
    let p = Patches::build(&geo.triangles, 0.25);
    let occ = Occluders::new(&geo.triangles);
    let env = crate::environment::EnvironmentMap::of_scene(&sc).unwrap();
    let points: Vec<Vec<DVec3>> = p.patches.iter().map(|q| vec![q.centre + q.normal * 1e-4]).collect();
    let to_sun = -DVec3::from_array(SUN).normalize();
    let cancelled = crate::util::progress::Cancel::new();
    cancelled.cancel();
    let running = crate::util::progress::Cancel::new();
    for mode in [Mode::Corrected, Mode::Faithful] {
        assert!(sun::lit_fraction(&p, &occ, to_sun, mode, Some(&cancelled)).is_none());
        let lit = sun::lit_fraction(&p, &occ, to_sun, mode, Some(&running)).unwrap();
        assert!(lit.iter().any(|&f| f > 0.0));
    }
    let sky = crate::lighting::radiosity::environment_light::irradiance;
    assert!(sky(&p, &occ, &env, &points, Some(&cancelled)).is_none());
    let e = sky(&p, &occ, &env, &points, Some(&running)).unwrap();
    assert!(e.iter().any(|e| e.x > 0.0));
}
