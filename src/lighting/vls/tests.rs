//! VLS's set-up against the truth (digest §5 items 16–19): with ≤ K lights it is the full sum
//! exactly; on a theatre of 100 spots it loses what the digest's simulation says and the
//! contribution ranking loses less; the feeler's misclassified area falls linearly with the
//! segment's edge, and both feelers agree; seams appear where neighbouring sets differ; the
//! sets never depend on intensities; bad parameters give one line naming file and parameter.

use glam::DVec3;

use super::setup::{self, choose, Feeler, LightSets, Point, Selection, SetupParams, ThesisFeeler, EMPTY};
use super::{Config, Layout};
use crate::bake::{Baker, Progress};
use crate::lighting::many_lights::{LightModel, ManyLight, Occluders, ScenePolygon, Segments};
use crate::scene::{MethodDecl, Scene};
use crate::world::Polygon;

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

struct Lcg(u64);
impl Lcg {
    fn f(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f()
    }
}

/// A horizontal square (facing +z) of side `side` centred at (cx, cy, z), as two triangles.
fn square(cx: f64, cy: f64, z: f64, side: f64) -> Vec<ScenePolygon> {
    let h = side / 2.0;
    let (a, b, c, d) = (
        v(cx - h, cy - h, z),
        v(cx + h, cy - h, z),
        v(cx + h, cy + h, z),
        v(cx - h, cy + h, z),
    );
    [vec![a, b, c], vec![a, c, d]]
        .into_iter()
        .map(|p| ScenePolygon {
            polygon: Polygon::from_vertices(p).unwrap(),
            albedo: DVec3::splat(0.5),
            emission: DVec3::ZERO,
            draw: 0,
        })
        .collect()
}

fn params(k: usize, selection: Selection, feeler: Feeler, model: LightModel) -> SetupParams {
    SetupParams {
        k,
        selection,
        can_illuminate: false,
        feeler,
        model,
        point: Point::Centroid,
    }
}

fn sets(polygons: &[ScenePolygon], segments: &Segments, lights: &[ManyLight], p: &SetupParams) -> LightSets {
    let occluders = Occluders::new(polygons.iter().map(|q| &q.polygon));
    setup::select(
        polygons,
        segments,
        lights,
        p,
        Some(&occluders),
        &mut Progress::new("test"),
    )
}

fn segments(polygons: &[ScenePolygon], max_area: f64) -> Segments {
    Segments::build(polygons.iter().map(|p| &p.polygon), max_area).unwrap()
}

/// Σ over `lights` (in index order, so two sums over the same lights are bit-identical) of
/// intensity × full-intensity shade.
fn sum(
    model: &LightModel,
    lights: &[ManyLight],
    which: impl Iterator<Item = usize>,
    scale: &[f64],
    p: DVec3,
    n: DVec3,
) -> DVec3 {
    let mut w: Vec<usize> = which.collect();
    w.sort_unstable();
    w.iter()
        .map(|&i| lights[i].shade(model, p, n, DVec3::splat(0.5)) * scale[i])
        .fold(DVec3::ZERO, |a, b| a + b)
}

/// Three spots and two points over a floor with a square occluder above it.
fn small_scene() -> (Vec<ScenePolygon>, Vec<ManyLight>) {
    let mut polygons = square(0.0, 0.0, 0.0, 4.0);
    // Off the segment grid's rational points: a feeler through an occluder's very edge may go
    // either way (the half-open rule against the BVH's), which is not what this scene tests.
    polygons.extend(square(0.2137, -0.0931, 1.0, 1.0));
    let spot = |p: DVec3, target: DVec3, i: f64| ManyLight {
        position: p,
        direction: (target - p).normalize(),
        intensity: DVec3::new(i, 0.8 * i, 0.6 * i),
        cone: Some((25f64.to_radians(), 40f64.to_radians())),
    };
    let point = |p: DVec3, i: f64| ManyLight {
        position: p,
        direction: -DVec3::Z,
        intensity: DVec3::splat(i),
        cone: None,
    };
    let lights = vec![
        spot(v(0.3, 0.2, 3.0), v(0.0, 0.0, 0.0), 10.0),
        spot(v(-1.5, 1.0, 2.5), v(0.5, -0.5, 0.0), 7.0),
        spot(v(1.7, -1.2, 2.0), v(-0.3, 0.4, 0.0), 5.0),
        point(v(-0.4, -1.1, 2.2), 3.0),
        point(v(1.2, 1.4, 1.6), 2.0),
    ];
    (polygons, lights)
}

