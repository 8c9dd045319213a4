use glam::DVec3;

mod border;
mod buried;
mod charts;
mod curved;
mod edge_blocks;
mod stop;
mod sun;
mod thin_walls;
mod visibility;

use crate::lighting::lightmap::patches::{Patches, Triangle};
use crate::lighting::lightmap::solve::{solve, Mode, Occluders, Settings};
use crate::util::progress::Progress;

/// A closed box [0, s]³ of inward-facing quads (two triangles each) of one albedo; `emit(face)`
/// gives each face's emitted radiance.
fn closed_box(s: f64, albedo: f64, emit: impl Fn(usize) -> f64) -> Vec<Triangle> {
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) * s;
    let faces = [
        [c(0., 0., 0.), c(1., 0., 0.), c(1., 0., 1.), c(0., 0., 1.)], // floor, normal +y
        [c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)], // ceiling, -y
        [c(0., 0., 0.), c(0., 0., 1.), c(0., 1., 1.), c(0., 1., 0.)], // x = 0, +x
        [c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)], // x = 1, -x
        [c(0., 0., 0.), c(0., 1., 0.), c(1., 1., 0.), c(1., 0., 0.)], // z = 0, +z
        [c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)], // z = 1, -z
    ];
    let mut out = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        let e = DVec3::splat(emit(i));
        for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            out.push(Triangle {
                p: t,
                object: i,
                albedo: DVec3::splat(albedo),
                emission: e,
                sky: false,
                part: 0,
            });
        }
    }
    // Every face looks into the box (the corner lists above are not all wound alike).
    let centre = DVec3::splat(0.5 * s);
    for t in &mut out {
        if t.normal().dot(centre - t.p[0]) < 0.0 {
            t.p.swap(1, 2);
        }
    }
    out
}

fn run(tris: &[Triangle], size: f64, settings: &Settings) -> (Patches, crate::lighting::lightmap::solve::Report) {
    let mut p = Patches::build(tris, size);
    let occ = Occluders::new(tris);
    let report = solve(&mut p, &occ, settings, &mut Progress::new("test"));
    (p, report)
}

#[test]
fn closed_box_energy_balance_and_uniform_exitance() {
    let rho = 0.5;
    // Uniform emission radiance 1/π is radiosity 1: B = E/(1 − ρ) = 2 on every patch.
    let tris = closed_box(1.0, rho, |_| 1.0 / std::f64::consts::PI);
    let settings = Settings {
        threshold: 1e-5,
        ..Settings::default()
    };
    let (p, report) = run(&tris, 0.25, &settings);
    let emitted = p.power(|q| q.emission).x;
    let total = p.power(|q| q.total).x;
    let rel = (total - emitted / (1.0 - rho)).abs() / (emitted / (1.0 - rho));
    assert!(
        (emitted - 6.0).abs() < 1e-9,
        "the box's emitted power is its area: {emitted}"
    );
    eprintln!("uniform box: Σ A·B relative error {rel:.2e}, {} shots", report.shots);
    assert!(
        rel < 1e-3,
        "Σ A·B = {total} against Σ A·E/(1 − ρ) = {}: {rel:.2e}",
        emitted / (1.0 - rho)
    );
    let worst = p
        .patches
        .iter()
        .filter(|q| q.inside())
        .map(|q| (q.total.x - 2.0).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.01, "largest per-patch deviation from E/(1 − ρ) = 2: {worst}");
    // The unshot power falls geometrically: after every patch has shot once more (a sweep of 24
    // blocks of 3×3 patches, with the partial ones), about ρ times what it was.
    let u = &report.unshot_power;
    let sweep = 24;
    assert!(u.len() > 3 * sweep, "{} shots", u.len());
    for k in 1..3 {
        let ratio = u[k * sweep] / u[(k - 1) * sweep];
        assert!(ratio < 0.75 && ratio > 0.2, "sweep {k}: unshot power ratio {ratio}");
    }
}

