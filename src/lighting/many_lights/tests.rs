//! The digest's §5 items 1–6, 10 and 11: the geometric primitives, segmentation and the light
//! models against closed forms and independent tests.

use glam::DVec3;

use super::geometry::{line_line, point_in_convex_polygon, segment_plane, BehindApex, Cone};
use super::light_model::{opengl_spot_exponent, physical_spot_falloff, seed_spot_ramp, LightModel, ManyLight};
use super::occluders::Occluders;
use super::segments::Segments;
use crate::world::{Plane, Polygon};

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// A small deterministic generator: the tests must not depend on a crate's RNG.
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

#[test]
fn line_line_meets_misses_and_covers_every_axis_pair() {
    let (p, s, t) = line_line(v(0.0, 0.0, 0.0), v(2.0, 2.0, 0.0), v(0.0, 2.0, 0.0), v(2.0, 0.0, 0.0)).unwrap();
    assert!(p.distance(v(1.0, 1.0, 0.0)) < 1e-12 && (s - 0.5).abs() < 1e-12 && (t - 0.5).abs() < 1e-12);
    // Parallel, then skew by 1 in z (the third-axis check), then meeting beyond a segment's end.
    assert!(line_line(v(0.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0), v(1.0, 2.0, 0.0)).is_none());
    assert!(line_line(v(0.0, 0.0, 0.0), v(2.0, 2.0, 0.0), v(0.0, 2.0, 1.0), v(2.0, 0.0, 1.0)).is_none());
    assert!(line_line(v(0.0, 0.0, 0.0), v(0.5, 0.5, 0.0), v(0.0, 2.0, 0.0), v(2.0, 0.0, 0.0)).is_none());
    // The same crossing in the x–z and y–z planes (the other (p, q) choices).
    let (p, _, _) = line_line(v(0.0, 0.0, 0.0), v(2.0, 0.0, 2.0), v(0.0, 0.0, 2.0), v(2.0, 0.0, 0.0)).unwrap();
    assert!(p.distance(v(1.0, 0.0, 1.0)) < 1e-12);
    let (p, _, _) = line_line(v(3.0, 0.0, 0.0), v(3.0, 2.0, 2.0), v(3.0, 0.0, 2.0), v(3.0, 2.0, 0.0)).unwrap();
    assert!(p.distance(v(3.0, 1.0, 1.0)) < 1e-12);
    // Random meeting segments in general position are found at the right point.
    let mut r = Lcg(7);
    for _ in 0..1000 {
        let x = v(r.range(-5.0, 5.0), r.range(-5.0, 5.0), r.range(-5.0, 5.0));
        let (du, dv) = (
            v(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0)),
            v(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0)),
        );
        if du.cross(dv).length() < 0.1 {
            continue;
        }
        let (p, _, _) = line_line(x - du, x + du, x - dv * 0.5, x + dv * 1.5).unwrap();
        assert!(p.distance(x) < 1e-9);
    }
}

#[test]
fn segment_plane_uses_the_corrected_formula() {
    let z1 = Plane {
        normal: DVec3::Z,
        dist: 1.0,
    };
    assert!(
        segment_plane(v(0.0, 0.0, 0.0), v(0.0, 0.0, 2.0), &z1)
            .unwrap()
            .distance(v(0.0, 0.0, 1.0))
            < 1e-12
    );
    assert!(segment_plane(v(0.0, 0.0, 2.0), v(0.0, 0.0, 3.0), &z1).is_none());
    assert!(segment_plane(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), &z1).is_none());
    let tilted = Plane::from_normal_point(v(1.0, 2.0, 3.0), v(0.2, -0.1, 0.4)).unwrap();
    let hit = segment_plane(v(-3.0, -2.0, -1.0), v(2.0, 3.0, 4.0), &tilted).unwrap();
    assert!(tilted.distance(hit).abs() < 1e-12);
}

#[test]
fn side_and_distance_of_points() {
    let p = Plane::from_normal_point(v(0.0, 0.0, 2.0), v(0.0, 0.0, 1.0)).unwrap();
    assert_eq!(p.distance(v(3.0, 4.0, 3.0)), 2.0);
    assert_eq!(p.distance(v(3.0, 4.0, -1.0)), -2.0);
    assert_eq!(p.side_of_point(v(1.0, 1.0, 1.0 + 5e-6)), crate::world::Side::On);
    assert_eq!(p.side_of_point(v(1.0, 1.0, 1.0 + 2e-5)), crate::world::Side::Front);
}

