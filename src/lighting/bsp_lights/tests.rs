//! The BSP shadow system on the CPU (digest §5): split conservation (7), tree invariants (8),
//! the shading scene (12), a square occluder against the ray cast and the analytic shadow (13),
//! every degenerate configuration (14), the three coloured lights (15), the bake's cache and
//! its refusals.

use glam::DVec3;

use super::setup::{self, build_tree, Projection, Settings, Setup};
use super::{Baked, Config, Mode, Storage};
use crate::lighting::many_lights::{LightModel, ManyLight, Occluders, ScenePolygon};
use crate::util::progress::Progress;
use crate::world::bsp::{Child, Tree};
use crate::world::polygon::point_segment_distance;
use crate::world::{Plane, Polygon, Split, Tolerance, PLANE_EPSILON};

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
    fn unit(&mut self) -> DVec3 {
        loop {
            let d = v(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            if (0.01..1.0).contains(&d.length_squared()) {
                return d.normalize();
            }
        }
    }
}

/// The quad `corner, corner + u, corner + u + w, corner + w` (front where `u × w` points).
fn quad(corner: DVec3, u: DVec3, w: DVec3) -> ScenePolygon {
    let polygon = Polygon::from_vertices(vec![corner, corner + u, corner + u + w, corner + w]).expect("a quad");
    ScenePolygon {
        polygon,
        albedo: DVec3::splat(0.5),
        emission: DVec3::ZERO,
        draw: 0,
    }
}

/// A floor at y = 0 of side `side` centred on the origin, facing up.
fn floor(side: f64) -> ScenePolygon {
    quad(v(-side / 2.0, 0.0, side / 2.0), v(side, 0.0, 0.0), v(0.0, 0.0, -side))
}

/// A horizontal square facing up at height `y`, centre `(x, z)`, side `side`.
fn plate(x: f64, y: f64, z: f64, side: f64) -> ScenePolygon {
    quad(
        v(x - side / 2.0, y, z + side / 2.0),
        v(side, 0.0, 0.0),
        v(0.0, 0.0, -side),
    )
}

fn point(position: DVec3, rgb: DVec3) -> ManyLight {
    ManyLight {
        position,
        direction: DVec3::NEG_Y,
        intensity: rgb,
        cone: None,
    }
}

fn run(polygons: &[ScenePolygon], lights: &[ManyLight], projection: Projection, area: f64) -> Setup {
    run_in(polygons, lights, projection, crate::world::Tolerance::EXACT, area)
}

fn run_in(
    polygons: &[ScenePolygon],
    lights: &[ManyLight],
    projection: Projection,
    tolerance: crate::world::Tolerance,
    area: f64,
) -> Setup {
    let model = match projection {
        Projection::Valid => LightModel::Physical,
        Projection::Thesis => LightModel::Seed { k: 1.0 },
    };
    let settings = Settings {
        model,
        projection,
        tolerance,
        max_segment_area: area,
        two_sided: projection == Projection::Valid,
        threads: 2,
        cull_by_cones: true,
        max_matrix_bytes: super::MAX_MATRIX_BYTES,
        bytes_per_entry: 12,
    };
    setup::run(polygons, lights, &settings, &mut Progress::new("test")).unwrap_or_else(|e| panic!("{e}"))
}

/// Per light, the vertices the shadow pass darkened against the ray cast: (disagreements
/// farther than `eps` from the shadow's edge, disagreements within it, vertices the light
/// reaches, vertices in shadow by the ray cast). Whether a vertex is near the edge is decided
/// by the ray cast itself (a verdict that flips within `eps` of the vertex), independent of any
/// projection. Vertices the light does not reach (facing away, outside a cone) are not counted.
fn against_ray_cast(
    s: &Setup,
    polygons: &[ScenePolygon],
    lights: &[ManyLight],
    l: usize,
    eps: f64,
) -> (usize, usize, usize, usize) {
    against_ray_cast_rows(s, polygons, lights, l, eps, 0..s.vertices())
}

/// [`against_ray_cast`] over the matrix rows `rows` only.
fn against_ray_cast_rows(
    s: &Setup,
    polygons: &[ScenePolygon],
    lights: &[ManyLight],
    l: usize,
    eps: f64,
    rows: std::ops::Range<usize>,
) -> (usize, usize, usize, usize) {
    let occluders = Occluders::new(polygons.iter().map(|p| &p.polygon));
    let light = &lights[l];
    let (mut far, mut near, mut reached, mut blocked_count) = (0, 0, 0, 0);
    for vtx in rows {
        let (p, n) = (s.segments.positions[vtx], s.segments.normals[vtx]);
        let model = LightModel::Physical;
        if light.shade(&model, p, n, DVec3::ONE) == DVec3::ZERO {
            continue;
        }
        reached += 1;
        let blocked = occluders.blocked(p, light.position);
        blocked_count += usize::from(blocked);
        let dark = s.colour(l, vtx) == [0.0; 3];
        if dark == blocked {
            continue;
        }
        // Jitter within the polygon's plane in eight directions.
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let flips = (0..8).any(|k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            occluders.blocked(p + (t * a.cos() + b * a.sin()) * eps, light.position) != blocked
        });
        if flips {
            near += 1;
        } else {
            far += 1;
        }
    }
    (far, near, reached, blocked_count)
}

fn area_of(points: &[DVec3]) -> f64 {
    Polygon::from_vertices(points.to_vec()).map_or(0.0, |p| p.area())
}

// ---------------------------------------------------------------------------------------------
// §5 item 7: split conservation.