#[test]
fn emission_anywhere_closes_energy_in_corrected_mode_and_not_exactly_in_faithful() {
    let rho = 0.6;
    // Only the ceiling emits: Σ A·B = Σ A·E/(1 − ρ) still, whatever the geometry.
    let tris = closed_box(2.0, rho, |f| if f == 1 { 1.0 } else { 0.0 });
    let settings = Settings {
        threshold: 1e-5,
        ..Settings::default()
    };
    let (p, _) = run(&tris, 0.25, &settings);
    let want = p.power(|q| q.emission).x / (1.0 - rho);
    let corrected = p.power(|q| q.total).x;
    assert!(
        (corrected - want).abs() / want < 1e-3,
        "corrected: {corrected} vs {want}"
    );
    let (pf, rf) = run(
        &tris,
        0.25,
        &Settings {
            mode: Mode::Faithful,
            ..settings
        },
    );
    let faithful = pf.power(|q| q.total).x;
    // The point-sampled form factors with the near-field clamp do not sum to 1: the faithful
    // solution misses energy by a few per cent at this patch size (digest §5.4).
    let miss = (faithful - want) / want;
    eprintln!(
        "ceiling-lit box: corrected {:+.2e}, faithful {miss:+.3} ({} full searches)",
        (corrected - want) / want,
        rf.full_searches
    );
    assert!(
        miss.abs() > 5e-3 && miss.abs() < 0.2,
        "faithful: {faithful} vs {want} ({miss:+.3})"
    );
    assert!(rf.full_searches >= 1, "the faithful selection ends with a full search");
}

#[test]
fn an_occluder_casts_a_shadow_and_a_closed_room_keeps_its_light() {
    // Two boxes side by side sharing no opening: light in the first stays in the first.
    let mut tris = closed_box(1.0, 0.5, |f| if f == 1 { 1.0 } else { 0.0 });
    let second: Vec<Triangle> = closed_box(1.0, 0.5, |_| 0.0)
        .into_iter()
        .map(|mut t| {
            for p in &mut t.p {
                p.x += 1.05;
            }
            t.object += 6;
            t
        })
        .collect();
    tris.extend(second);
    let (p, _) = run(
        &tris,
        0.25,
        &Settings {
            threshold: 1e-4,
            ..Settings::default()
        },
    );
    let dark = p
        .patches
        .iter()
        .filter(|q| q.inside() && p.charts[q.chart].object >= 6)
        .map(|q| q.total.x)
        .fold(0.0, f64::max);
    assert_eq!(dark, 0.0, "light leaked into the closed neighbour");
    let lit = p
        .patches
        .iter()
        .filter(|q| q.inside() && p.charts[q.chart].object == 0)
        .map(|q| q.total.x)
        .fold(0.0, f64::max);
    assert!(lit > 0.1, "the first box's floor is lit: {lit}");
}

#[test]
fn a_one_sided_emitter_lights_only_what_it_faces() {
    // A small emitter facing down (-y) between a floor below and a ceiling above it.
    let quad = |y: f64, s: f64, down: bool, object: usize, emission: f64, albedo: f64| {
        let (a, b, c, d) = (
            DVec3::new(-s, y, -s),
            DVec3::new(s, y, -s),
            DVec3::new(s, y, s),
            DVec3::new(-s, y, s),
        );
        let tris = if down {
            [[a, b, c], [a, c, d]]
        } else {
            [[a, c, b], [a, d, c]]
        };
        tris.map(|p| Triangle {
            p,
            object,
            albedo: DVec3::splat(albedo),
            emission: DVec3::splat(emission),
            sky: false,
            part: 0,
        })
    };
    let mut tris = Vec::new();
    tris.extend(quad(0.0, 1.0, false, 0, 0.0, 0.5)); // floor, facing up
    tris.extend(quad(1.0, 0.2, true, 1, 1.0, 0.0)); // emitter, facing down
    tris.extend(quad(1.5, 1.0, true, 2, 0.0, 0.5)); // ceiling above it, facing down
    assert!(tris[0].normal().y > 0.0 && tris[2].normal().y < 0.0 && tris[4].normal().y < 0.0);
    let (p, _) = run(
        &tris,
        0.1,
        &Settings {
            threshold: 1e-4,
            block: 1,
            ..Settings::default()
        },
    );
    let lit = |object: usize| {
        p.patches
            .iter()
            .filter(|q| q.inside() && p.charts[q.chart].object == object)
            .map(|q| q.total.x)
            .fold(0.0, f64::max)
    };
    assert!(lit(0) > 0.05, "the floor under the emitter: {}", lit(0));
    // The ceiling is behind the emitter: only light bounced off the floor reaches it, far less
    // than the floor gets.
    assert!(lit(2) < 0.1 * lit(0), "ceiling {} vs floor {}", lit(2), lit(0));
}

