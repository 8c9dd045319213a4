//! Shadow-caster set tests: the seed's Fig. 8(c) case, the empty room, and the sizes and
//! completeness of the sets on the generated level.

use glam::DVec3;

use super::super::level_gen::{fig8c_case, generate_rooms, Rng, RoomsParams};
use super::super::CompiledWorld;
use super::world::point_in_leaf;

#[test]
fn fig8c_caster_outside_the_light_pvs_is_missed_by_b_and_found_by_c() {
    let case = fig8c_case();
    let w = case.world.compile().unwrap();
    let d = w.leaf_of(case.light);
    let caster = w.faces.iter().position(|f| {
        f.polygon.contains_point(case.caster_point, 1e-9) && f.polygon.plane.distance(case.caster_point).abs() < 1e-9
    });
    let caster = caster.expect("the pillar's back face exists") as u32;
    let e = w.faces[caster as usize].leaves.clone();
    assert_eq!(e.len(), 1, "the back face bounds leaf E only");
    assert!(!w.is_visible(d, e[0]), "E is not in PVS(D)");
    // The receiver is in a leaf D sees, the segment to it crosses the caster and nothing else
    // back-facing: brute force says it is in shadow of exactly this face.
    let receiver_leaf = w.leaf_of(case.receiver_point - DVec3::Y * 1e-3);
    assert!(w.is_visible(d, receiver_leaf));
    assert!(w.occluded(case.light, case.receiver_point));
    let crossing: Vec<u32> = (0..w.faces.len() as u32)
        .filter(|&f| w.faces[f as usize].polygon.plane.distance(case.light) < 0.0)
        .filter(|&f| {
            w.faces[f as usize]
                .polygon
                .intersect_ray(case.light, case.receiver_point - case.light, 0.0, 1.0 - 1e-9)
                .is_some()
        })
        .collect();
    assert_eq!(crossing, vec![caster]);
    let radius = 30.0;
    let b = w.back_facing(&w.casters_light_pvs(case.light, radius), case.light);
    let c = w.back_facing(&w.casters_with_pscs(case.light, radius), case.light);
    assert!(
        !b.contains(&caster),
        "(b) misses the caster: the shadow would be missing"
    );
    assert!(c.contains(&caster), "(c) with the PSCS has it");
    assert!(w.casters_naive().len() >= c.len() && c.len() > b.len());
    // Over random lit receiver points: (b) leaves some shadowed point uncovered, (c) none.
    let (shadowed, missing_b) = shadows_complete(&w, case.light, radius, &b, &mut Rng::new(4));
    let (_, missing_c) = shadows_complete(&w, case.light, radius, &c, &mut Rng::new(4));
    assert!(
        shadowed > 20 && missing_b > 0,
        "{shadowed} shadowed, {missing_b} missed by (b)"
    );
    assert_eq!(missing_c, 0);
}

#[test]
fn empty_room_has_six_front_facing_and_no_back_facing_casters_as_the_seed_says() {
    let w = super::box_room().compile().unwrap();
    let light = DVec3::new(1.0, 1.0, 2.0);
    let in_pvs = w.casters_light_pvs(light, 100.0);
    assert_eq!(w.front_facing(&in_pvs, light).len(), 6, "the seed's approach (a)");
    assert_eq!(
        w.back_facing(&w.casters_with_pscs(light, 100.0), light).len(),
        0,
        "the seed's approach (c)"
    );
    // A radius reaching only the floor and two walls keeps only those.
    assert_eq!(w.casters_light_pvs(DVec3::new(0.5, 0.5, 0.5), 0.6).len(), 3);
}

/// For a light, checks on random points of lit receivers that whenever the light is blocked, a
/// back-facing face of `casters` crosses the segment (the shadow volumes would cover it).
fn shadows_complete(w: &CompiledWorld, light: DVec3, radius: f64, casters: &[u32], rng: &mut Rng) -> (usize, usize) {
    let receivers = w.front_facing(&w.casters_light_pvs(light, radius), light);
    let (mut shadowed, mut missing) = (0, 0);
    for &r in &receivers {
        let poly = &w.faces[r as usize].polygon;
        for _ in 0..8 {
            // A random convex combination of the vertices.
            let weights: Vec<f64> = poly.vertices.iter().map(|_| rng.unit() + 1e-3).collect();
            let p =
                poly.vertices.iter().zip(&weights).map(|(v, k)| *v * *k).sum::<DVec3>() / weights.iter().sum::<f64>();
            if p.distance(light) > radius || !w.occluded(light, p) {
                continue;
            }
            shadowed += 1;
            let dir = p - light;
            let covered = casters.iter().any(|&c| {
                w.faces[c as usize]
                    .polygon
                    .intersect_ray(light, dir, 1e-9, 1.0 - 1e-9)
                    .is_some()
            });
            missing += usize::from(!covered);
        }
    }
    (shadowed, missing)
}

#[test]
fn caster_sets_shrink_from_a_to_c_to_b_and_c_shadows_everything_brute_force_does() {
    let world = generate_rooms(1, &RoomsParams::default());
    let w = world.compile().unwrap();
    let mut rng = Rng::new(3);
    let mut report = Vec::new();
    for (i, leaf) in w.empty_leaves().step_by(7).enumerate().take(6) {
        let Some(light) = point_in_leaf(&w, leaf, &mut rng) else {
            continue;
        };
        let radius = 6.0 + i as f64 * 2.0;
        let (a, b, c) = (
            w.casters_naive(),
            w.casters_light_pvs(light, radius),
            w.casters_with_pscs(light, radius),
        );
        let (bb, cb) = (w.back_facing(&b, light), w.back_facing(&c, light));
        assert!(
            a.len() >= c.len() && c.len() >= b.len(),
            "{} {} {}",
            a.len(),
            c.len(),
            b.len()
        );
        assert!(b.len() < a.len(), "PVS and radius must cull on a multi-room level");
        assert!(b.iter().all(|f| c.contains(f)));
        let (shadowed, missing) = shadows_complete(&w, light, radius, &cb, &mut rng.clone());
        assert_eq!(
            missing, 0,
            "light {light}: {missing} of {shadowed} shadowed samples uncovered by (c)"
        );
        let (_, missing_b) = shadows_complete(&w, light, radius, &bb, &mut rng);
        report.push((a.len(), b.len(), c.len(), bb.len(), cb.len(), shadowed, missing_b));
    }
    assert!(report.len() >= 4);
    println!("(a, b, c, back-facing b, back-facing c, shadowed samples, missed by b): {report:?}");
}