/// With ≤ K lights: every segment's VLS sum is the full sum with the same feeler's
/// shadows, bit for bit, for every selection, feeler and model, per segment and per vertex.
#[test]
fn with_at_most_k_lights_vls_is_the_full_sum() {
    let (polygons, lights) = small_scene();
    let segs = segments(&polygons, 0.02);
    let ones = vec![1.0; lights.len()];
    let occluders = Occluders::new(polygons.iter().map(|q| &q.polygon));
    let mut shadowed = 0;
    for model in [
        LightModel::Physical,
        LightModel::Seed { k: 1.0 },
        LightModel::OpenGl {
            kc: 1.0,
            kl: 0.2,
            kq: 0.5,
        },
    ] {
        for selection in [Selection::Closest, Selection::Contribution] {
            for (feeler, point) in [
                (Feeler::Thesis, Point::Centroid),
                (Feeler::Bvh, Point::Centroid),
                (Feeler::Bvh, Point::Vertex),
            ] {
                let p = SetupParams {
                    point,
                    ..params(8, selection, feeler, model)
                };
                let s = sets(&polygons, &segs, &lights, &p);
                for (t, &(c, n, _)) in setup::points(&segs, point).iter().enumerate() {
                    let unblocked: Vec<usize> = (0..lights.len())
                        .filter(|&i| !occluders.blocked(c, lights[i].position))
                        .collect();
                    shadowed += lights.len() - unblocked.len();
                    let full = sum(&model, &lights, unblocked.into_iter(), &ones, c, n);
                    let vls = sum(&model, &lights, s.of(t), &ones, c, n);
                    assert_eq!(
                        vls,
                        full,
                        "{point:?} {t} ({selection:?}, {feeler:?}, {model:?}): {:?}",
                        s.of(t).collect::<Vec<_>>()
                    );
                }
            }
        }
    }
    assert!(
        shadowed > 0,
        "the occluder must shadow some segments for the test to mean anything"
    );
}

/// Digest §3.3 item 8's layout: 100 (or 25) spots on a grid over a 10 m floor aimed down with
/// ±0.3 jitter, random intensities in U(0, 1), no occluders.
fn theatre(
    lights_side: usize,
    height: f64,
    full_deg: f64,
    null_deg: f64,
    seed: u64,
) -> (Vec<ScenePolygon>, Vec<ManyLight>, Vec<f64>) {
    let mut r = Lcg(seed);
    let mut lights = Vec::new();
    let cell = 10.0 / lights_side as f64;
    for j in 0..lights_side {
        for i in 0..lights_side {
            let p = v(-5.0 + cell * (i as f64 + 0.5), -5.0 + cell * (j as f64 + 0.5), height);
            let d = v(r.range(-0.3, 0.3), r.range(-0.3, 0.3), -1.0).normalize();
            lights.push(ManyLight {
                position: p,
                direction: d,
                intensity: DVec3::ONE,
                cone: Some((full_deg.to_radians(), null_deg.to_radians())),
            });
        }
    }
    let intensities = (0..lights.len()).map(|_| r.f()).collect();
    (square(0.0, 0.0, 0.0, 10.0), lights, intensities)
}

/// Relative error of VLS against the full sum at every segment's centroid.
#[derive(Debug)]
struct ErrorStats {
    mean: f64,
    max: f64,
    p95: f64,
    over_5_percent: f64,
    energy_ratio: f64,
}

