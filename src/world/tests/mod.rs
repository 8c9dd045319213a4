//! Geometry and single-room tests: polygon splitting, brushes, CSG, the box room.

mod casters;
mod world;

use glam::DVec3;

use super::brush::{csg_faces, Brush};
use super::level_gen::{LevelBuilder, Rng};
use super::polygon::{Aabb, Plane, Polygon, Split};
use super::{CompileError, World, PLANE_EPSILON};

/// A random convex polygon: a regular n-gon of random size in a random plane.
fn random_polygon(rng: &mut Rng) -> Polygon {
    let n = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)).normalize();
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let center = DVec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
    let (count, r) = (3 + rng.below(6), rng.range(0.5, 3.0));
    let verts = (0..count)
        .map(|i| {
            let a = i as f64 / count as f64 * std::f64::consts::TAU;
            center + (u * a.cos() + v * a.sin()) * r
        })
        .collect();
    Polygon::from_vertices(verts).expect("regular polygon is valid")
}

#[test]
fn split_preserves_area_and_keeps_each_piece_on_its_side() {
    let mut rng = Rng::new(1);
    let mut spanning = 0;
    for _ in 0..2000 {
        let poly = random_polygon(&mut rng);
        let normal = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let Some(plane) = Plane::from_normal_point(normal, poly.center() + DVec3::splat(rng.range(-1.0, 1.0))) else {
            continue;
        };
        let area = poly.area();
        match poly.clone().split(&plane) {
            Split::Spanning { front, back } => {
                spanning += 1;
                let (fa, ba) = (
                    front.as_ref().map_or(0.0, Polygon::area),
                    back.as_ref().map_or(0.0, Polygon::area),
                );
                // A dropped sliver is below MIN_POLYGON_AREA.
                assert!(
                    (fa + ba - area).abs() < 1e-9 * area.max(1.0) + 2e-6,
                    "{fa} + {ba} != {area}"
                );
                for v in front.iter().flat_map(|p| &p.vertices) {
                    assert!(plane.distance(*v) > -PLANE_EPSILON);
                }
                for v in back.iter().flat_map(|p| &p.vertices) {
                    assert!(plane.distance(*v) < PLANE_EPSILON);
                }
                // Both pieces keep the original plane and winding.
                for p in front.iter().chain(back.iter()) {
                    assert_eq!(p.plane, poly.plane);
                    assert!(
                        Polygon::from_vertices(p.vertices.clone())
                            .unwrap()
                            .plane
                            .normal
                            .dot(poly.plane.normal)
                            > 0.999
                    );
                }
            }
            Split::Front(p) => assert!(p.vertices.iter().all(|&v| plane.distance(v) > -PLANE_EPSILON)),
            Split::Back(p) => assert!(p.vertices.iter().all(|&v| plane.distance(v) < PLANE_EPSILON)),
            Split::On(..) => panic!("random planes are not coplanar"),
        }
    }
    assert!(spanning > 500, "the test must exercise real splits, got {spanning}");
}

#[test]
fn on_plane_vertices_go_to_both_pieces_and_coplanar_polygons_classify_on() {
    let square = Polygon::from_vertices(vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y]).unwrap();
    // The diagonal through (0,0) and (1,1): both corners lie on it.
    let diagonal = Plane::from_normal_point(DVec3::new(1.0, -1.0, 0.0), DVec3::ZERO).unwrap();
    let Split::Spanning {
        front: Some(f),
        back: Some(b),
    } = square.clone().split(&diagonal)
    else {
        panic!("must span")
    };
    assert_eq!((f.vertices.len(), b.vertices.len()), (3, 3));
    for corner in [DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)] {
        assert!(f.vertices.contains(&corner) && b.vertices.contains(&corner));
    }
    assert!((f.area() - 0.5).abs() < 1e-12 && (b.area() - 0.5).abs() < 1e-12);
    let z0 = Plane {
        normal: DVec3::Z,
        dist: 0.0,
    };
    assert!(matches!(square.clone().split(&z0), Split::On(_, true)));
    assert!(matches!(square.split(&z0.flipped()), Split::On(_, false)));
}

