//! The surface-visibility matrix (digest §5.4): symmetric, NONE for back-to-back surfaces, every
//! FULL pair confirmed by brute-force segments between the two surfaces, and the solve's result
//! unchanged when FULL is disabled (only rays are saved).

use glam::DVec3;

use crate::lighting::lightmap::patches::{Patches, Triangle};
use crate::lighting::lightmap::solve::{solve, Mode, Occluders, Report, Settings};
use crate::lighting::lightmap::visibility::{Matrix, Tester, Vis};
use crate::scene::Scene;
use crate::util::progress::Progress;

fn triangles(file: &str) -> (Scene, Vec<Triangle>) {
    let scene =
        Scene::from_file(format!("{}/scenes/{file}", env!("CARGO_MANIFEST_DIR"))).unwrap_or_else(|e| panic!("{e}"));
    let geo =
        crate::lighting::lightmap::geometry::scene_geometry(&scene, "radiosity").unwrap_or_else(|e| panic!("{e}"));
    (scene, geo.triangles)
}

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A point strictly inside one of `tris` (picked by area).
    fn on(&mut self, tris: &[&Triangle]) -> DVec3 {
        let total: f64 = tris.iter().map(|t| t.area()).sum();
        let mut pick = self.next() * total;
        let t = tris.iter().find(|t| {
            pick -= t.area();
            pick <= 0.0
        });
        let t = t.unwrap_or(&tris[tris.len() - 1]);
        let (mut a, mut b) = (self.next(), self.next());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        // Pulled a little toward the centroid: strictly inside.
        let q = t.p[0] + (t.p[1] - t.p[0]) * a + (t.p[2] - t.p[0]) * b;
        let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
        c + (q - c) * 0.998
    }
}