#[test]
fn cone_containment_and_edge_angle() {
    let c = Cone {
        apex: DVec3::ZERO,
        axis: v(0.0, 0.0, -1.0),
        spread: 30f64.to_radians(),
    };
    assert!(c.contains(v(0.0, 0.0, -1.0)));
    assert!(!c.contains(v(1.0, 0.0, -1.0)));
    assert!((c.angle_to_edge(v(0.0, 0.0, -1.0)).unwrap() - 30f64.to_radians()).abs() < 1e-12);
    assert_eq!(c.angle_to_edge(v(0.0, 0.0, 1.0)), Err(BehindApex));
}

/// Inside, outside, on edges and vertices in all three dominant-axis orientations, and 10⁵
/// random points against an independent half-plane test (disagreement only within ε of an edge).
#[test]
fn point_in_convex_polygon_agrees_with_half_planes() {
    let mut r = Lcg(11);
    let frames = [
        (DVec3::X, DVec3::Y),
        (DVec3::Y, DVec3::Z),
        (DVec3::Z, DVec3::X),
        (v(1.0, 1.0, 0.3).normalize(), v(-0.2, 0.5, 1.0).normalize()),
    ];
    let mut disagreements_far = 0;
    for (fu, fv) in frames {
        let fv = (fv - fu * fu.dot(fv)).normalize();
        let n = fu.cross(fv);
        for shape in 0..2 {
            let corners: Vec<(f64, f64)> = if shape == 0 {
                vec![(0.0, 0.0), (1.0, 0.0), (0.3, 0.8)]
            } else {
                vec![(-1.0, -0.5), (1.0, -0.7), (1.2, 0.6), (-0.8, 0.9)]
            };
            let poly: Vec<DVec3> = corners.iter().map(|&(a, b)| fu * a + fv * b + n * 0.7).collect();
            let polygon = Polygon::from_vertices(poly.clone()).unwrap();
            assert!(point_in_convex_polygon(polygon.center(), &poly, n));
            assert!(!point_in_convex_polygon(polygon.center() + fu * 5.0, &poly, n));
            for _ in 0..12_500 {
                let p = fu * r.range(-1.5, 1.5) + fv * r.range(-1.5, 1.5) + n * 0.7;
                let ours = point_in_convex_polygon(p, &poly, n);
                let theirs = polygon.contains_point(p, 0.0);
                if ours != theirs && polygon.distance_to_boundary(p) > 1e-9 {
                    disagreements_far += 1;
                }
            }
        }
    }
    assert_eq!(disagreements_far, 0);
    // A vertex exactly on the positive axis (the half-open rule): a point level with a vertex,
    // left of the square, is inside once, not twice.
    let square = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(2.0, 2.0, 0.0), v(0.0, 2.0, 0.0)];
    let diamond = [v(1.0, 0.0, 0.0), v(2.0, 1.0, 0.0), v(1.0, 2.0, 0.0), v(0.0, 1.0, 0.0)];
    assert!(point_in_convex_polygon(v(0.5, 1.0, 0.0), &diamond, DVec3::Z));
    assert!(!point_in_convex_polygon(v(-0.5, 1.0, 0.0), &diamond, DVec3::Z));
    assert!(point_in_convex_polygon(v(1.0, 1.0, 0.0), &square, DVec3::Z));
}

#[test]
fn segmentation_conserves_area_winding_and_bounds_size() {
    let quad = Polygon::from_vertices(vec![
        v(0.0, 0.0, 0.0),
        v(3.0, 0.0, 0.0),
        v(3.5, 2.0, 1.0),
        v(0.2, 2.5, 1.25),
    ]);
    let quad = quad.unwrap_or_else(|| {
        Polygon::from_vertices(vec![
            v(0.0, 0.0, 0.0),
            v(3.0, 0.0, 0.0),
            v(3.0, 2.0, 0.0),
            v(0.0, 2.0, 0.0),
        ])
        .unwrap()
    });
    let pentagon = Polygon::from_vertices(
        (0..5)
            .map(|k| v((k as f64 * 1.2566).cos(), 0.0, -(k as f64 * 1.2566).sin()))
            .collect(),
    )
    .unwrap();
    let polygons = [quad, pentagon];
    for max_area in [10.0, 0.3, 0.01] {
        let s = Segments::build(polygons.iter(), max_area).unwrap();
        for (pi, p) in polygons.iter().enumerate() {
            let tris: Vec<usize> = (0..s.triangles.len())
                .filter(|&t| s.triangle_polygon[t] == pi as u32)
                .collect();
            let area: f64 = tris.iter().map(|&t| s.triangle_area(t)).sum();
            assert!(
                (area - p.area()).abs() <= 1e-12 * p.area().max(1.0),
                "area {area} vs {}",
                p.area()
            );
            for &t in &tris {
                assert!(s.triangle_area(t) <= max_area * (1.0 + 1e-12));
                let [a, b, c] = s.triangles[t].map(|i| s.positions[i as usize]);
                assert!((b - a).cross(c - a).dot(p.plane.normal) > 0.0, "winding flipped");
            }
        }
        // No duplicate vertices within a polygon: shared fan edges are welded.
        let mut seen = std::collections::HashSet::new();
        for (i, p) in s.positions.iter().enumerate() {
            assert!(seen.insert((s.vertex_polygon[i], p.x.to_bits(), p.y.to_bits(), p.z.to_bits())));
        }
    }
    // One round: the 1→4 split's new vertices are the edge midpoints.
    let tri = Polygon::from_vertices(vec![v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0)]).unwrap();
    let s = Segments::build([&tri], 1.0).unwrap();
    assert_eq!((s.triangles.len(), s.positions.len()), (4, 6));
    for m in [v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(1.0, 1.0, 0.0)] {
        assert!(s.positions.contains(&m));
    }
    assert!(Segments::build([&tri], 0.0).is_err());
    assert!(Segments::build([&tri], 1e-12).is_err());
}