#[test]
fn degenerate_polygons_and_brushes_are_dropped_not_panicked_on() {
    assert!(
        Polygon::from_vertices(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0]).is_none(),
        "collinear"
    );
    assert!(
        Polygon::from_vertices(vec![DVec3::ZERO, DVec3::X * 1e-4, DVec3::Y * 1e-4]).is_none(),
        "below min area"
    );
    assert!(Polygon::from_vertices(vec![]).is_none());
    // A slab of zero thickness, a brush of two planes, and a valid cube.
    let flat = Brush::cuboid(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0), 0);
    let open = Brush {
        sides: Brush::cuboid(DVec3::ZERO, DVec3::ONE, 0).sides[..2].to_vec(),
    };
    let cube = Brush::cuboid(DVec3::splat(3.0), DVec3::splat(4.0), 0);
    let (faces, stats) = csg_faces(&[flat, open, cube]);
    assert_eq!(stats.degenerate_brushes, 2);
    assert_eq!(faces.len(), 6);
    // Compiling garbage reports an error instead of panicking.
    let world = World {
        brushes: vec![Brush::cuboid(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0), 0)],
        start: DVec3::splat(5.0),
    };
    assert_eq!(world.compile().unwrap_err(), CompileError::NoFaces);
}

#[test]
fn cuboid_brush_has_six_outward_faces_with_the_right_areas() {
    let b = Brush::cuboid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), 7);
    let polys: Vec<Polygon> = b.side_polygons().into_iter().flatten().collect();
    assert_eq!(polys.len(), 6);
    let mut areas: Vec<f64> = polys.iter().map(Polygon::area).collect();
    areas.sort_by(f64::total_cmp);
    for (a, e) in areas.iter().zip([2.0, 2.0, 3.0, 3.0, 6.0, 6.0]) {
        assert!((a - e).abs() < 1e-9);
    }
    let center = DVec3::new(0.5, 1.0, 1.5);
    assert!(
        polys.iter().all(|p| p.plane.distance(center) < 0.0),
        "normals point out"
    );
}

#[test]
fn csg_removes_touching_and_buried_faces_and_dedups_coplanar_ones() {
    // Two unit cubes side by side: the touching faces vanish, 10 remain, area 10.
    let a = Brush::cuboid(DVec3::ZERO, DVec3::ONE, 0);
    let b = Brush::cuboid(DVec3::X, DVec3::new(2.0, 1.0, 1.0), 1);
    let (faces, _) = csg_faces(&[a.clone(), b]);
    let area: f64 = faces.iter().map(|f| f.polygon.area()).sum();
    assert!((area - 10.0).abs() < 1e-9, "area {area}");
    assert!(faces.iter().all(|f| f.polygon.center().x != 1.0));
    // Overlapping cubes with a common top plane: the top is counted once (area 1.5 in z+).
    let c = Brush::cuboid(DVec3::new(0.5, 0.0, 0.0), DVec3::new(1.5, 1.0, 1.0), 2);
    let (faces, _) = csg_faces(&[a.clone(), c]);
    let top: f64 = faces
        .iter()
        .filter(|f| f.polygon.plane.normal.z > 0.5)
        .map(|f| f.polygon.area())
        .sum();
    assert!((top - 1.5).abs() < 1e-9, "top {top}");
    let total: f64 = faces.iter().map(|f| f.polygon.area()).sum();
    assert!(
        (total - (1.5 * 2.0 + 1.5 * 2.0 + 2.0)).abs() < 1e-9,
        "surface of the 1.5×1×1 union, got {total}"
    );
    // A cube buried in a bigger one leaves only the big one's faces.
    let big = Brush::cuboid(DVec3::splat(-1.0), DVec3::splat(2.0), 3);
    let (faces, _) = csg_faces(&[a, big]);
    assert_eq!(faces.len(), 6);
    assert!(faces.iter().all(|f| f.brush == 1));
}

