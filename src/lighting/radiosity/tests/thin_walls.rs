//! A wall thinner than a patch standing across a floor: cut along it
//! (`lightmap::cut::along_thin_walls`), each side of the floor holds its own light, judged
//! against the exact direct light and against the dark room's zero.

use glam::DVec3;

use crate::lighting::lightmap::cut::along_thin_walls;
use crate::lighting::lightmap::form_factor::point_to_polygon;
use crate::lighting::lightmap::geometry::StaticGeometry;
use crate::lighting::lightmap::patches::{Patches, Triangle};
use crate::lighting::lightmap::solve::{solve, Occluders, Settings};
use crate::util::progress::Progress;

const RADIANCE: f64 = 1.0;
const PATCH: f64 = 0.25;

/// Two triangles of the quad `q` of `object`, turned to face `inward`.
fn quad(q: [DVec3; 4], object: usize, (albedo, emission): (f64, f64), inward: DVec3) -> [Triangle; 2] {
    [[q[0], q[1], q[2]], [q[0], q[2], q[3]]].map(|p| {
        let mut t = Triangle {
            p,
            object,
            albedo: DVec3::splat(if emission > 0.0 { 0.0 } else { albedo }),
            emission: DVec3::splat(emission),
            sky: false,
            part: 0,
        };
        if t.normal().dot(inward) < 0.0 {
            t.p.swap(1, 2);
        }
        t
    })
}

/// The 2 × 1 × 1 m box room parted by a full-height wall over x ∈ [a, a + 0.03], lit by a
/// ceiling panel in the first room (x < a), every surface of `albedo`; as light-map geometry.
fn rooms(a: f64, albedo: f64) -> (StaticGeometry, [DVec3; 4]) {
    let v = DVec3::new;
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let b = a + 0.03;
    let panel = [
        v(0.1, 0.99, 0.3),
        v(0.4, 0.99, 0.3),
        v(0.4, 0.99, 0.6),
        v(0.1, 0.99, 0.6),
    ];
    // The room's six sides, then the wall's two faces (objects 0 to 7), each as its quad and
    // the way it faces.
    let sides = [
        ([v(0., 0., 0.), v(2., 0., 0.), v(2., 0., 1.), v(0., 0., 1.)], y),
        ([v(0., 1., 0.), v(2., 1., 0.), v(2., 1., 1.), v(0., 1., 1.)], -y),
        ([v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)], x),
        ([v(2., 0., 0.), v(2., 1., 0.), v(2., 1., 1.), v(2., 0., 1.)], -x),
        ([v(0., 0., 0.), v(2., 0., 0.), v(2., 1., 0.), v(0., 1., 0.)], z),
        ([v(0., 0., 1.), v(2., 0., 1.), v(2., 1., 1.), v(0., 1., 1.)], -z),
        ([v(a, 0., 0.), v(a, 1., 0.), v(a, 1., 1.), v(a, 0., 1.)], -x),
        ([v(b, 0., 0.), v(b, 1., 0.), v(b, 1., 1.), v(b, 0., 1.)], x),
    ];
    let mut faces: Vec<[Triangle; 2]> = sides
        .into_iter()
        .enumerate()
        .map(|(object, (q, inward))| quad(q, object, (albedo, 0.0), inward))
        .collect();
    faces.push(quad(panel, 8, (0.0, RADIANCE), -y));
    let triangles: Vec<Triangle> = faces.into_iter().flatten().collect();
    let n = triangles.len();
    let geometry = StaticGeometry {
        draw: triangles.iter().map(|t| t.object).collect(),
        object_space: triangles.iter().map(|t| t.p.map(|q| q.as_vec3().to_array())).collect(),
        uvs: triangles
            .iter()
            .map(|t| t.p.map(|q| [q.x as f32, q.z as f32]))
            .collect(),
        material: vec![None; n],
        entities: Vec::new(),
        triangles,
    };
    (geometry, panel)
}

/// The floor's light as drawn at `x` (the texel of the floor patch whose chart holds `x`).
fn floor_drawn(p: &Patches, triangles: &[Triangle], x: DVec3) -> f64 {
    for c in p.charts.iter().filter(|c| c.object == 0) {
        let flat = c.flat_triangles(triangles);
        let q = glam::DVec2::new((x - c.origin).dot(c.u), (x - c.origin).dot(c.v));
        if flat
            .iter()
            .any(|t| crate::lighting::lightmap::patches::inside_triangle(q, t))
        {
            let (i, j) = ((q.x / p.size) as usize, (q.y / p.size) as usize);
            return p.patches[c.first + j * c.width + i].total.x;
        }
    }
    panic!("no floor chart holds {x}");
}

/// Bakes the rooms with the wall at `a`, cut along thin walls or not; the floor's drawn light
/// at `x`.
fn bake(a: f64, albedo: f64, cut: bool, at: &[DVec3]) -> Vec<f64> {
    let (mut g, _) = rooms(a, albedo);
    let lines = if cut { along_thin_walls(&mut g, PATCH) } else { 0 };
    assert_eq!(lines > 0, cut, "cut lines: {lines}");
    let mut p = Patches::build(&g.triangles, PATCH);
    let occ = Occluders::new(&g.triangles);
    crate::lighting::lightmap::buried::exclude(&mut p, &occ, None);
    let settings = Settings {
        threshold: 1e-4,
        ..Settings::default()
    };
    solve(&mut p, &occ, &settings, &mut Progress::new("test"));
    at.iter().map(|&x| floor_drawn(&p, &g.triangles, x)).collect()
}