fn error_stats(
    polygons: &[ScenePolygon],
    segs: &Segments,
    lights: &[ManyLight],
    intensities: &[f64],
    p: &SetupParams,
) -> ErrorStats {
    let s = sets(polygons, segs, lights, p);
    let (mut errors, mut e_all, mut e_vls) = (Vec::new(), 0.0, 0.0);
    for t in 0..segs.triangles.len() {
        let (c, n) = (segs.centroid(t), DVec3::Z);
        let full = sum(&p.model, lights, 0..lights.len(), intensities, c, n).x;
        let vls = sum(&p.model, lights, s.of(t), intensities, c, n).x;
        e_all += full;
        e_vls += vls;
        if full > 1e-9 {
            errors.push((full - vls).abs() / full);
        }
    }
    errors.sort_by(f64::total_cmp);
    let count = errors.len().max(1) as f64;
    ErrorStats {
        mean: errors.iter().sum::<f64>() / count,
        max: errors.last().copied().unwrap_or(0.0),
        p95: errors.get((0.95 * count) as usize).copied().unwrap_or(0.0),
        over_5_percent: errors.iter().filter(|&&e| e > 0.05).count() as f64 / count,
        energy_ratio: e_vls / e_all.max(1e-300),
    }
}

/// On many lights: the thesis's 8 closest lose about a third of the light under 100
/// overlapping spots (the digest's simulation: mean 0.354 with 1/d, 20°/30°, 4 m), much less
/// under 25 sparse ones (0.029); ranking by potential contribution loses less in both.
#[test]
fn many_lights_error_closest_against_contribution() {
    for (side, height, full, null, want_closest) in
        [(10, 4.0, 20.0, 30.0, (0.2, 0.5)), (5, 3.0, 30.0, 45.0, (0.0, 0.08))]
    {
        let (polygons, lights, intensities) = theatre(side, height, full, null, 3);
        let segs = segments(&polygons, 0.02);
        let model = LightModel::Seed { k: 1.0 };
        let closest = error_stats(
            &polygons,
            &segs,
            &lights,
            &intensities,
            &params(8, Selection::Closest, Feeler::None, model),
        );
        let contribution = error_stats(
            &polygons,
            &segs,
            &lights,
            &intensities,
            &params(8, Selection::Contribution, Feeler::None, model),
        );
        println!("{} lights, {} segments, 1/d, {full}°/{null}° at {height} m:\n  closest      {closest:.3?}\n  contribution {contribution:.3?}", lights.len(), segs.triangles.len());
        assert!(
            closest.mean > want_closest.0 && closest.mean < want_closest.1,
            "closest mean {} outside the digest's ballpark {want_closest:?}",
            closest.mean
        );
        assert!(
            contribution.mean < closest.mean && contribution.energy_ratio > closest.energy_ratio,
            "contribution should lose less: {contribution:?} vs {closest:?}"
        );
        assert!(
            contribution.over_5_percent < closest.over_5_percent && contribution.p95 < closest.p95,
            "{contribution:?} vs {closest:?}"
        );
        for e in [&closest, &contribution] {
            assert!(
                e.energy_ratio < 1.0 + 1e-12 && e.max <= 1.0 && e.p95 >= e.mean * 0.5,
                "dropped lights can only remove light: {e:?}"
            );
        }
    }
}

/// Area of the convex polygon `poly` (in the z = 0 plane) inside the rectangle `[x0, x1] × [y0, y1]`.
fn clipped_area(poly: &[DVec3], (x0, x1, y0, y1): (f64, f64, f64, f64)) -> f64 {
    let mut pts: Vec<DVec3> = poly.to_vec();
    let planes: [(usize, f64, f64); 4] = [(0, x0, 1.0), (0, x1, -1.0), (1, y0, 1.0), (1, y1, -1.0)];
    for (axis, at, sign) in planes {
        let inside = |p: &DVec3| (p[axis] - at) * sign >= 0.0;
        let mut out = Vec::new();
        for i in 0..pts.len() {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            if inside(&a) {
                out.push(a);
            }
            if inside(&a) != inside(&b) {
                let t = (at - a[axis]) / (b[axis] - a[axis]);
                out.push(a + (b - a) * t);
            }
        }
        pts = out;
        if pts.is_empty() {
            return 0.0;
        }
    }
    (1..pts.len().saturating_sub(1))
        .map(|k| 0.5 * (pts[k] - pts[0]).cross(pts[k + 1] - pts[0]).z)
        .sum()
}