/// A camera inside a box mesh (faces pointing out) sees every light-mapped surface from behind
/// and is warned; outside the same box, or inside a room of inward quads, it is not.
#[test]
fn a_view_of_surfaces_from_behind_is_warned_about() {
    use crate::lighting::lightmap::geometry::{behind_warning, scene_geometry, seen_from_behind};
    let scene = |camera: &str, objects: &str| {
        let text = format!(
            "methods = [\"radiosity\"]\n[camera]\n{camera}\n[[materials]]\nname = \"m\"\nalbedo = 0.5\n{objects}"
        );
        crate::scene::Scene::from_str(&text, "box.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
    };
    let boxed = "[[objects]]\nmesh = \"box\"\nsize = 4\nmaterial = \"m\"\n";
    let inside = scene("position = [0.3, 0.2, 0.5]\ntarget = [0, 0, -1]", boxed);
    let g = scene_geometry(&inside, "radiosity").unwrap();
    assert_eq!(seen_from_behind(&g.triangles, &inside.camera), 1.0);
    let w = behind_warning(&inside, &g.triangles, "radiosity").expect("warned");
    assert!(
        w.starts_with("warning: box.toml: radiosity: 100% of the camera's view sees surfaces from behind"),
        "{w}"
    );
    let outside = scene("position = [0, 1, 8]\ntarget = [0, 0, 0]", boxed);
    assert_eq!(seen_from_behind(&g.triangles, &outside.camera), 0.0);
    assert!(behind_warning(&outside, &g.triangles, "radiosity").is_none());
}

/// The emitters' first shot alone: in a closed box whose every face emits radiosity 1 and
/// reflects ρ, each patch receives ρ·ΣF = ρ (the form factors to the other faces sum to 1), the
/// first term of the furnace series, and nothing of the later bounces.
#[test]
fn the_emitters_first_shot_is_the_furnace_series_first_term() {
    let rho = 0.5;
    let tris = closed_box(1.0, rho, |_| 1.0 / std::f64::consts::PI);
    let p = Patches::build(&tris, 0.25);
    let occ = Occluders::new(&tris);
    let first = crate::lighting::lightmap::solve::emitters_first_shot(&p, &occ, &Settings::default());
    let worst = p
        .patches
        .iter()
        .zip(&first)
        .filter(|(q, _)| q.inside())
        .map(|(_, f)| (f.x - rho).abs())
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-9 + 1e-3 * rho, "worst patch off ρ = {rho} by {worst:.2e}");
    // One face alone emitting: its own patches receive nothing (they only see the others).
    let one = closed_box(1.0, rho, |f| if f == 0 { 1.0 / std::f64::consts::PI } else { 0.0 });
    let p = Patches::build(&one, 0.25);
    let first = crate::lighting::lightmap::solve::emitters_first_shot(&p, &Occluders::new(&one), &Settings::default());
    let (own, others): (Vec<_>, Vec<_>) = p
        .patches
        .iter()
        .zip(&first)
        .filter(|(q, _)| q.inside())
        .partition(|(q, _)| p.charts[q.chart].object == 0);
    assert!(own.iter().all(|(_, f)| f.x == 0.0));
    assert!(others.iter().all(|(_, f)| f.x > 0.0));
}

/// The atlas keeps one empty texel between charts (and inside its bounds): no chart's texels
/// touch another's, even diagonally, so bilinear filtering at a chart's edge never reads a
/// neighbour's light.
#[test]
fn the_atlas_keeps_a_one_texel_gap_between_charts() {
    let scene = crate::scene::Scene::from_file(format!("{}/scenes/two_rooms.toml", env!("CARGO_MANIFEST_DIR")))
        .unwrap_or_else(|e| panic!("{e}"));
    let g = crate::lighting::lightmap::geometry::scene_geometry(&scene, "radiosity").unwrap();
    for size in [0.2, 0.35] {
        let p = Patches::build(&g.triangles, size);
        let atlas = crate::lighting::lightmap::atlas::pack(&p);
        let rects: Vec<(u32, u32, u32, u32)> = p
            .charts
            .iter()
            .zip(&atlas.offsets)
            .map(|(c, &(x, y))| (x, y, x + c.width as u32, y + c.height as u32))
            .collect();
        assert!(rects.len() > 10);
        for (i, a) in rects.iter().enumerate() {
            assert!(
                a.2 <= atlas.width && a.3 <= atlas.height,
                "chart {i} {a:?} outside the atlas"
            );
            for (j, b) in rects.iter().enumerate().filter(|&(j, _)| j != i) {
                // Separated by at least one column or one row of empty texels.
                let apart = a.2 < b.0 || b.2 < a.0 || a.3 < b.1 || b.3 < a.1;
                assert!(
                    apart,
                    "patch {size}: charts {i} {a:?} and {j} {b:?} have no texel between them"
                );
            }
        }
    }
}