#[test]
fn spot_ramp_is_linear_in_angle_between_the_cones() {
    let (full, null) = (20f64.to_radians(), 30f64.to_radians());
    for deg in [0.0, 10.0, 20.0] {
        assert_eq!(seed_spot_ramp(full, null, f64::to_radians(deg)), 1.0);
    }
    assert!((seed_spot_ramp(full, null, 25f64.to_radians()) - 0.5).abs() < 1e-12);
    assert_eq!(seed_spot_ramp(full, null, 30f64.to_radians()), 0.0);
    assert_eq!(seed_spot_ramp(full, null, 45f64.to_radians()), 0.0);
    let mut last = 1.0;
    for k in 0..=100 {
        let x = seed_spot_ramp(full, null, (20.0 + 0.1 * k as f64).to_radians());
        assert!(x <= last);
        last = x;
    }
    // The spot light through the model: the 25° point gets half the axis's light.
    let light = ManyLight {
        position: DVec3::ZERO,
        direction: v(0.0, 0.0, -1.0),
        intensity: DVec3::ONE,
        cone: Some((full, null)),
    };
    let model = LightModel::Seed { k: 1.0 };
    let at = |deg: f64| {
        let a = f64::to_radians(deg);
        let p = v(a.sin(), 0.0, -a.cos()) * 2.0;
        light.shade(&model, p, -p.normalize(), DVec3::ONE).x
    };
    assert!((at(25.0) / at(0.0) - 0.5).abs() < 1e-9);
}

#[test]
fn attenuation_cosine_and_back_faces() {
    let light = ManyLight {
        position: v(0.0, 0.0, 4.0),
        direction: v(0.0, 0.0, -1.0),
        intensity: v(2.0, 1.0, 0.5),
        cone: None,
    };
    let rho = v(0.5, 0.5, 0.5);
    let seed = LightModel::Seed { k: 3.0 };
    let near = light.shade(&seed, v(0.0, 0.0, 2.0), DVec3::Z, rho);
    let far = light.shade(&seed, v(0.0, 0.0, 0.0), DVec3::Z, rho);
    assert!(
        (near.x - 2.0 * far.x).abs() < 1e-12,
        "1/d: doubling d halves the modifier"
    );
    assert!((far.x - 3.0 * 0.5 * 2.0 / 4.0).abs() < 1e-12, "k·ρ·cos·I/d");
    assert_eq!(
        light.shade(&seed, v(0.0, 0.0, 0.0), -DVec3::Z, rho),
        DVec3::ZERO,
        "back faces are clamped to zero"
    );
    // Physical: ρ/π · I/d² · cos.
    let phys = light
        .shade(&LightModel::Physical, v(3.0, 0.0, 0.0), v(0.0, 0.0, 1.0), rho)
        .x;
    let (d2, cos) = (25.0, 4.0 / 5.0);
    assert!((phys - 0.5 / std::f64::consts::PI * 2.0 / d2 * cos).abs() < 1e-12);
    // OpenGL fixed function: 1/(kc + kl d + kq d²) and cos^e inside the cutoff.
    let gl = LightModel::OpenGl {
        kc: 1.0,
        kl: 0.5,
        kq: 0.25,
    };
    let g = light.shade(&gl, v(0.0, 0.0, 0.0), DVec3::Z, rho).x;
    assert!((g - 0.5 * 2.0 / (1.0 + 2.0 + 4.0)).abs() < 1e-12);
    let spot = ManyLight {
        cone: Some((20f64.to_radians(), 30f64.to_radians())),
        ..light
    };
    let e = opengl_spot_exponent(20f64.to_radians());
    assert!((20f64.to_radians().cos().powf(e) - 0.5).abs() < 1e-12);
    let a = 25f64.to_radians();
    let p = v(4.0 * a.tan(), 0.0, 0.0);
    let expected = a.cos().powf(e) * 0.5 * 2.0
        / (1.0 + 0.5 * p.distance(spot.position) + 0.25 * p.distance_squared(spot.position))
        * a.cos();
    assert!((spot.shade(&gl, p, DVec3::Z, rho).x - expected).abs() < 1e-12);
    // The physical spot is the forward method's smoothstep.
    assert!((physical_spot_falloff(0.5, 0.9, 0.7) - 0.5).abs() < 1e-12);
}