/// A 1 m square at z = 1 over a floor, a light at (0.3, 0.2, 3) (and five more near it,
/// so that no one alignment of the shadow's edges with the segment grid decides the result): the
/// exact shadow is the square scaled 1.5× about the light's footprint. The feeler judges a
/// segment by its centroid, so the misclassified area is a band along the shadow's edge about
/// one segment wide: it halves when the segment's edge halves. Both feelers give the same flags.
#[test]
fn feeler_misclassification_falls_linearly_with_segment_edge() {
    let mut polygons = square(0.0, 0.0, 0.0, 4.0);
    polygons.extend(square(0.0, 0.0, 1.0, 1.0));
    let lights: Vec<DVec3> = (0..6)
        .map(|j| v(0.3 + 0.137 * j as f64, 0.2 - 0.093 * j as f64, 3.0))
        .collect();
    // Central projection from z = 3 through z = 1 onto z = 0: x → 1.5·x − 0.5·L.x.
    let shadow = |l: DVec3| (-0.75 - 0.5 * l.x, 0.75 - 0.5 * l.x, -0.75 - 0.5 * l.y, 0.75 - 0.5 * l.y);
    let shadow_area = 1.5 * 1.5 * lights.len() as f64;
    let thesis = ThesisFeeler::new(&polygons);
    let occluders = Occluders::new(polygons.iter().map(|q| &q.polygon));
    let mut fractions = Vec::new();
    for depth in [4, 5, 6] {
        let segs = segments(&polygons, 8.0 / 4f64.powi(depth));
        let mut wrong = 0.0;
        for &light in &lights {
            for t in (0..segs.triangles.len()).filter(|&t| segs.triangle_polygon[t] < 2) {
                let c = segs.centroid(t);
                let by_thesis = thesis.blocked(segs.triangle_polygon[t] as usize, c, light);
                assert_eq!(by_thesis, occluders.blocked(c, light), "the feelers disagree at {c}");
                let tri: Vec<DVec3> = segs.triangles[t].iter().map(|&i| segs.positions[i as usize]).collect();
                let (area, inside) = (segs.triangle_area(t), clipped_area(&tri, shadow(light)));
                wrong += if by_thesis { area - inside } else { inside };
            }
        }
        println!(
            "segment legs {:.4} m: misclassified {:.3} % of the shadows' area",
            4.0 / 2f64.powi(depth),
            100.0 * wrong / shadow_area
        );
        fractions.push(wrong / shadow_area);
    }
    for w in fractions.windows(2) {
        let ratio = w[0] / w[1];
        assert!(
            (1.6..=2.5).contains(&ratio),
            "misclassification should halve with the edge: {fractions:?}"
        );
    }
}

/// The two feelers on random lights over the small scene, every segment: the same answers.
#[test]
fn thesis_feeler_equals_the_bvh_feeler() {
    let (polygons, _) = small_scene();
    let mut polygons = polygons;
    // A slanted occluder too, so not every plane is axis-aligned.
    let slanted = Polygon::from_vertices(vec![v(-1.5, 0.5, 0.6), v(-0.5, 0.7, 1.4), v(-0.7, 1.6, 1.2)]).unwrap();
    polygons.push(ScenePolygon {
        polygon: slanted,
        albedo: DVec3::splat(0.5),
        emission: DVec3::ZERO,
        draw: 0,
    });
    let segs = segments(&polygons, 0.05);
    let thesis = ThesisFeeler::new(&polygons);
    let occluders = Occluders::new(polygons.iter().map(|q| &q.polygon));
    let mut r = Lcg(5);
    let (mut blocked, mut total) = (0, 0);
    for _ in 0..20 {
        let light = v(r.range(-2.0, 2.0), r.range(-2.0, 2.0), r.range(1.5, 3.5));
        for t in 0..segs.triangles.len() {
            let c = segs.centroid(t);
            let a = thesis.blocked(segs.triangle_polygon[t] as usize, c, light);
            assert_eq!(a, occluders.blocked(c, light), "segment {t} at {c}, light {light}");
            blocked += usize::from(a);
            total += 1;
        }
    }
    println!("{blocked} of {total} feelers blocked");
    assert!(blocked > total / 50 && blocked < total, "{blocked} of {total}");
}

