use glam::DVec3;

mod border;
mod sun;
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