/// Two rooms under one floor and one ceiling (2 × 1 × 1 m), parted by a 3 cm wall at
/// x ∈ [0.70, 0.73], with an emitter in the first only. A 3 × 3 shooting block of 0.25 m floor
/// patches spans the wall with most of its area in the second room: shot as one from its centre
/// there, it carried the first room's light over (0.0056 on the brightest patch). Parted by the
/// wall, the second room stays black.
#[test]
fn a_shooting_block_a_thin_wall_crosses_keeps_each_room_s_light() {
    let quad = |q: [DVec3; 4], object: usize, emission: f64, inward: DVec3| {
        [[q[0], q[1], q[2]], [q[0], q[2], q[3]]].map(|p| {
            let mut t = Triangle {
                p,
                object,
                albedo: DVec3::splat(0.5),
                emission: DVec3::splat(emission),
                sky: false,
                part: 0,
            };
            if t.normal().dot(inward) < 0.0 {
                t.p.swap(1, 2);
            }
            t
        })
    };
    let v = DVec3::new;
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let faces = [
        quad([v(0., 0., 0.), v(2., 0., 0.), v(2., 0., 1.), v(0., 0., 1.)], 0, 0.0, y),
        quad([v(0., 1., 0.), v(2., 1., 0.), v(2., 1., 1.), v(0., 1., 1.)], 1, 0.0, -y),
        quad([v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)], 2, 0.0, x),
        quad([v(2., 0., 0.), v(2., 1., 0.), v(2., 1., 1.), v(2., 0., 1.)], 3, 0.0, -x),
        quad([v(0., 0., 0.), v(2., 0., 0.), v(2., 1., 0.), v(0., 1., 0.)], 4, 0.0, z),
        quad([v(0., 0., 1.), v(2., 0., 1.), v(2., 1., 1.), v(0., 1., 1.)], 5, 0.0, -z),
        quad(
            [v(0.7, 0., 0.), v(0.7, 1., 0.), v(0.7, 1., 1.), v(0.7, 0., 1.)],
            6,
            0.0,
            -x,
        ),
        quad(
            [v(0.73, 0., 0.), v(0.73, 1., 0.), v(0.73, 1., 1.), v(0.73, 0., 1.)],
            7,
            0.0,
            x,
        ),
        quad(
            [
                v(0.1, 0.99, 0.3),
                v(0.4, 0.99, 0.3),
                v(0.4, 0.99, 0.6),
                v(0.1, 0.99, 0.6),
            ],
            8,
            1.0,
            -y,
        ),
    ];
    let tris: Vec<Triangle> = faces.into_iter().flatten().collect();
    let mut p = Patches::build(&tris, 0.25);
    let occ = Occluders::new(&tris);
    crate::lighting::lightmap::buried::exclude(&mut p, &occ, None);
    let settings = Settings {
        threshold: 1e-4,
        ..Settings::default()
    };
    assert_eq!((settings.mode, settings.block), (Mode::Corrected, 3));
    solve(&mut p, &occ, &settings, &mut Progress::new("test"));
    let brightest = |second: bool| {
        p.patches
            .iter()
            .filter(|q| q.inside() && p.charts[q.chart].object != 8 && (q.centre.x > 0.715) == second)
            .map(|q| q.total.x)
            .fold(0.0, f64::max)
    };
    let (first, second) = (brightest(false), brightest(true));
    assert!(first > 0.05, "the first room is lit: {first}");
    assert_eq!(second, 0.0, "the first room's light reached the second");
}