/// At every vertex shared by segments with different light sets, the largest colour
/// difference between the segments' sums — zero for the full sum, clearly not for VLS.
#[test]
fn seams_show_where_neighbouring_light_sets_differ() {
    let (polygons, lights, intensities) = theatre(10, 4.0, 20.0, 30.0, 3);
    let segs = segments(&polygons, 0.08);
    let model = LightModel::Seed { k: 1.0 };
    let seam = |k: usize| -> (f64, usize) {
        let s = sets(
            &polygons,
            &segs,
            &lights,
            &params(k, Selection::Closest, Feeler::None, model),
        );
        let mut by_vertex: Vec<Vec<usize>> = vec![Vec::new(); segs.positions.len()];
        for (t, tri) in segs.triangles.iter().enumerate() {
            for &i in tri {
                by_vertex[i as usize].push(t);
            }
        }
        let (mut worst, mut seams) = (0.0f64, 0);
        for (vi, ts) in by_vertex.iter().enumerate() {
            let colours: Vec<f64> = ts
                .iter()
                .map(|&t| sum(&model, &lights, s.of(t), &intensities, segs.positions[vi], DVec3::Z).x)
                .collect();
            let differ = ts.windows(2).any(|w| {
                let (mut a, mut b): (Vec<usize>, Vec<usize>) = (s.of(w[0]).collect(), s.of(w[1]).collect());
                a.sort_unstable();
                b.sort_unstable();
                a != b
            });
            if differ {
                seams += 1;
                let (lo, hi) = colours
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(lo, hi), &c| (lo.min(c), hi.max(c)));
                worst = worst.max(hi - lo);
            }
        }
        (worst, seams)
    };
    let (vls, seams) = seam(8);
    let (full, full_seams) = seam(lights.len());
    println!("seam metric: VLS k=8 {vls:.4} over {seams} vertices; k = all {full} over {full_seams}");
    assert!(
        seams > 0 && vls > 0.01,
        "VLS should show seams: {vls} at {seams} vertices"
    );
    assert_eq!((full, full_seams), (0.0, 0));
}

/// The run-time intensities never reach the set-up — `closest` picks the same sets
/// whatever the lights' intensities (and the method's bake key holds the scene's full
/// intensities only).
#[test]
fn light_sets_do_not_depend_on_intensities() {
    let (polygons, lights) = small_scene();
    let segs = segments(&polygons, 0.05);
    let mut r = Lcg(9);
    for can in [false, true] {
        let p = SetupParams {
            can_illuminate: can,
            ..params(3, Selection::Closest, Feeler::Bvh, LightModel::Physical)
        };
        let base = sets(&polygons, &segs, &lights, &p);
        for _ in 0..5 {
            let dimmed: Vec<ManyLight> = lights
                .iter()
                .map(|l| ManyLight {
                    intensity: l.intensity * r.range(0.0, 1.0),
                    ..*l
                })
                .collect();
            assert_eq!(sets(&polygons, &segs, &dimmed, &p), base);
        }
    }
}

/// `can_illuminate` skips lights behind the surface and outside the cone; plain `closest` wastes
/// slots on them (the thesis's pseudocode). `contribution` skips the light outside its cone only:
/// the shader lights a surface from the viewer's side, so a light behind it counts on that side.
#[test]
fn can_illuminate_skips_lights_that_cannot_reach() {
    let p = v(0.0, 0.0, 0.0);
    let below = ManyLight {
        position: v(0.0, 0.0, -0.5),
        direction: DVec3::Z,
        intensity: DVec3::ONE,
        cone: None,
    };
    let away = ManyLight {
        position: v(0.0, 0.0, 0.6),
        direction: DVec3::Z,
        intensity: DVec3::ONE,
        cone: Some((0.3, 0.5)),
    };
    let good = ManyLight {
        position: v(0.0, 0.0, 3.0),
        direction: -DVec3::Z,
        intensity: DVec3::ONE,
        cone: Some((0.3, 0.5)),
    };
    let lights = [below, away, good];
    let mut sp = params(1, Selection::Closest, Feeler::None, LightModel::Physical);
    assert_eq!(choose(&lights, &sp, p, DVec3::Z, 1, |_| false).0, vec![0]);
    sp.can_illuminate = true;
    assert_eq!(choose(&lights, &sp, p, DVec3::Z, 1, |_| false).0, vec![2]);
    sp = params(3, Selection::Contribution, Feeler::None, LightModel::Physical);
    assert_eq!(choose(&lights, &sp, p, DVec3::Z, 3, |_| false).0, vec![0, 2]);
    // Past k: one more light that passes is light dropped; one that is shadowed is not.
    sp = params(1, Selection::Contribution, Feeler::None, LightModel::Physical);
    assert_eq!(choose(&lights, &sp, p, DVec3::Z, 1, |_| false), (vec![0], true));
    assert_eq!(
        choose(&lights, &sp, p, DVec3::Z, 1, |l| l.position.z > 1.0),
        (vec![0], false)
    );
    assert_eq!(choose(&lights, &sp, p, DVec3::Z, 2, |_| false), (vec![0, 2], false));
}