/// A closed box room: interior [0,4]×[0,3]×[0,2.5].
pub(super) fn box_room() -> World {
    let mut b = LevelBuilder::new(0.25);
    b.hollow_box(
        Aabb {
            min: DVec3::ZERO,
            max: DVec3::new(4.0, 3.0, 2.5),
        },
        &[],
        [false; 6],
        2,
    );
    b.into_world(DVec3::new(2.0, 1.5, 1.0))
}

#[test]
fn single_box_room_compiles_to_one_empty_leaf_with_six_inward_faces() {
    let w = box_room().compile().unwrap();
    assert_eq!(w.faces.len(), 6);
    assert_eq!(w.empty_leaves().count(), 1);
    assert_eq!(
        w.leaves().len(),
        7,
        "one empty leaf plus one solid leaf behind each of the six node planes"
    );
    assert!(w.portals.is_empty());
    let center = DVec3::new(2.0, 1.5, 1.25);
    for f in &w.faces {
        assert!(f.polygon.plane.distance(center) > 0.0, "faces look into the room");
    }
    let total: f64 = w.faces.iter().map(|f| f.polygon.area()).sum();
    assert!((total - 2.0 * (4.0 * 3.0 + 4.0 * 2.5 + 3.0 * 2.5)).abs() < 1e-9);
    let room = w.leaf_of(center);
    assert_eq!(w.leaves()[room as usize].faces.len(), 6);
    assert_eq!(w.visible_leaves(room).collect::<Vec<_>>(), vec![room]);
    // The six slabs have 36 sides; CSG buries some where slabs overlap at the corners, the
    // flood fill drops all outside faces. What is left is exactly the six inner ones.
    assert_eq!(w.stats.csg.faces_out - w.stats.unreachable_faces_dropped, 6);
    assert!(w.stats.unreachable_faces_dropped >= 6);
    // Outside the room is solid; a point outside has an empty PVS.
    assert!(w.is_solid(w.leaf_of(DVec3::new(-3.0, 1.0, 1.0))));
    assert_eq!(w.visible_leaves(w.leaf_of(DVec3::new(-3.0, 1.0, 1.0))).count(), 0);
}

#[test]
fn leaks_and_starts_in_solid_are_reported() {
    let mut b = LevelBuilder::new(0.25);
    let mut open = [false; 6];
    open[0] = true; // no +x wall
    b.hollow_box(
        Aabb {
            min: DVec3::ZERO,
            max: DVec3::new(4.0, 3.0, 2.5),
        },
        &[],
        open,
        2,
    );
    let leaky = b.into_world(DVec3::new(2.0, 1.5, 1.0));
    assert!(matches!(leaky.compile(), Err(CompileError::Leak { .. })));
    let mut inside_wall = box_room();
    inside_wall.start = DVec3::new(-0.1, 1.5, 1.0);
    assert!(matches!(inside_wall.compile(), Err(CompileError::StartInSolid { .. })));
}

#[test]
fn flood_fill_drops_an_unreachable_sealed_box() {
    let room = box_room();
    let plain = room.compile().unwrap();
    let mut with_box = room.clone();
    let mut b = LevelBuilder::new(0.25);
    b.hollow_box(
        Aabb {
            min: DVec3::new(10.0, 0.0, 0.0),
            max: DVec3::new(12.0, 2.0, 2.0),
        },
        &[],
        [false; 6],
        5,
    );
    let sealed_faces = csg_faces(&b.brushes).0.len();
    with_box.brushes.extend(b.brushes);
    let w = with_box.compile().unwrap();
    assert_eq!(w.faces.len(), plain.faces.len(), "the sealed box contributes no face");
    assert!(w.faces.iter().all(|f| f.material != 5));
    assert_eq!(
        w.stats.unreachable_faces_dropped,
        plain.stats.unreachable_faces_dropped + sealed_faces
    );
    // Its inside is solid as far as the world is concerned.
    assert!(w.is_solid(w.leaf_of(DVec3::new(11.0, 1.0, 1.0))));
}