fn random_convex(rng: &mut Lcg) -> Polygon {
    loop {
        let n = rng.unit();
        let c = v(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let k = 3 + (rng.f() * 6.0) as usize;
        let mut angles: Vec<f64> = (0..k).map(|_| rng.range(0.0, std::f64::consts::TAU)).collect();
        angles.sort_by(f64::total_cmp);
        let r = rng.range(0.2, 1.5);
        let points = angles.iter().map(|a| c + (t * a.cos() + b * a.sin()) * r).collect();
        if let Some(p) = Polygon::from_vertices(points) {
            return p;
        }
    }
}

fn assert_convex_planar(p: &Polygon, normal: DVec3, what: &str) {
    let n = p.vertices.len();
    assert!(n >= 3, "{what}: {n} vertices");
    for i in 0..n {
        let (a, b, c) = (p.vertices[i], p.vertices[(i + 1) % n], p.vertices[(i + 2) % n]);
        assert!(
            p.plane.distance(a).abs() < 1e-9,
            "{what}: vertex {i} off its plane by {}",
            p.plane.distance(a)
        );
        // Counter-clockwise about the original normal at every corner: convex, cyclic order.
        assert!(
            (b - a).cross(c - b).dot(normal) >= -1e-9,
            "{what}: reflex or reordered corner {i}"
        );
    }
}

#[test]
fn splitting_conserves_area_sides_and_convexity() {
    let mut rng = Lcg(3);
    let mut spanning = 0;
    for case in 0..2000 {
        let poly = random_convex(&mut rng);
        let plane = Plane::from_normal_point(rng.unit(), poly.center() + rng.unit() * rng.range(0.0, 0.8)).unwrap();
        let (area, normal) = (poly.area(), poly.plane.normal);
        match poly.clone().split(&plane) {
            Split::Spanning { front, back } => {
                spanning += 1;
                let fa = front.as_ref().map_or(0.0, |p| p.area());
                let ba = back.as_ref().map_or(0.0, |p| p.area());
                // A piece thinner than the epsilon is dropped as degenerate (at most its area).
                let dropped = f64::from(u8::from(front.is_none()) + u8::from(back.is_none())) * 1e-4;
                assert!(
                    (fa + ba - area).abs() <= 1e-12 * area.max(1.0) + dropped,
                    "case {case}: {fa} + {ba} != {area}"
                );
                if let Some(f) = &front {
                    assert!(
                        f.vertices.iter().all(|&x| plane.distance(x) >= -PLANE_EPSILON),
                        "case {case}: front piece behind the plane"
                    );
                    assert_convex_planar(f, normal, &format!("case {case} front"));
                }
                if let Some(b) = &back {
                    assert!(
                        b.vertices.iter().all(|&x| plane.distance(x) <= PLANE_EPSILON),
                        "case {case}: back piece in front of the plane"
                    );
                    assert_convex_planar(b, normal, &format!("case {case} back"));
                }
            }
            Split::Front(p) => assert!(p.vertices.iter().all(|&x| plane.distance(x) >= -PLANE_EPSILON)),
            Split::Back(p) => assert!(p.vertices.iter().all(|&x| plane.distance(x) <= PLANE_EPSILON)),
            Split::On(..) => {}
        }
    }
    assert!(spanning > 500, "only {spanning} of the random cases were split");
}

// ---------------------------------------------------------------------------------------------
// §5 item 8: tree invariants.

/// Every fragment of the subtree at `child` lies on the kept side of every plane in `path`
/// (`true`: in front), within the epsilon.
fn check_sides(tree: &Tree, child: Child, path: &mut Vec<(Plane, bool)>, visited: &mut usize) {
    let Child::Node(n) = child else { return };
    let node = &tree.nodes[n as usize];
    for &f in &node.faces {
        *visited += 1;
        let polygon = &tree.fragments[f as usize].0.polygon;
        for (plane, front) in path.iter() {
            for &x in &polygon.vertices {
                let d = plane.distance(x);
                assert!(
                    if *front {
                        d >= -PLANE_EPSILON
                    } else {
                        d <= PLANE_EPSILON
                    },
                    "fragment {f} on the wrong side of an ancestor ({d})"
                );
            }
        }
    }
    path.push((node.plane, true));
    check_sides(tree, node.front, path, visited);
    path.pop();
    path.push((node.plane, false));
    check_sides(tree, node.back, path, visited);
    path.pop();
}

#[test]
fn the_first_polygon_tree_conserves_area_and_keeps_fragments_on_their_side() {
    let mut rng = Lcg(11);
    for scene in 0..5 {
        let polygons: Vec<ScenePolygon> = (0..40)
            .map(|_| ScenePolygon {
                polygon: random_convex(&mut rng),
                albedo: DVec3::ONE,
                emission: DVec3::ZERO,
                draw: 0,
            })
            .collect();
        let tree = build_tree(&polygons);
        let before: f64 = polygons.iter().map(|p| p.polygon.area()).sum();
        let after: f64 = tree.fragments.iter().map(|(f, _)| f.polygon.area()).sum();
        let slack = tree.degenerate_fragments as f64 * crate::world::MIN_POLYGON_AREA;
        assert!(
            (before - after).abs() <= 1e-9 * before + slack,
            "scene {scene}: area {before} -> {after}"
        );
        assert!(
            tree.fragments.len() > polygons.len(),
            "scene {scene}: random polygons should split"
        );
        // The first polygon is the root's splitter.
        assert_eq!(tree.nodes[0].plane, polygons[0].polygon.plane);
        let mut visited = 0;
        check_sides(&tree, tree.root.unwrap(), &mut Vec::new(), &mut visited);
        assert_eq!(visited, tree.fragments.len());
        // Each source's fragments add up to its area.
        for (i, p) in polygons.iter().enumerate() {
            let a: f64 = tree
                .fragments
                .iter()
                .filter(|(f, _)| f.source == i)
                .map(|(f, _)| f.polygon.area())
                .sum();
            assert!(
                (a - p.polygon.area()).abs() <= 1e-9 * p.polygon.area() + slack,
                "scene {scene}: polygon {i}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// §5 item 12: the shading scene.

/// A unit box (outward faces) with its lower face at `y0`.
fn cube(y0: f64) -> Vec<ScenePolygon> {
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let c = v(-0.5, y0, -0.5);
    vec![
        quad(c + y, z, x), // top (+y)
        quad(c, x, z),     // bottom (−y)
        quad(c + x, y, z), // +x
        quad(c, z, y),     // −x
        quad(c + z, x, y), // +z
        quad(c, y, x),     // −z
    ]
}

#[test]
fn a_box_above_a_plane_under_an_overhead_light() {
    let mut polygons = vec![floor(6.0)];
    polygons.extend(cube(0.5));
    for (i, p) in polygons.iter().enumerate().skip(1) {
        // The faces point out of the box.
        assert!(
            p.polygon.plane.normal.dot(p.polygon.center() - v(0.0, 1.0, 0.0)) > 0.0,
            "face {i}"
        );
    }
    // Nearly overhead: the +x and +z sides see the light at a grazing angle.
    let light = v(1.0, 5.0, 0.6);
    let lights = [point(light, DVec3::splat(10.0))];
    let s = run(&polygons, &lights, Projection::Valid, 0.01);
    // The front sides (the back rows of the faces the light is behind are inside the box).
    let by_source = |src: u32| -> Vec<f32> {
        (0..s.front_vertices)
            .filter(|&x| s.fragment_source[s.segments.vertex_polygon[x] as usize] == src)
            .map(|x| s.colour(0, x)[0])
            .collect()
    };
    let top = by_source(1);
    let bottom = by_source(2);
    let sides: Vec<f32> = (3..7).flat_map(by_source).collect();
    let min_top = top.iter().copied().fold(f32::INFINITY, f32::min);
    let max_side = sides.iter().copied().fold(0.0, f32::max);
    println!("top {min_top:.5}..; sides ..{max_side:.5}");
    assert!(
        max_side > 0.0 && max_side < 0.25 * min_top,
        "sides {max_side} vs top {min_top}"
    );
    assert!(bottom.iter().all(|&c| c == 0.0), "the bottom faces away");
    // Closed form at the top's centre: I·ρ·cos/(π·d²).
    let top_centre = v(0.0, 1.5, 0.0);
    let centre = (0..s.vertices())
        .find(|&x| s.segments.positions[x].distance(top_centre) < 1e-9)
        .expect("a vertex at the top's centre");
    let d = light.distance(top_centre);
    let want = 10.0 * 0.5 * (3.5 / d) / (std::f64::consts::PI * d * d);
    assert!((s.colour(0, centre)[0] as f64 - want).abs() < 1e-6 * want);
    // The floor under the box is in its shadow; the floor's far corner is lit.
    let floor_at = |p: DVec3| {
        (0..s.vertices())
            .filter(|&x| s.fragment_source[s.segments.vertex_polygon[x] as usize] == 0)
            .min_by(|&a, &b| {
                s.segments.positions[a]
                    .distance(p)
                    .total_cmp(&s.segments.positions[b].distance(p))
            })
            .unwrap()
    };
    assert_eq!(s.colour(0, floor_at(v(0.1, 0.0, 0.1)))[0], 0.0);
    assert!(s.colour(0, floor_at(v(2.9, 0.0, 2.9)))[0] > 0.0);
}

/// Corrected mode lights both sides of a thin surface, as every other method and the path
/// tracer do: a plate lit from above by a red light and from below by a blue one, with a small
/// plate under it casting a shadow on its underside. Its front rows carry the red light only,
/// its back rows (normal turned) the blue one only, the underside's shadow matches the ray
/// cast, and the closed form holds on the underside. Faithful mode (the thesis) has no back
/// rows.
#[test]
fn two_sided_rows_light_the_back_of_a_surface_with_its_shadows() {
    let polygons = vec![plate(0.0, 1.0, 0.0, 2.0), plate(0.3, 0.5, 0.0, 0.4)];
    let (above, below) = (v(0.2, 2.0, 0.1), v(0.1, 0.0, -0.1));
    let lights = [point(above, v(4.0, 0.0, 0.0)), point(below, v(0.0, 0.0, 4.0))];
    let s = run(&polygons, &lights, Projection::Valid, 0.005);
    let panel = |x: usize| s.fragment_source[s.segments.vertex_polygon[x] as usize] == 0;
    let (front, back): (Vec<usize>, Vec<usize>) = (0..s.vertices())
        .filter(|&x| panel(x))
        .partition(|&x| x < s.front_vertices);
    assert!(
        !back.is_empty() && front.len() == back.len(),
        "every vertex of the panel has its back row ({} front, {} back)",
        front.len(),
        back.len()
    );
    for &x in &front {
        assert!(
            s.colour(0, x)[0] > 0.0 && s.colour(1, x) == [0.0; 3],
            "front row {x}: red only"
        );
        let b = s.back_row[x] as usize;
        assert!(
            back.contains(&b) && s.segments.positions[b] == s.segments.positions[x],
            "front row {x}: its back row {b} is at the same place"
        );
    }
    for &x in &back {
        assert_eq!(s.colour(0, x), [0.0; 3], "back row {x}: no red");
        assert!(s.segments.normals[x].y < -0.999);
    }
    let (far, near, reached, blocked) = against_ray_cast(&s, &polygons, &lights, 1, 1e-4);
    println!("blue light: {reached} rows reached, {blocked} blocked, {far} far from the edge disagree, {near} near");
    assert_eq!(far, 0);
    let dark = back.iter().filter(|&&x| s.colour(1, x) == [0.0; 3]).count();
    assert!(
        dark > 20 && dark < back.len() / 4,
        "the small plate shadows part of the underside ({dark} of {} rows)",
        back.len()
    );
    // I·ρ·cos/(π·d²) at the underside's corner, far from the shadow.
    let corner = *back
        .iter()
        .min_by(|&&a, &&b| {
            s.segments.positions[a]
                .distance(v(-1.0, 1.0, 1.0))
                .total_cmp(&s.segments.positions[b].distance(v(-1.0, 1.0, 1.0)))
        })
        .unwrap();
    let p = s.segments.positions[corner];
    let d = p.distance(below);
    let want = 4.0 * 0.5 * (1.0 / d) / (std::f64::consts::PI * d * d);
    assert!(
        (s.colour(1, corner)[2] as f64 - want).abs() < 1e-6 * want,
        "{} against {want}",
        s.colour(1, corner)[2]
    );
    let faithful = run(&polygons, &lights, Projection::Thesis, 0.005);
    assert_eq!(
        faithful.vertices(),
        faithful.front_vertices,
        "the thesis lights the front only"
    );
}

// ---------------------------------------------------------------------------------------------
// §5 item 13: a square occluder against the ray cast and the analytic shadow.

#[test]
fn a_square_occluder_against_the_ray_cast_and_the_analytic_shadow() {
    let polygons = vec![floor(5.0), plate(0.0, 1.0, 0.0, 1.0)];
    let light = v(0.3, 3.0, 0.2);
    let lights = [point(light, DVec3::splat(5.0))];
    // Analytic shadow: the square's corners projected from the light onto y = 0.
    let shadow: Vec<DVec3> = polygons[1]
        .polygon
        .vertices
        .iter()
        .map(|&c| c + (c - light) * (c.y / (light.y - c.y)))
        .collect();
    let (area, perimeter) = (area_of(&shadow), 4.0 * shadow[0].distance(shadow[1]));
    assert!(
        (area - 2.25).abs() < 1e-9,
        "the analytic shadow is the square scaled 1.5x: {area}"
    );
    // The thesis's rounding moves a vertex and a shadow's corners by at most 0.5e-4 per axis
    // (7.1e-5 in the floor's plane), less than the 1e-4 margin.
    for (projection, tolerance) in [
        (Projection::Valid, Tolerance::EXACT),
        (Projection::Thesis, Tolerance::EXACT),
        (Projection::Thesis, Tolerance::THESIS),
    ] {
        let projection_name = format!("{projection:?} {tolerance:?}");
        // Floor segments of about 2 cm (2^8 steps along its 5 m edges).
        let s = run_in(&polygons, &lights, projection, tolerance, 2e-4);
        let (far, near, reached, blocked) = against_ray_cast(&s, &polygons, &lights, 0, 1e-4);
        println!("{projection_name}: {reached} vertices lit by the model, {blocked} blocked; {far} disagree farther than 1e-4 from the edge, {near} within");
        assert_eq!(
            far, 0,
            "{projection_name}: vertices away from the shadow's edge disagree with the ray cast"
        );
        // Agreement by the analytic boundary too.
        let mut disagreements_off_edge = 0;
        let (mut dark_floor, mut floor_vertices) = (0usize, 0usize);
        for x in 0..s.vertices() {
            let p = s.segments.positions[x];
            if s.fragment_source[s.segments.vertex_polygon[x] as usize] != 0 {
                continue;
            }
            floor_vertices += 1;
            let dark = s.colour(0, x) == [0.0; 3];
            dark_floor += usize::from(dark);
            let inside = Polygon::from_vertices(shadow.clone()).unwrap().contains_point(p, 0.0);
            let edge = (0..4)
                .map(|i| point_segment_distance(p, shadow[i], shadow[(i + 1) % 4]))
                .fold(f64::INFINITY, f64::min);
            if edge > 1e-4 && dark != inside {
                disagreements_off_edge += 1;
            }
        }
        assert_eq!(disagreements_off_edge, 0, "{projection_name}");
        // Shadowed area: dark vertices × the area per floor vertex, against the closed form,
        // within one vertex spacing along the perimeter.
        let h = 5.0 / 256.0;
        let measured = dark_floor as f64 * 25.0 / floor_vertices as f64;
        println!(
            "{projection_name}: shadowed area {measured:.4} m² vs analytic {area:.4} (allowed ±{:.4})",
            perimeter * h
        );
        assert!(
            (measured - area).abs() <= perimeter * h,
            "{projection_name}: {measured} vs {area}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// §5 item 14: the degenerate configurations.

/// Floor vertices darkened for light 0.
fn dark_floor(s: &Setup, pred: impl Fn(DVec3) -> bool) -> usize {
    (0..s.vertices())
        .filter(|&x| {
            s.fragment_source[s.segments.vertex_polygon[x] as usize] == 0
                && pred(s.segments.positions[x])
                && s.colour(0, x) == [0.0; 3]
        })
        .count()
}

#[test]
fn a_light_between_occluder_and_receiver_casts_nothing_there() {
    // The plate is above the light: seen from the floor it is behind the light.
    let polygons = vec![floor(4.0), plate(0.2, 2.0, 0.0, 1.0)];
    let lights = [point(v(0.0, 1.0, 0.0), DVec3::splat(5.0))];
    let s = run(&polygons, &lights, Projection::Valid, 0.002);
    let (far, _, reached, blocked) = against_ray_cast(&s, &polygons, &lights, 0, 1e-4);
    assert_eq!((far, blocked), (0, 0), "{reached} reached");
    assert_eq!(dark_floor(&s, |_| true), 0, "corrected: no floor vertex is dark");
    // The thesis projects the plate through the light (t = −1): an inverted shadow.
    let faithful = run(&polygons, &lights, Projection::Thesis, 0.002);
    let inverted = dark_floor(&faithful, |p| p.x < 0.0);
    println!("faithful: {inverted} floor vertices under the inverted shadow");
    assert!(
        inverted > 100,
        "the thesis's projection should show the inverted shadow"
    );
}

#[test]
fn an_occluder_straddling_the_lights_parallel_plane_is_clipped_not_inverted() {
    // A steep plate from y = 1 (x = 0.5) to y = 3 (x = 1), through the plane y = 2 of the light.
    let occluder = quad(v(0.5, 1.0, 0.5), v(0.5, 2.0, 0.0), v(0.0, 0.0, -1.0));
    let polygons = vec![floor(5.0), occluder];
    let lights = [point(v(0.0, 2.0, 0.0), DVec3::splat(5.0))];
    let corrected = run(&polygons, &lights, Projection::Valid, 0.002);
    let (far, near, reached, blocked) = against_ray_cast(&corrected, &polygons, &lights, 0, 1e-4);
    println!("corrected: {reached} reached, {blocked} blocked, {far} disagree away from the edge, {near} near it");
    assert_eq!(far, 0, "corrected");
    assert!(blocked > 100, "the lower half casts a real shadow beyond x = 1");
    assert_eq!(
        dark_floor(&corrected, |p| p.x < 0.9),
        0,
        "corrected: nothing dark on the light's side of the shadow"
    );
    // The thesis's projection of the upper half lands through the light, at negative x.
    let faithful = run(&polygons, &lights, Projection::Thesis, 0.002);
    let (far, ..) = against_ray_cast(&faithful, &polygons, &lights, 0, 1e-4);
    let inverted = dark_floor(&faithful, |p| p.x < 0.0);
    println!("faithful: {far} disagree with the ray cast, {inverted} dark at x < 0");
    assert!(
        far > 100 && inverted > 100,
        "the thesis's projection should show the inverted shadow"
    );
}

#[test]
fn a_receiver_in_front_of_the_occluder_is_not_shadowed_by_it() {
    // Seen from the light, the small plate at y = 2 is in front of the one at y = 1.
    let polygons = vec![floor(4.0), plate(0.0, 1.0, 0.0, 1.0), plate(0.0, 2.0, 0.0, 0.6)];
    let lights = [point(v(0.1, 3.0, 0.0), DVec3::splat(5.0))];
    for projection in [Projection::Valid, Projection::Thesis] {
        let s = run(&polygons, &lights, projection, 0.002);
        let front = (0..s.vertices()).filter(|&x| s.fragment_source[s.segments.vertex_polygon[x] as usize] == 2);
        assert!(front.clone().count() > 0);
        for x in front {
            assert_ne!(
                s.colour(0, x),
                [0.0; 3],
                "{projection:?}: the front plate is lit everywhere"
            );
        }
        let (far, ..) = against_ray_cast(&s, &polygons, &lights, 0, 1e-4);
        assert_eq!(far, 0, "{projection:?}");
    }
}

#[test]
fn coplanar_and_touching_polygons_cast_no_slivers_and_do_not_shadow_themselves() {
    // Two floor tiles sharing an edge, and a box standing on one of them (touching it).
    let tiles = vec![
        quad(v(-2.0, 0.0, 2.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -4.0)),
        quad(v(0.0, 0.0, 2.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, -4.0)),
    ];
    let light = v(0.0, 4.0, 0.0);
    let lights = [point(light, DVec3::splat(5.0))];
    for projection in [Projection::Valid, Projection::Thesis] {
        let s = run(&tiles, &lights, projection, 0.005);
        assert!(
            (0..s.vertices()).all(|x| s.colour(0, x) != [0.0; 3]),
            "{projection:?}: coplanar tiles darken each other"
        );
    }
    let mut polygons = tiles.clone();
    polygons.extend(cube(0.0).into_iter().map(|mut p| {
        p.polygon.vertices.iter_mut().for_each(|x| *x += v(0.7, 0.0, 0.3));
        p.polygon.plane.dist = p.polygon.plane.normal.dot(p.polygon.vertices[0]);
        p
    }));
    let s = run(&polygons, &lights, Projection::Valid, 0.005);
    let top = (0..s.vertices()).filter(|&x| s.fragment_source[s.segments.vertex_polygon[x] as usize] == 2);
    assert!(
        top.clone().all(|x| s.colour(0, x) != [0.0; 3]),
        "the box's top is lit everywhere"
    );
    // The other face that sees the light (−x) is not shadowed by the box itself.
    let minus_x = (0..s.front_vertices).filter(|&x| s.fragment_source[s.segments.vertex_polygon[x] as usize] == 5);
    assert!(
        minus_x
            .clone()
            .all(|x| s.colour(0, x) != [0.0; 3] || s.segments.positions[x].y < 1e-9),
        "the −x face shadows itself"
    );
    // The front sides: the back rows here are the box's inside, where three vertices' rays to
    // the light run exactly along the box's edges (either verdict is right there).
    let (far, near, reached, blocked) = against_ray_cast_rows(&s, &polygons, &lights, 0, 1e-4, 0..s.front_vertices);
    println!("box on the floor: {reached} reached, {blocked} blocked, {far} far, {near} near");
    assert_eq!(far, 0);
}

#[test]
fn an_occluder_partly_outside_the_receiver_shadows_only_the_receiver() {
    // A 1 m floor; the plate's shadow falls half off it.
    let polygons = vec![floor(1.0), plate(0.5, 1.0, 0.0, 0.8)];
    let lights = [point(v(0.5, 3.0, 0.0), DVec3::splat(5.0))];
    for projection in [Projection::Valid, Projection::Thesis] {
        let s = run(&polygons, &lights, projection, 0.001);
        let (far, _, _, blocked) = against_ray_cast(&s, &polygons, &lights, 0, 1e-4);
        assert_eq!(far, 0, "{projection:?}");
        // Only the receiver's vertices exist to be darkened: the shadow is clipped to it.
        assert!(blocked > 50 && dark_floor(&s, |_| true) > 50, "{projection:?}");
    }
}

#[test]
fn a_light_inside_another_lights_cone_is_unaffected() {
    let polygons = vec![floor(6.0), plate(0.0, 1.0, 0.0, 1.0)];
    // The second light sits in the first's cone: lights are not occluders, so neither column
    // changes with the other present.
    let a = ManyLight {
        position: v(0.0, 4.0, 0.0),
        direction: DVec3::NEG_Y,
        intensity: DVec3::splat(8.0),
        cone: Some((0.5, 0.7)),
    };
    let b = ManyLight {
        position: v(0.3, 2.5, 0.0),
        direction: v(0.3, -1.0, 0.0).normalize(),
        intensity: DVec3::new(0.0, 4.0, 0.0),
        cone: Some((0.4, 0.6)),
    };
    assert!(
        a.reach(&LightModel::Physical, b.position).is_some(),
        "b is inside a's cone"
    );
    let both = run(&polygons, &[a, b], Projection::Valid, 0.01);
    let alone_a = run(&polygons, &[a], Projection::Valid, 0.01);
    let alone_b = run(&polygons, &[b], Projection::Valid, 0.01);
    for x in 0..both.vertices() {
        assert_eq!(both.colour(0, x), alone_a.colour(0, x));
        assert_eq!(both.colour(1, x), alone_b.colour(0, x));
    }
    for l in 0..2 {
        let (far, ..) = against_ray_cast(&both, &polygons, &[a, b], l, 1e-4);
        assert_eq!(far, 0, "light {l}");
    }
}

// ---------------------------------------------------------------------------------------------
// §5 item 15: three coloured lights.

#[test]
fn three_coloured_lights_darken_exactly_their_own_channel_where_their_ray_is_blocked() {
    let polygons = vec![floor(6.0), plate(0.0, 1.0, 0.0, 1.0)];
    let lights = [
        point(v(-1.5, 3.0, 0.0), v(6.0, 0.0, 0.0)),
        point(v(1.5, 3.0, 0.5), v(0.0, 6.0, 0.0)),
        point(v(0.0, 3.0, -1.5), v(0.0, 0.0, 6.0)),
    ];
    for projection in [Projection::Valid, Projection::Thesis] {
        let s = run(&polygons, &lights, projection, 0.002);
        for l in 0..lights.len() {
            let (far, near, reached, blocked) = against_ray_cast(&s, &polygons, &lights, l, 1e-4);
            println!("{projection:?} light {l}: {reached} reached, {blocked} blocked, {far} far, {near} near");
            assert_eq!(far, 0, "{projection:?} light {l}");
            assert!(blocked > 500, "{projection:?} light {l}: a shadow on the floor");
            // Only this light's channel carries its colour: the sum's channel l is dark exactly
            // where light l's column is.
            for x in 0..s.vertices() {
                let c = s.colour(l, x);
                assert!((0..3).all(|ch| ch == l || c[ch] == 0.0));
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The bake: its cache, its refusals and its parameters.

fn scene(methods: &str, lights: usize) -> crate::scene::Scene {
    let mut text = format!(
        "methods = [{methods}]\n[camera]\nposition = [0, 3, 4]\ntarget = [0, 0, 0]\n\
         [[objects]]\nmesh = \"plane\"\nsize = 4\n\
         [[objects]]\nmesh = \"box\"\nsize = 0.6\ntranslate = [0, 0.8, 0]\n"
    );
    for i in 0..lights {
        let x = -1.5 + 3.0 * (i as f64 + 0.5) / lights as f64;
        text += &format!("[[lights]]\ntype = \"point\"\nposition = [{x}, 2.5, 0.3]\nintensity = [2, 2, 2]\n");
    }
    crate::scene::Scene::from_str(&text, "bsp test.toml", std::path::Path::new("scenes"))
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_bake_round_trips_through_the_cache_and_its_key() {
    use crate::bake::{BakeData, BakeKey, Baker};
    let sc = scene("{ name = \"bsp_lights\", max_segment_area = 0.05 }", 3);
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&sc, super::NAME).unwrap();
    let config = Config::from_decl(&sc.methods[0], Some(&sc)).unwrap();
    let (s, polygons) = super::bake_scene(
        &sc,
        &geometry,
        &config,
        super::MAX_MATRIX_BYTES,
        &mut Progress::new("test"),
    )
    .unwrap();
    let baked = Baked::from_setup(&s, &polygons);
    assert_eq!(Baked::decode(&baked.encode()), Some(baked.clone()));
    // A second set-up of the same inputs stores the same bytes: no timings in them.
    let (again, _) = super::bake_scene(
        &sc,
        &geometry,
        &config,
        super::MAX_MATRIX_BYTES,
        &mut Progress::new("test"),
    )
    .unwrap();
    assert_ne!(again.phases, s.phases, "two set-ups ran in exactly the same time");
    assert!(Baked::from_setup(&again, &polygons).encode() == baked.encode());
    assert!(Baked::decode(&baked.encode()[..100]).is_none());
    // The painter's tree survives the round trip: the same order from any eye as the set-up's
    // tree, and a cut-off or trailing byte is refused.
    let decoded = Baked::decode(&baked.encode()).unwrap();
    for eye in [
        DVec3::new(0.0, 3.0, 4.0),
        DVec3::new(-2.0, 0.5, -3.0),
        DVec3::new(1.0, -1.0, 0.2),
    ] {
        let order = s.tree.faces_back_to_front(eye);
        assert_eq!(order.len(), s.tree.fragments.len());
        assert_eq!(decoded.painter.back_to_front(eye), order);
    }
    let bytes = baked.encode();
    assert!(Baked::decode(&bytes[..bytes.len() - 1]).is_none());
    assert!(Baked::decode(&[bytes.as_slice(), &[0]].concat()).is_none());
    assert_eq!(baked.bytes_per_light(Storage::F32), 12 * baked.vertices.len() as u64);
    assert_eq!(baked.bytes_per_light(Storage::F16), 6 * baked.vertices.len() as u64);
    let dir = crate::util::test_files::TestDir::new("bsp-lights");
    let mut baker = Baker::new(Some(dir.to_path_buf()));
    let key = BakeKey::new("bsp test").with("config", config);
    let mut runs = 0;
    for _ in 0..2 {
        let got: Baked = baker
            .bake("bsp test", &key, |_| {
                runs += 1;
                Ok(baked.clone())
            })
            .unwrap();
        assert_eq!(got, baked);
    }
    assert_eq!(runs, 1, "the second bake comes from the cache");
    assert!(baker.reports()[1].cached);
}

#[test]
fn too_large_a_matrix_is_one_error_naming_the_file_and_the_parameter() {
    // 2,000 lights over ~9k vertices at 12 bytes: about 200 MiB.
    let sc = scene("{ name = \"bsp_lights\", max_segment_area = 0.002 }", 2000);
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&sc, super::NAME).unwrap();
    let config = Config::from_decl(&sc.methods[0], Some(&sc)).unwrap();
    let err = match super::bake_scene(
        &sc,
        &geometry,
        &config,
        super::MAX_MATRIX_BYTES,
        &mut Progress::new("test"),
    ) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    };
    println!("{err}");
    assert!(
        !err.contains('\n')
            && err.contains("bsp test.toml")
            && err.contains("methods[0].max_segment_area")
            && err.contains("MiB storage-buffer limit"),
        "{err}"
    );
}

/// The fewest vertices the segmentation can make bounds what it makes, closely enough to refuse
/// a hopeless matrix before the BSP tree is built.
#[test]
fn the_matrix_is_refused_up_front_from_the_fewest_vertices_the_segments_can_make() {
    let sc = scene("{ name = \"bsp_lights\" }", 4);
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&sc, super::NAME).unwrap();
    let polygons = super::scene_polygons(&sc.source, &geometry, super::NAME, &Tolerance::MESH).unwrap();
    for area in [0.5, 0.05, 0.005] {
        let made = crate::lighting::many_lights::Segments::build(polygons.iter().map(|p| &p.polygon), area)
            .unwrap()
            .positions
            .len();
        let least = setup::min_vertices(&polygons, area);
        println!("max area {area}: at least {least} vertices, {made} made");
        assert!(least <= made && 8 * least >= made, "{least} vs {made}");
    }
    // 8,000 lights at 0.0005 m²: the bound alone is over 128 MiB; the refusal says so and names
    // the size, before any BSP or segment is made.
    let sc = scene("{ name = \"bsp_lights\", max_segment_area = 0.0005 }", 8000);
    let geometry = crate::lighting::lightmap::geometry::scene_geometry(&sc, super::NAME).unwrap();
    let config = Config::from_decl(&sc.methods[0], Some(&sc)).unwrap();
    let t = std::time::Instant::now();
    let err = match super::bake_scene(
        &sc,
        &geometry,
        &config,
        super::MAX_MATRIX_BYTES,
        &mut Progress::new("test"),
    ) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    };
    println!("{err} ({:.1} ms)", t.elapsed().as_secs_f64() * 1e3);
    assert!(
        err.contains("at least") && err.contains(" MiB of vertex colours, over the device's 128 MiB"),
        "{err}"
    );
}

#[test]
fn bad_parameters_are_one_line_naming_the_file_and_field() {
    for (decl, field) in [
        ("{ name = \"bsp_lights\", mode = \"exact\" }", "methods[0].mode"),
        (
            "{ name = \"bsp_lights\", max_segment_area = 0 }",
            "methods[0].max_segment_area",
        ),
        ("{ name = \"bsp_lights\", k = -1 }", "methods[0].k"),
        ("{ name = \"bsp_lights\", threshold = 1.5 }", "methods[0].threshold"),
        ("{ name = \"bsp_lights\", storage = \"f8\" }", "methods[0].storage"),
    ] {
        let sc = scene(decl, 1);
        let err = Config::from_decl(&sc.methods[0], Some(&sc))
            .err()
            .unwrap_or_else(|| panic!("{decl}: accepted"))
            .to_string();
        assert!(
            !err.contains('\n') && err.contains(field) && err.contains("bsp test.toml"),
            "{decl}: {err}"
        );
    }
    let ok = scene(
        "{ name = \"bsp_lights\", mode = \"faithful\", k = 2, threshold = 0, storage = \"f16\", max_segment_area = 1 }",
        1,
    );
    let c = Config::from_decl(&ok.methods[0], Some(&ok)).unwrap();
    assert_eq!(
        (c.mode, c.k, c.threshold, c.storage, c.max_segment_area),
        (Mode::Faithful, 2.0, 0.0, Storage::F16, 1.0)
    );
    assert_eq!(c.model(), LightModel::Seed { k: 2.0 });
    // A directional light is refused by name.
    let text =
        "methods = [\"bsp_lights\"]\n[camera]\nposition = [0, 2, 3]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"plane\"\n[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n";
    let sc = crate::scene::Scene::from_str(text, "bsp test.toml", std::path::Path::new("scenes")).unwrap();
    let err = ManyLight::from_scene(&sc, super::NAME).err().unwrap().to_string();
    assert!(
        !err.contains('\n') && err.contains("lights[0]") && err.contains("bsp test.toml"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------------------------
// §5 item 9: painter's order against a depth buffer (CPU ray-cast rasteriser).

/// Per pixel of a `size`² view from `eye` toward the origin: every fragment the pixel's ray
/// hits, with its distance.
fn pixel_hits(tree: &Tree, eye: DVec3, size: usize) -> Vec<Vec<(usize, f64)>> {
    let f = (-eye).normalize();
    let r = f.cross(DVec3::Y).normalize();
    let u = r.cross(f);
    let tan = 0.45;
    let mut out = Vec::with_capacity(size * size);
    for j in 0..size {
        for i in 0..size {
            let (x, y) = (
                ((i as f64 + 0.5) / size as f64 * 2.0 - 1.0) * tan,
                ((j as f64 + 0.5) / size as f64 * 2.0 - 1.0) * tan,
            );
            let dir = (f + r * x - u * y).normalize();
            out.push(
                tree.fragments
                    .iter()
                    .enumerate()
                    .filter_map(|(k, (frag, _))| {
                        frag.polygon
                            .intersect_ray(eye, dir, 1e-9, f64::INFINITY)
                            .map(|t| (k, t))
                    })
                    .collect(),
            );
        }
    }
    out
}

#[test]
fn the_bsp_painters_order_matches_a_depth_buffer_where_a_centroid_sort_does_not() {
    let mut rng = Lcg(21);
    // Random polygons crossing each other (cyclic overlaps a sort cannot resolve), and the
    // thesis's two intersecting polygons (Fig. 6-8).
    let mut polygons: Vec<ScenePolygon> = (0..12)
        .map(|_| ScenePolygon {
            polygon: random_convex(&mut rng),
            albedo: DVec3::ONE,
            emission: DVec3::ZERO,
            draw: 0,
        })
        .collect();
    polygons.push(quad(v(-1.0, -0.5, 0.0), v(2.0, 0.0, 0.0), v(0.0, 1.0, 0.3)));
    polygons.push(quad(v(-1.0, -0.5, 0.3), v(2.0, 0.0, 0.0), v(0.0, 1.0, -0.3)));
    let tree = build_tree(&polygons);
    let size = 48;
    let (mut bsp_wrong, mut sort_wrong, mut covered) = (0usize, 0usize, 0usize);
    for _ in 0..100 {
        let eye = rng.unit() * 5.0;
        let order = tree.faces_back_to_front(eye);
        let mut rank = vec![0usize; tree.fragments.len()];
        for (k, &f) in order.iter().enumerate() {
            rank[f as usize] = k;
        }
        // The naive painter: fragments sorted far to near by their centre's distance.
        let mut sorted: Vec<usize> = (0..tree.fragments.len()).collect();
        sorted.sort_by(|&a, &b| {
            tree.fragments[b]
                .0
                .polygon
                .center()
                .distance(eye)
                .total_cmp(&tree.fragments[a].0.polygon.center().distance(eye))
        });
        let mut sort_rank = vec![0usize; tree.fragments.len()];
        for (k, &f) in sorted.iter().enumerate() {
            sort_rank[f] = k;
        }
        let source = |k: usize| tree.fragments[k].0.source;
        for hits in pixel_hits(&tree, eye, size) {
            let Some(&(nearest, _)) = hits.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
                continue;
            };
            covered += 1;
            let painted = hits.iter().max_by_key(|h| rank[h.0]).unwrap().0;
            let naive = hits.iter().max_by_key(|h| sort_rank[h.0]).unwrap().0;
            bsp_wrong += usize::from(source(painted) != source(nearest));
            sort_wrong += usize::from(source(naive) != source(nearest));
        }
    }
    println!("{} fragments from {} polygons; over 100 eyes, {covered} covered pixels: BSP order wrong at {bsp_wrong}, centroid sort at {sort_wrong}", tree.fragments.len(), polygons.len());
    assert!(tree.fragments.len() > polygons.len());
    assert!(
        bsp_wrong as f64 <= 1e-3 * covered as f64,
        "BSP painter's order differs from the depth buffer at {bsp_wrong} of {covered} pixels"
    );
    assert!(
        sort_wrong > 10 * bsp_wrong.max(1),
        "the scene should defeat a centroid sort ({sort_wrong})"
    );
}

#[test]
fn the_sweep_covers_segment_areas_and_both_modes() {
    let sc = scene("{ name = \"bsp_lights\", max_segment_area = 0.02 }", 1);
    let labels: Vec<String> = super::sweep(&sc.methods[0]).into_iter().map(|(l, _)| l).collect();
    assert_eq!(
        labels,
        [
            "bsp_lights corrected area=0.02",
            "bsp_lights corrected area=0.08",
            "bsp_lights corrected area=0.005 f16",
            "bsp_lights faithful area=0.02"
        ]
    );
}

/// The thesis's rounding (§5.6.1, its fix for "zero-width sliver polygons when polygons just
/// touch"): a wall whose foot sits 40 µm under the floor is cut by the floor (the first
/// polygon, the root's splitter) into the wall and a 40 µm sliver under exact numerics; rounded
/// to four decimals its foot is on the floor and nothing is cut. Faithful mode's every vertex
/// lies on the 1e-4 grid, and its bake key differs from corrected mode's.
#[test]
fn faithful_numerics_round_to_four_decimals_and_leave_no_sliver_where_polygons_touch() {
    let wall = quad(v(-1.0, -4e-5, 0.0), v(2.0, 0.0, 0.0), v(0.0, 1.5, 0.0));
    let polygons = vec![floor(5.0), wall];
    let lights = [point(v(0.3, 3.0, 2.0), DVec3::splat(5.0))];
    let exact = run_in(&polygons, &lights, Projection::Thesis, Tolerance::EXACT, 0.01);
    let thesis = run_in(&polygons, &lights, Projection::Thesis, Tolerance::THESIS, 0.01);
    let wall_pieces = |s: &Setup| {
        s.tree
            .fragments
            .iter()
            .filter(|(f, _)| f.source == 1)
            .map(|(f, _)| f.polygon.bounds())
            .collect::<Vec<_>>()
    };
    let (exact_wall, thesis_wall) = (wall_pieces(&exact), wall_pieces(&thesis));
    assert_eq!(
        exact_wall.len(),
        2,
        "exact numerics cut the wall's foot off: {exact_wall:?}"
    );
    assert!(
        exact_wall.iter().any(|b| (b.max.y - b.min.y) < 1e-4),
        "one piece is a sliver under 1e-4 tall: {exact_wall:?}"
    );
    assert_eq!(
        thesis_wall.len(),
        1,
        "the rounded wall stands on the floor uncut: {thesis_wall:?}"
    );
    let on_grid = |p: DVec3| (0..3).all(|i| ((p[i] / 1e-4) - (p[i] / 1e-4).round()).abs() < 1e-6);
    assert!(
        thesis.segments.positions.iter().all(|&p| on_grid(p)),
        "every segment vertex on the 1e-4 grid"
    );
    assert!(
        thesis
            .tree
            .fragments
            .iter()
            .all(|(f, _)| f.polygon.vertices.iter().all(|&p| on_grid(p))),
        "every fragment vertex on the grid"
    );
    assert!(
        !exact.segments.positions.iter().all(|&p| on_grid(p)),
        "exact numerics keep the wall's foot at -4e-5"
    );
    let faithful = Config {
        mode: Mode::Faithful,
        ..Config::default()
    };
    assert_eq!(
        (faithful.tolerance(), Config::default().tolerance()),
        (Tolerance::THESIS, Tolerance::MESH)
    );
}

/// The shadow pass's cone test only skips pairs that cannot shadow: over a floor under 150
/// small plates at three heights (most pairs of plates far apart as seen from a light, some
/// overlapping), lit by three lights, the matrix with the skip is the matrix without it, bit
/// for bit.
#[test]
fn skipping_pairs_whose_cones_are_apart_changes_no_vertex() {
    let mut rng = crate::world::level_gen::Rng::new(11);
    let mut polygons = vec![floor(6.0)];
    for _ in 0..150 {
        let (x, z) = (rng.unit() * 5.0 - 2.5, rng.unit() * 5.0 - 2.5);
        polygons.push(plate(
            x,
            0.3 + 0.4 * (rng.unit() * 3.0).floor(),
            z,
            0.1 + 0.3 * rng.unit(),
        ));
    }
    let lights = [
        point(v(0.5, 3.0, 0.2), DVec3::splat(4.0)),
        point(v(-2.0, 1.6, 1.0), DVec3::new(2.0, 1.0, 1.0)),
        point(v(1.0, 0.5, -1.5), DVec3::splat(1.0)),
    ];
    let settings = |cull_by_cones| Settings {
        model: LightModel::Physical,
        projection: Projection::Valid,
        tolerance: crate::world::Tolerance::MESH,
        max_segment_area: 0.02,
        two_sided: true,
        threads: 2,
        cull_by_cones,
        max_matrix_bytes: super::MAX_MATRIX_BYTES,
        bytes_per_entry: 12,
    };
    let run = |cull| {
        let start = std::time::Instant::now();
        let s = setup::run(&polygons, &lights, &settings(cull), &mut Progress::new("test")).unwrap();
        (s, start.elapsed().as_secs_f64())
    };
    let ((culled, fast), (every, slow)) = (run(true), run(false));
    let dark = every.colours.iter().filter(|c| **c == [0.0; 3]).count();
    println!(
        "{} fragments, {} vertices x 3 lights, {dark} entries dark: {fast:.3} s with the skip, {slow:.3} s without",
        every.tree.fragments.len(),
        every.vertices()
    );
    assert!(
        dark > every.colours.len() / 20,
        "the plates shadow the floor: {dark} dark"
    );
    assert!(culled.colours == every.colours, "the skip changed the matrix");
}