/// A spot light inside a closed box (faces outward, as a box mesh's are) pointed at one face:
/// the face's segments, seen from inside, keep it under `contribution`, as the two-sided
/// shading lights them with it; a spot light outside its cone stays dropped.
#[test]
fn contribution_keeps_a_spot_light_inside_a_closed_box() {
    let wall = v(0.0, 0.0, -1.0);
    let outward = -DVec3::Z;
    let inside = ManyLight {
        position: v(0.0, 0.0, 0.5),
        direction: -DVec3::Z,
        intensity: DVec3::ONE,
        cone: Some((0.3, 0.5)),
    };
    let turned = ManyLight {
        direction: DVec3::Z,
        ..inside
    };
    let sp = params(2, Selection::Contribution, Feeler::None, LightModel::Physical);
    assert_eq!(choose(&[inside, turned], &sp, wall, outward, 2, |_| false).0, vec![0]);
    // The potential seen from inside equals that of the same wall facing the light.
    let lit = setup::potential(&LightModel::Physical, &inside, wall, -outward);
    assert!(lit > 0.0);
    assert_eq!(setup::potential(&LightModel::Physical, &inside, wall, outward), lit);
}

const SCENE: &str = r#"
methods = [METHOD]

[camera]
position = [0.0, 4.0, 3.0]
target = [0.0, 0.0, 0.0]

[[materials]]
name = "grey"
albedo = 0.5

[[objects]]
name = "floor"
mesh = "quad"
corner = [-2, 0, -2]
edge_u = [0, 0, 4]
edge_v = [4, 0, 0]
material = "grey"

[[lights]]
name = "lamp"
type = "spot"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
intensity = [5.0, 5.0, 5.0]
inner_deg = 20
outer_deg = 30
"#;