#[test]
fn queries_on_degenerate_input_answer_without_panicking() {
    let w = box_room().compile().unwrap();
    let inside = DVec3::new(2.0, 1.5, 1.0);
    let nan = DVec3::splat(f64::NAN);
    // NaN in, anything but a panic out.
    let _ = w.cast_ray(inside, nan, 10.0);
    let _ = w.cast_ray(nan, DVec3::X, 10.0);
    assert!(w.cast_ray(inside, DVec3::X, -1.0).is_none());
    assert!(w.cast_ray(inside, DVec3::X, f64::NAN).is_none());
    assert!(!w.occluded(inside, inside));
    let _ = w.occluded(inside, nan);
    // A ray with a zero direction stays where it is: in empty space, no hit.
    assert!(w.cast_ray(inside, DVec3::ZERO, 10.0).is_none());
    // Starting inside solid: a hit at t = 0 naming no face.
    let hit = w.cast_ray(DVec3::new(-0.1, 1.5, 1.0), DVec3::X, 10.0).unwrap();
    assert_eq!((hit.t, hit.face), (0.0, None));
    // A light inside a wall has no PVS and casts nothing under (b) and (c).
    let in_wall = DVec3::new(-0.1, 1.5, 1.0);
    assert!(w.casters_light_pvs(in_wall, 5.0).is_empty());
    assert!(w.casters_with_pscs(in_wall, 5.0).is_empty());
    assert!(
        w.back_facing(&[0, 999_999], inside).len() <= 1,
        "unknown ids are skipped"
    );
    assert!(!w.is_visible(0, 999_999) && w.visible_leaves(999_999).count() == 0);
    assert!(w.casters_light_pvs(inside, f64::NAN).is_empty());
}

/// Ridderhof 2002's numeric policy (§5.6.1): a point within 1e-4 of a plane is on it, and the cuts a
/// split makes land on the 1e-4 grid; the exact policy keeps both as they are.
#[test]
fn the_thesis_tolerance_thickens_planes_and_rounds_cuts_to_four_decimals() {
    use super::Tolerance;
    let floor = Plane {
        normal: DVec3::Y,
        dist: 0.0,
    };
    let near = DVec3::new(0.3, 5e-5, 0.2);
    assert_eq!(floor.side_of_point(near), super::Side::Front);
    assert_eq!(floor.side_of_point_in(near, &Tolerance::THESIS), super::Side::On);
    let on_grid = |v: DVec3| (0..3).all(|i| ((v[i] / 1e-4) - (v[i] / 1e-4).round()).abs() < 1e-6);
    // A slanted cut through a square: its crossings fall between grid points unless rounded.
    let square = Polygon::from_vertices(vec![
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, -1.0),
    ])
    .unwrap();
    let cut = Plane::from_normal_point(DVec3::new(1.0, 0.0, 0.37), DVec3::new(0.123457, 0.0, 0.0)).unwrap();
    for (tolerance, rounded) in [(Tolerance::EXACT, false), (Tolerance::THESIS, true)] {
        let Split::Spanning {
            front: Some(front),
            back: Some(back),
        } = square.clone().split_in(&cut, &tolerance)
        else {
            panic!("{tolerance:?}: the cut spans the square")
        };
        let all = front.vertices.iter().chain(&back.vertices);
        assert_eq!(
            all.clone().all(|&v| on_grid(v)),
            rounded,
            "{tolerance:?}: {front:?} {back:?}"
        );
        // Rounded or not, the pieces still cover the square (to the grid's slack along the cut).
        let slack = if rounded { 2.0 * 2.0 * 1e-4 } else { 1e-12 };
        assert!(
            (front.area() + back.area() - 4.0).abs() <= slack,
            "{tolerance:?}: {} + {}",
            front.area(),
            back.area()
        );
    }
}