/// Möller–Trumbore in f64: does the open segment a→b touch triangle t (edges included)?
fn blocks(a: DVec3, b: DVec3, t: &Triangle) -> bool {
    let d = b - a;
    let (e1, e2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-15 {
        return false;
    }
    let s = a - t.p[0];
    let u = s.dot(pv) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let h = e2.dot(q) / det;
    (-1e-9..=1.0 + 1e-9).contains(&u) && v >= -1e-9 && u + v <= 1.0 + 1e-9 && h > 1e-9 && h < 1.0 - 1e-9
}

#[test]
fn the_matrix_is_symmetric_and_every_full_pair_is_unoccluded() {
    for file in ["cornell_radiosity.toml", "two_rooms.toml"] {
        let (_, tris) = triangles(file);
        let p = Patches::build(&tris, 0.2);
        let m = Matrix::build(&tris, &p, true);
        let tester = Tester::new(&tris, &p);
        let n = p.charts.len();
        for i in 0..n {
            for j in 0..n {
                assert_eq!(m.get(i, j), m.get(j, i));
                assert_eq!(
                    tester.classify(i, j, true),
                    tester.classify(j, i, true),
                    "{file}: charts {i}, {j}"
                );
            }
            assert_eq!(m.get(i, i), Vis::None);
        }
        let of = |c: usize| p.charts[c].triangles.iter().map(|&t| &tris[t]).collect::<Vec<_>>();
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let (mut confirmed, mut partial_blocked) = (0, 0);
        for i in 0..n {
            for j in 0..i {
                let vis = m.get(i, j);
                if vis == Vis::None {
                    continue;
                }
                let others: Vec<&Triangle> = tris
                    .iter()
                    .enumerate()
                    .filter(|(t, _)| !p.charts[i].triangles.contains(t) && !p.charts[j].triangles.contains(t))
                    .map(|(_, t)| t)
                    .collect();
                let (ti, tj) = (of(i), of(j));
                let segments = if vis == Vis::Full { 1000 } else { 100 };
                let hit = (0..segments).find_map(|_| {
                    let (a, b) = (rng.on(&ti), rng.on(&tj));
                    others.iter().find(|t| blocks(a, b, t)).map(|t| (a, b, t.p))
                });
                match vis {
                    Vis::Full => {
                        assert!(
                            hit.is_none(),
                            "{file}: charts {i} and {j} are FULL but segment {hit:?} is blocked"
                        );
                        confirmed += 1;
                    }
                    _ => partial_blocked += usize::from(hit.is_some()),
                }
            }
        }
        let (none, partial, full) = m.counts();
        eprintln!("{file}: {n} charts; pairs NONE {none}, PARTIAL {partial} ({partial_blocked} with a blocked segment found), FULL {full} (each confirmed by 1000 segments)");
        assert!(confirmed > 0 && confirmed == full, "{file}: {confirmed} of {full}");
        assert!(partial_blocked > 0, "{file}: no PARTIAL pair is really occluded");
    }
    // Back to back: room A's wall at x = 0 and room B's at x = 0.05 face away from each other.
    let (scene, tris) = triangles("two_rooms.toml");
    let p = Patches::build(&tris, 0.2);
    let m = Matrix::build(&tris, &p, true);
    let chart = |name: &str| {
        let o = scene.objects.iter().position(|o| o.name == name).unwrap();
        p.charts.iter().position(|c| c.object == o).unwrap()
    };
    assert_eq!(m.get(chart("A wall +x"), chart("B wall -x")), Vis::None);
    assert_eq!(
        m.get(chart("A floor"), chart("B ceiling")),
        Vis::Partial,
        "room A's floor sees room B's ceiling's plane, through the wall"
    );
    assert_eq!(
        m.get(chart("B floor"), chart("B ceiling")),
        Vis::Full,
        "an empty room's floor and ceiling"
    );
    assert_eq!(
        m.get(chart("A floor"), chart("A ceiling")),
        Vis::Partial,
        "room A's ceiling light hangs between them"
    );
}

fn run(tris: &[Triangle], settings: &Settings) -> (Patches, Report) {
    let mut p = Patches::build(tris, 0.2);
    let occ = Occluders::new(tris);
    let report = solve(&mut p, &occ, settings, &mut Progress::new("test"));
    (p, report)
}

#[test]
fn full_pairs_only_save_rays() {
    let (_, tris) = triangles("cornell_radiosity.toml");
    for mode in [Mode::Corrected, Mode::Faithful] {
        let settings = Settings {
            mode,
            threshold: 1e-3,
            ..Settings::default()
        };
        let (with, r1) = run(&tris, &settings);
        let (without, r2) = run(
            &tris,
            &Settings {
                full_visibility: false,
                ..settings
            },
        );
        let worst = with
            .patches
            .iter()
            .zip(&without.patches)
            .map(|(a, b)| (a.total - b.total).abs().max_element())
            .fold(0.0f64, f64::max);
        let peak = without
            .patches
            .iter()
            .map(|q| q.total.max_element())
            .fold(0.0f64, f64::max);
        eprintln!(
            "{mode:?}: {} shots; rays {} with FULL (+{} saved, {:.1}%), {} without; largest difference {worst:.3e} of peak {peak:.3}; pairs {:?}",
            r1.shots,
            r1.rays,
            r1.rays_saved,
            100.0 * r1.rays_saved as f64 / (r1.rays + r1.rays_saved) as f64,
            r2.rays,
            r1.visibility
        );
        assert_eq!(r1.shots, r2.shots);
        assert_eq!(r2.rays_saved, 0);
        assert_eq!(
            r1.rays + r1.rays_saved,
            r2.rays,
            "every skipped ray is one the unskipped solve casts"
        );
        assert!(r1.rays_saved > 0);
        assert!(
            worst <= 1e-12 * peak,
            "{mode:?}: skipping FULL rays changed a patch by {worst}"
        );
    }
}

/// The document's start of the matrix from the leaf PVS (scenes/bsp_rooms.toml, a compiled BSP world
/// with a PVS): the pairs it rules out become NONE, none of them a pair the geometric test finds
/// FULL (sure to see each other), every other pair classified as without it; the solve's light
/// changes by less than its stop, and the time saved is printed.
#[test]
fn the_leaf_pvs_starts_the_matrix_in_a_bsp_world() {
    use crate::lighting::lightmap::visibility::{bsp_world, chart_pvs};
    let (scene, tris) = triangles("bsp_rooms.toml");
    let p = Patches::build(&tris, 1.0);
    let (world, translate) = bsp_world(&scene).unwrap().expect("a BSP world");
    let pvs = chart_pvs(&p, &tris, &world, translate);
    let plain = Matrix::build(&tris, &p, true);
    let started = Matrix::build_in(&tris, &p.charts, true, Some(&pvs));
    let n = p.charts.len();
    let mut ruled_out = 0;
    for i in 0..n {
        for j in 0..i {
            if pvs.sees(i, j) {
                assert_eq!(started.get(i, j), plain.get(i, j));
            } else {
                assert_eq!(started.get(i, j), Vis::None);
                assert_ne!(
                    plain.get(i, j),
                    Vis::Full,
                    "charts {i}, {j}: the PVS rules out a FULL pair"
                );
                ruled_out += usize::from(plain.get(i, j) != Vis::None);
            }
        }
    }
    let (none, partial, full) = plain.counts();
    eprintln!("bsp_rooms at 1 m: {n} charts; without the PVS NONE {none}, PARTIAL {partial}, FULL {full}; the PVS rules out {ruled_out} more");
    assert!(ruled_out > 0, "the PVS rules out no pair the geometry leaves open");
    let solve_with = |pvs: Option<crate::lighting::lightmap::visibility::ChartPvs>| {
        let mut p = Patches::build(&tris, 1.0);
        let mut occ = Occluders::new(&tris);
        occ.pvs = pvs;
        crate::lighting::radiosity::bake::add_direct_light(&mut p, &occ, &scene).unwrap();
        let start = std::time::Instant::now();
        let report = solve(&mut p, &occ, &Settings::default(), &mut Progress::new("test"));
        (p.power(|q| q.total), report, start.elapsed().as_secs_f64())
    };
    let (with, r_with, t_with) = solve_with(Some(pvs));
    let (without, r_without, t_without) = solve_with(None);
    let diff = (with - without).abs().max_element() / without.max_element();
    eprintln!(
        "solve: {t_with:.2} s and {} rays with the PVS, {t_without:.2} s and {} rays without; light differs by {diff:.2e}",
        r_with.rays, r_without.rays
    );
    assert!(r_with.rays < r_without.rays);
    assert!(diff < Settings::default().threshold, "{diff:.2e}");
}