#[test]
fn occluders_block_only_between_the_ends() {
    let square = Polygon::from_vertices(vec![
        v(-0.5, -0.5, 1.0),
        v(0.5, -0.5, 1.0),
        v(0.5, 0.5, 1.0),
        v(-0.5, 0.5, 1.0),
    ])
    .unwrap();
    let floor = Polygon::from_vertices(vec![
        v(-5.0, -5.0, 0.0),
        v(5.0, -5.0, 0.0),
        v(5.0, 5.0, 0.0),
        v(-5.0, 5.0, 0.0),
    ])
    .unwrap();
    let o = Occluders::new([&square, &floor]);
    assert!(o.blocked(v(0.0, 0.0, 0.0), v(0.0, 0.0, 3.0)), "the square is between");
    assert!(
        !o.blocked(v(2.0, 0.0, 0.0), v(2.0, 0.0, 3.0)),
        "beside the square; the floor under the start does not count"
    );
    assert!(
        !o.blocked(v(0.0, 0.0, 2.0), v(0.0, 0.0, 3.0)),
        "the light and receiver both above"
    );
}

/// The shadow rays' clearance follows the scene: a 3 mm model's 10 µm gap under a floating
/// square still shadows the floor (a fixed 0.1 mm would step over it), and a wall 3 km from the
/// origin does not shadow its own points (0.1 mm is under one step of an f32 coordinate there,
/// and the ray started on the wall).
#[test]
fn occluders_keep_clear_by_the_scene_s_size_and_distance() {
    let quad = |c: DVec3, u: DVec3, w: DVec3| {
        Polygon::from_vertices(vec![c - u - w, c + u - w, c + u + w, c - u + w]).unwrap()
    };
    let mm = 1e-3;
    let floor = quad(v(0.0, 0.0, 0.0), v(1.5 * mm, 0.0, 0.0), v(0.0, 1.5 * mm, 0.0));
    let square = quad(v(0.0, 0.0, 0.01 * mm), v(0.5 * mm, 0.0, 0.0), v(0.0, 0.5 * mm, 0.0));
    let small = Occluders::new([&floor, &square]);
    assert!(
        small.blocked(v(0.0, 0.0, 0.0), v(0.0, 0.0, 3.0 * mm)),
        "the square 10 µm above the floor"
    );
    assert!(
        !small.blocked(v(1.0 * mm, 0.0, 0.0), v(1.0 * mm, 0.0, 3.0 * mm)),
        "beside it"
    );
    // A floor meeting a wall at 25 degrees 3 km out; receivers along their junction, on both
    // at once, each lit from in front of the wall.
    let (x, z) = (3000.3, 2000.7);
    let along = v(-(25f64.to_radians().sin()), 0.0, 25f64.to_radians().cos());
    let front = v(-along.z, 0.0, along.x);
    let wall = quad(v(x, 1.0, z), v(0.0, 1.0, 0.0), along);
    let ground = quad(v(x, 0.0, z), v(2.0, 0.0, 0.0), v(0.0, 0.0, 2.0));
    let far = Occluders::new([&wall, &ground]);
    let mut rng = Lcg(7);
    let mut shadowed = 0;
    for _ in 0..1000 {
        let p = v(x, 0.0, z) + along * rng.range(-0.9, 0.9);
        let light = p + front * rng.range(0.5, 5.0) + v(0.0, rng.range(0.5, 3.0), 0.0) + along * rng.range(-3.0, 3.0);
        shadowed += usize::from(far.blocked(p, light));
    }
    assert_eq!(
        shadowed, 0,
        "of 1,000 points where the wall meets the floor, lit from the room"
    );
}