/// The floor's radiosity at `x` from the panel's light alone, exact.
fn direct(x: DVec3, panel: &[DVec3; 4], albedo: f64) -> f64 {
    albedo * std::f64::consts::PI * RADIANCE * point_to_polygon(x, DVec3::Y, panel)
}

#[test]
fn the_cut_keeps_area_winding_and_the_maps_coordinates_and_parts_what_the_wall_stands_on() {
    let (mut g, _) = rooms(0.64, 0.5);
    let before: Vec<Triangle> = g.triangles.clone();
    // The floor, the ceiling and the two end walls the wall abuts: a line each.
    assert_eq!(along_thin_walls(&mut g, PATCH), 4);
    let area = |ts: &[Triangle], object: usize| {
        ts.iter()
            .filter(|t| t.object == object)
            .map(Triangle::area)
            .sum::<f64>()
    };
    for object in 0..9 {
        assert!(
            (area(&before, object) - area(&g.triangles, object)).abs() < 1e-12,
            "object {object}'s area"
        );
    }
    for (k, t) in g.triangles.iter().enumerate() {
        let n0 = before.iter().find(|b| b.object == t.object).unwrap().normal();
        assert!(t.normal().dot(n0) > 1.0 - 1e-12, "triangle {k} keeps its winding");
        for c in 0..3 {
            // Built with object space = world space and uv = (x, z): the corners carry both.
            assert!((g.object_space[k][c][0] as f64 - t.p[c].x).abs() < 1e-6);
            assert!((g.uvs[k][c][1] as f64 - t.p[c].z).abs() < 1e-6);
        }
        assert_eq!(g.draw[k], t.object);
    }
    // Each parts at the wall's midline, 0.655; the other walls and the panel are not cut.
    for object in [0, 1, 4, 5] {
        let parts: std::collections::BTreeSet<u64> = g
            .triangles
            .iter()
            .filter(|t| t.object == object)
            .map(|t| t.part)
            .collect();
        assert_eq!(parts.len(), 2, "object {object}'s sides");
        for t in g.triangles.iter().filter(|t| t.object == object) {
            let (lo, hi) =
                t.p.iter()
                    .fold((f64::MAX, f64::MIN), |(l, h), q| (l.min(q.x), h.max(q.x)));
            assert!(
                hi <= 0.655 + 1e-9 || lo >= 0.655 - 1e-9,
                "object {object}: a piece spans the wall: {lo}..{hi}"
            );
        }
    }
    for object in [2, 3, 6, 7, 8] {
        assert_eq!(
            g.triangles.iter().filter(|t| t.object == object).count(),
            2,
            "object {object} is whole"
        );
    }
    let charts = Patches::build(&g.triangles, PATCH).charts;
    assert_eq!(charts.iter().filter(|c| c.object == 0).count(), 2);
}

/// The wall at x ∈ [0.64, 0.67] leaves the patch cell [0.5, 0.75) mostly in the lit room: uncut,
/// its texel painted that light on the dark room's 8 cm strip. At x ∈ [0.58, 0.61] the cell is
/// mostly in the dark room, and the lit room's 8 cm strip drew the dark room's black (judged
/// with albedo 0.05, where the exact direct light is nearly all of it).
#[test]
fn a_floor_cut_along_a_thin_wall_draws_each_room_s_own_light_up_to_it() {
    let dark = DVec3::new(0.71, 0.0, 0.45);
    let lit_uncut = bake(0.64, 0.5, false, &[dark])[0];
    let lit_cut = bake(0.64, 0.5, true, &[dark])[0];
    println!("the dark room's strip draws {lit_uncut:.4} uncut, {lit_cut:.4} cut");
    assert!(
        lit_uncut > 0.02,
        "uncut, the lit room's light shows past the wall: {lit_uncut}"
    );
    assert_eq!(lit_cut, 0.0, "cut, the dark room's strip is dark");

    let albedo = 0.05;
    let (_, panel) = rooms(0.58, albedo);
    let strip = DVec3::new(0.54, 0.0, 0.45);
    let exact = direct(strip, &panel, albedo);
    let uncut = bake(0.58, albedo, false, &[strip])[0] / exact;
    let cut = bake(0.58, albedo, true, &[strip])[0] / exact;
    println!("the lit room's strip draws {uncut:.3} uncut, {cut:.3} cut of the exact direct light");
    assert!(
        uncut < 0.5,
        "uncut, the lit room's strip drew the dark room's light: {uncut}"
    );
    // A texel averages its part of the cell (here x in [0.5, 0.58]) and bounces add a little.
    assert!(
        (0.9..1.15).contains(&cut),
        "cut, the lit room's strip draws its light: {cut}"
    );
}