fn scene(method: &str) -> Scene {
    Scene::from_str(
        &SCENE.replace("METHOD", method),
        "scenes/vls_test.toml",
        std::path::Path::new("scenes"),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Bad parameters: one line naming the scene file and the parameter.
#[test]
fn bad_parameters_name_the_file_and_the_parameter() {
    for (decl, param) in [
        (r#"{ name = "vls", k = 0 }"#, "k"),
        (r#"{ name = "vls", k = 33 }"#, "k"),
        (r#"{ name = "vls", selection = "brightest" }"#, "selection"),
        (r#"{ name = "vls", feeler = "exact" }"#, "feeler"),
        (r#"{ name = "vls", max_segment_area = -1.0 }"#, "max_segment_area"),
        (r#"{ name = "vls", mode = "loose" }"#, "mode"),
        (r#"{ name = "vls", model = "opengl", kc = 0, kl = 0, kq = 0 }"#, "kc"),
        (r#"{ name = "vls", can_illuminate = 1 }"#, "can_illuminate"),
    ] {
        let s = scene(decl);
        let e = Config::from_decl_in(&s.methods[0], Some(&s)).unwrap_err().to_string();
        println!("{e}");
        assert!(
            e.contains("scenes/vls_test.toml") && e.contains(&format!("methods[0].{param}")) && !e.contains('\n'),
            "{decl}: {e}"
        );
    }
    // Too fine a segmentation for the scene is refused by the same parameter, at creation.
    let s = scene(r#"{ name = "vls", max_segment_area = 1e-6 }"#);
    let config = Config::from_decl_in(&s.methods[0], Some(&s)).unwrap();
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&s, "vls").unwrap();
    let e = Layout::new(&s, &geometry, &s.methods[0], &config)
        .err()
        .expect("too many segments")
        .to_string();
    assert!(
        e.contains("scenes/vls_test.toml") && e.contains("methods[0].max_segment_area") && !e.contains('\n'),
        "{e}"
    );
    // A directional light is not one of Ridderhof 2002's lights.
    let text = SCENE.replace("METHOD", r#""vls""#)
        + "\n[[lights]]\nname = \"sun\"\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1.0\n";
    let s = Scene::from_str(&text, "scenes/vls_test.toml", std::path::Path::new("scenes")).unwrap();
    let config = Config::from_decl(&s.methods[0]).unwrap();
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&s, "vls").unwrap();
    let e = Layout::new(&s, &geometry, &s.methods[0], &config)
        .err()
        .expect("a directional light")
        .to_string();
    assert!(e.contains("scenes/vls_test.toml") && e.contains("lights[1]"), "{e}");
}

/// The set-up goes through the bake stage: built once, then read back identical from the cache;
/// another K is another key.
#[test]
fn the_setup_is_a_cached_bake() {
    let s = scene(r#"{ name = "vls", max_segment_area = 0.5 }"#);
    let config = Config::from_decl(&s.methods[0]).unwrap();
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&s, "vls").unwrap();
    let layout = Layout::new(&s, &geometry, &s.methods[0], &config).unwrap();
    let dir = crate::util::test_files::TestDir::new("vls-bake");
    let mut baker = Baker::new(Some(dir.to_path_buf()));
    let key = layout.key(&config);
    let a = baker
        .bake("vls", &key, |p| Ok(layout.select(&config.setup, p)))
        .unwrap();
    let b = baker
        .bake("vls", &key, |_| panic!("should come from the cache"))
        .unwrap();
    assert_eq!(a, b);
    assert_eq!(a.segments(), layout.segments.triangles.len());
    assert!(a.indices.contains(&0) && a.indices.contains(&EMPTY));
    assert_eq!(
        baker.reports().iter().map(|r| r.cached).collect::<Vec<_>>(),
        vec![false, true]
    );
    let other = Config {
        setup: SetupParams { k: 4, ..config.setup },
        ..config
    };
    assert_ne!(layout.key(&other).hash(), key.hash());
}

/// The chart's sweep covers K, both selections, three segment sizes and the faithful mode.
#[test]
fn the_sweep_covers_k_selection_and_area() {
    let decl = MethodDecl {
        name: "vls".into(),
        line: 1,
        params: Vec::new(),
    };
    let labels: Vec<String> = super::sweep(&decl).into_iter().map(|(l, _)| l).collect();
    for want in [
        "k=1 ",
        "k=32 ",
        "closest",
        "contribution",
        "area=0.2",
        "area=0.0125",
        "faithful",
    ] {
        assert!(
            labels.iter().any(|l| l.contains(want)),
            "{want} missing from {labels:?}"
        );
    }
}

/// Set-up time against segments × lights × polygons, per feeler (`cargo test --release --lib
/// vls::tests::setup_time -- --ignored --nocapture`).
#[test]
#[ignore]
fn setup_time() {
    println!(
        "{:>8} {:>7} {:>9} {:>8} {:>12} {:>10}",
        "segments", "lights", "polygons", "feeler", "S·L·P", "ms"
    );
    for (area, side, occluders) in [
        (0.08, 5, 8),
        (0.02, 5, 8),
        (0.02, 10, 8),
        (0.02, 10, 32),
        (0.02, 10, 128),
        (0.005, 10, 32),
    ] {
        let (mut polygons, lights, _) = theatre(side, 4.0, 20.0, 30.0, 3);
        let mut r = Lcg(1);
        for _ in 0..occluders / 2 {
            polygons.extend(square(r.range(-4.0, 4.0), r.range(-4.0, 4.0), r.range(0.5, 2.5), 0.5));
        }
        let segs = segments(&polygons, area);
        for feeler in [Feeler::Thesis, Feeler::Bvh] {
            let p = params(8, Selection::Closest, feeler, LightModel::Physical);
            let start = std::time::Instant::now();
            let _ = sets(&polygons, &segs, &lights, &p);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let work = segs.triangles.len() * lights.len() * polygons.len();
            println!(
                "{:>8} {:>7} {:>9} {:>8} {:>12} {:>10.1}",
                segs.triangles.len(),
                lights.len(),
                polygons.len(),
                format!("{feeler:?}"),
                work,
                ms
            );
        }
    }
}
