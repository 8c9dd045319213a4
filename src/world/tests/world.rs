//! Whole-world tests: portals and PVS on small levels, conservativeness by ray sampling, ray
//! casting against brute force, the Fig. 8(c) case and the caster-set sizes.

use glam::DVec3;

use super::super::compile::CompileOptions;
use super::super::level_gen::{generate_rooms, LevelBuilder, Opening, Rng, RoomsParams};
use super::super::polygon::Aabb;
use super::super::{CompiledWorld, LeafId, SplitHeuristic, World};

/// A uniformly random point of an empty leaf (rejection sampling in its bounds).
pub(super) fn point_in_leaf(w: &CompiledWorld, leaf: LeafId, rng: &mut Rng) -> Option<DVec3> {
    let b = w.leaves()[leaf as usize].bounds;
    (0..200).map(|_| rng.point_in(&b)).find(|&p| w.leaf_of(p) == leaf)
}

/// Rooms given as interiors, joined by x- or y-corridors between consecutive rooms: the
/// `(room a, room b, axis, offset across)` list. Door 1.6 × 2.2, walls 0.3.
fn rooms_with_corridors(rooms: &[Aabb], links: &[(usize, usize, usize, f64)]) -> World {
    let mut b = LevelBuilder::new(0.3);
    let mut openings = vec![Vec::new(); rooms.len()];
    for &(a, c, axis, across_center) in links {
        let across = 1 - axis;
        let mut interior = Aabb {
            min: DVec3::ZERO,
            max: DVec3::new(0.0, 0.0, 2.2),
        };
        interior.min[axis] = rooms[a].max[axis];
        interior.max[axis] = rooms[c].min[axis];
        interior.min[across] = across_center - 0.8;
        interior.max[across] = across_center + 0.8;
        let mut open = [false; 6];
        open[2 * axis] = true;
        open[2 * axis + 1] = true;
        b.hollow_box(interior, &[], open, 4);
        openings[a].push(Opening {
            face: 2 * axis,
            rect: interior,
        });
        openings[c].push(Opening {
            face: 2 * axis + 1,
            rect: interior,
        });
    }
    for (i, r) in rooms.iter().enumerate() {
        b.hollow_box(*r, &openings[i], [false; 6], 2);
    }
    b.into_world(rooms[0].center().with_z(1.0))
}

fn room(x: f64, y: f64) -> Aabb {
    Aabb {
        min: DVec3::new(x, y, 0.0),
        max: DVec3::new(x + 6.0, y + 6.0, 3.0),
    }
}

fn leaves_in(w: &CompiledWorld, b: &Aabb) -> Vec<LeafId> {
    w.empty_leaves()
        .filter(|&l| w.leaves()[l as usize].bounds.overlaps(&b.expanded(-0.01)))
        .collect()
}

fn assert_symmetric(w: &CompiledWorld) {
    for a in w.empty_leaves() {
        for b in w.visible_leaves(a) {
            assert!(w.is_visible(b, a), "PVS not symmetric: {a} sees {b}");
        }
    }
}

/// Shoots `samples` segments between random points of random empty leaves; every unobstructed
/// one must join leaves the PVS marks visible. Returns how many were unobstructed.
fn assert_conservative(w: &CompiledWorld, samples: usize, seed: u64) -> usize {
    let leaves: Vec<LeafId> = w.empty_leaves().collect();
    let mut rng = Rng::new(seed);
    let mut clear = 0;
    for _ in 0..samples {
        let (la, lb) = (leaves[rng.below(leaves.len())], leaves[rng.below(leaves.len())]);
        let (Some(a), Some(b)) = (point_in_leaf(w, la, &mut rng), point_in_leaf(w, lb, &mut rng)) else {
            continue;
        };
        if !w.occluded(a, b) {
            clear += 1;
            assert!(
                w.is_visible(la, lb),
                "leaf {la} sees leaf {lb} along {a} → {b}, but the PVS says no"
            );
        }
    }
    clear
}

/// Targets the pairs the PVS rules out: `samples` random segments between each such pair of
/// leaves must all be blocked. (Random leaf pairs alone rarely hit a narrow sightline.)
fn assert_invisible_pairs_are_occluded(w: &CompiledWorld, samples: usize, min_pairs: usize) {
    let leaves: Vec<LeafId> = w.empty_leaves().collect();
    let mut rng = Rng::new(17);
    let mut checked = 0;
    for &a in &leaves {
        for &b in leaves.iter().filter(|&&b| b > a && !w.is_visible(a, b)) {
            for _ in 0..samples {
                let (Some(p), Some(q)) = (point_in_leaf(w, a, &mut rng), point_in_leaf(w, b, &mut rng)) else {
                    break;
                };
                assert!(w.occluded(p, q), "PVS says {a} cannot see {b}, but {p} → {q} is clear");
            }
            checked += 1;
        }
    }
    assert!(checked >= min_pairs, "only {checked} invisible pairs");
}

#[test]
fn two_rooms_joined_by_a_doorway_see_each_other_through_exactly_tiled_portals() {
    let rooms = [room(0.0, 0.0), room(10.0, 0.0)];
    let w = rooms_with_corridors(&rooms, &[(0, 1, 0, 3.0)]).compile().unwrap();
    // Room, corridor, room: nothing inside them to split on, so three empty leaves and one
    // portal per door.
    assert_eq!(w.empty_leaves().count(), 3);
    assert_eq!(w.portals.len(), 2);
    // The portals in each door plane tile the door exactly: 1.6 × 2.2.
    for door_x in [6.0, 10.0] {
        let area: f64 = w
            .portals
            .iter()
            .filter(|p| p.polygon.plane.axis() == Some(0) && (p.polygon.center().x - door_x).abs() < 1e-9)
            .map(|p| p.polygon.area())
            .sum();
        assert!(
            (area - 1.6 * 2.2).abs() < 1e-9,
            "door at x = {door_x}: portal area {area}"
        );
    }
    for p in &w.portals {
        assert!(!w.is_solid(p.front) && !w.is_solid(p.back));
    }
    assert_symmetric(&w);
    let (a, b) = (
        w.leaf_of(DVec3::new(3.0, 3.0, 1.0)),
        w.leaf_of(DVec3::new(13.0, 3.0, 1.0)),
    );
    assert!(w.is_visible(a, b) && w.is_visible(b, a));
    // Every leaf of either room sees some leaf of the other.
    for (from, to) in [(&rooms[0], &rooms[1]), (&rooms[1], &rooms[0])] {
        let there = leaves_in(&w, to);
        for l in leaves_in(&w, from) {
            assert!(
                there.iter().any(|&t| w.is_visible(l, t)),
                "leaf {l} sees nothing of the other room"
            );
        }
    }
    assert!(assert_conservative(&w, 400, 7) > 100);
}

#[test]
fn l_shaped_rooms_a_does_not_see_c_and_sampling_finds_nothing_the_pvs_misses() {
    // A and B side by side along x, C above B along y: A → B → C turns a corner.
    let rooms = [room(0.0, 0.0), room(10.0, 0.0), room(10.0, 10.0)];
    let w = rooms_with_corridors(&rooms, &[(0, 1, 0, 3.0), (1, 2, 1, 13.0)])
        .compile()
        .unwrap();
    assert_symmetric(&w);
    let (in_a, in_b, in_c) = (
        leaves_in(&w, &rooms[0]),
        leaves_in(&w, &rooms[1]),
        leaves_in(&w, &rooms[2]),
    );
    assert!(!in_a.is_empty() && !in_c.is_empty());
    for &a in &in_a {
        for &c in &in_c {
            assert!(!w.is_visible(a, c), "room A leaf {a} must not see room C leaf {c}");
        }
    }
    assert!(in_b.iter().any(|&b| in_a.iter().any(|&a| w.is_visible(a, b))));
    assert!(in_b.iter().any(|&b| in_c.iter().any(|&c| w.is_visible(c, b))));
    assert!(assert_conservative(&w, 3000, 11) > 300);
}

#[test]
fn generated_level_is_sealed_connected_and_its_pvs_conservative_and_symmetric() {
    for seed in [1, 2, 3] {
        let world = generate_rooms(seed, &RoomsParams::default());
        let w = world.compile().unwrap();
        assert!(w.stats.unreachable_faces_dropped > 0);
        assert_eq!(w.stats.second_pass_faces_dropped, 0);
        assert_eq!(w.stats.degenerate_fragments, 0);
        // Every empty leaf is reachable through portals from the start (flood fill defined them).
        let start = w.leaf_of(world.start);
        assert!(!w.is_solid(start));
        assert_symmetric(&w);
        // Neighbours through a portal always see each other.
        for p in &w.portals {
            assert!(w.is_visible(p.front, p.back));
        }
        // The PVS must cull something on a multi-room level, or it is not doing its job.
        let empty = w.empty_leaves().count();
        assert!(
            w.stats.pvs.visible_pairs < empty * (empty - 1) * 3 / 4,
            "{:?}",
            w.stats.pvs
        );
        assert!(assert_conservative(&w, 3000, seed) > 200);
        if seed == 1 {
            assert_invisible_pairs_are_occluded(&w, 40, 500);
        }
        // Faces bound their leaves: just in front of the centre of a face is one of its leaves.
        for f in &w.faces {
            let probe = f.polygon.center() + f.polygon.plane.normal * 1e-3;
            assert!(
                f.leaves.contains(&w.leaf_of(probe)),
                "face at {} does not bound its leaf",
                f.polygon.center()
            );
        }
    }
}

#[test]
fn ray_casts_through_the_tree_equal_brute_force_over_all_faces() {
    for heuristic in [SplitHeuristic::default(), SplitHeuristic::FirstFace] {
        let options = CompileOptions {
            heuristic,
            compute_pvs: false,
        };
        let w = generate_rooms(5, &RoomsParams::default())
            .compile_with(options)
            .unwrap();
        let leaves: Vec<LeafId> = w.empty_leaves().collect();
        let mut rng = Rng::new(99);
        let mut hits = 0;
        for _ in 0..1500 {
            let leaf = leaves[rng.below(leaves.len())];
            let Some(origin) = point_in_leaf(&w, leaf, &mut rng) else {
                continue;
            };
            let dir = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            let max_t = rng.range(1.0, 60.0);
            let tree = w.cast_ray(origin, dir, max_t);
            let brute = w.cast_ray_brute_force(origin, dir, max_t);
            match (tree, brute) {
                (None, None) => {}
                (Some(t), Some(b)) => {
                    hits += 1;
                    assert!(
                        (t.t - b.t).abs() < 1e-9,
                        "t {} vs {} from {origin} along {dir}",
                        t.t,
                        b.t
                    );
                    if t.face != b.face {
                        // Only on a shared edge may two faces both be right.
                        let edge = w.faces[b.face.unwrap() as usize].polygon.distance_to_boundary(b.point);
                        assert!(edge < 1e-6, "face {:?} vs {:?} at {}", t.face, b.face, b.point);
                    }
                    assert!(w.occluded(origin, origin + dir * (b.t + 1e-3)));
                    assert!(!w.occluded(origin, origin + dir * (b.t - 1e-3)));
                }
                _ => panic!("tree {tree:?} vs brute force {brute:?} from {origin} along {dir}"),
            }
        }
        assert!(hits > 1000);
    }
}

#[test]
fn back_to_front_order_paints_farther_faces_first_along_every_ray() {
    let w = generate_rooms(2, &RoomsParams::default()).compile().unwrap();
    let mut rng = Rng::new(21);
    let leaves: Vec<LeafId> = w.empty_leaves().collect();
    for _ in 0..20 {
        let Some(eye) = point_in_leaf(&w, leaves[rng.below(leaves.len())], &mut rng) else {
            continue;
        };
        let order = w.faces_back_to_front(eye);
        let mut rank = vec![usize::MAX; w.faces.len()];
        for (i, &f) in order.iter().enumerate() {
            assert_eq!(rank[f as usize], usize::MAX, "face {f} listed twice");
            rank[f as usize] = i;
        }
        assert!(rank.iter().all(|&r| r != usize::MAX), "every face listed");
        // Painter's correctness: of all faces one ray from the eye passes (occluded or not),
        // the nearer ones come later.
        for _ in 0..50 {
            let dir = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            let mut hits: Vec<(f64, usize)> = (0..w.faces.len())
                .filter_map(|f| w.faces[f].polygon.intersect_ray(eye, dir, 0.0, 1e3).map(|t| (t, f)))
                .collect();
            hits.sort_by(|a, b| a.0.total_cmp(&b.0));
            for pair in hits.windows(2) {
                if pair[1].0 - pair[0].0 > 1e-6 {
                    assert!(
                        rank[pair[0].1] > rank[pair[1].1],
                        "nearer face {} painted before farther {}",
                        pair[0].1,
                        pair[1].1
                    );
                }
            }
        }
    }
}

fn oblique_transform() -> (glam::DQuat, DVec3) {
    (
        glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.31, -0.47, 0.83),
        DVec3::new(3.3, -7.1, 2.9),
    )
}

/// The L-shaped three-room level turned by an arbitrary rotation and moved: every plane is
/// oblique.
fn oblique_l_rooms() -> World {
    let rooms = [room(0.0, 0.0), room(10.0, 0.0), room(10.0, 10.0)];
    let mut world = rooms_with_corridors(&rooms, &[(0, 1, 0, 3.0), (1, 2, 1, 13.0)]);
    let (rotation, offset) = oblique_transform();
    for brush in &mut world.brushes {
        for side in &mut brush.sides {
            let n = rotation * side.plane.normal;
            side.plane = super::super::Plane {
                normal: n,
                dist: side.plane.dist + n.dot(offset),
            };
        }
    }
    world.start = rotation * world.start + offset;
    world
}

#[test]
fn oblique_level_compiles_sealed_with_exact_ray_casts_and_a_conservative_pvs() {
    let w = oblique_l_rooms().compile().unwrap();
    let axial = oblique_l_rooms();
    assert!(axial
        .brushes
        .iter()
        .flat_map(|b| &b.sides)
        .all(|s| s.plane.axis().is_none()));
    assert_eq!(w.stats.second_pass_faces_dropped, 0);
    assert_symmetric(&w);
    assert!(assert_conservative(&w, 2000, 5) > 200);
    assert_invisible_pairs_are_occluded(&w, 200, 1);
    // Still: A and C see B, not each other.
    let (rotation, offset) = oblique_transform();
    let at = |p: DVec3| w.leaf_of(rotation * p + offset);
    let (a, b, c) = (
        at(DVec3::new(3.0, 3.0, 1.0)),
        at(DVec3::new(13.0, 3.0, 1.0)),
        at(DVec3::new(13.0, 13.0, 1.0)),
    );
    assert!(w.is_visible(a, b) && w.is_visible(c, b) && !w.is_visible(a, c));
    let leaves: Vec<LeafId> = w.empty_leaves().collect();
    let mut rng = Rng::new(8);
    for _ in 0..500 {
        let Some(origin) = point_in_leaf(&w, leaves[rng.below(leaves.len())], &mut rng) else {
            continue;
        };
        let dir = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let (t, b) = (
            w.cast_ray(origin, dir, 100.0),
            w.cast_ray_brute_force(origin, dir, 100.0),
        );
        assert_eq!(
            t.map(|h| (h.t * 1e6).round()),
            b.map(|h| (h.t * 1e6).round()),
            "from {origin} along {dir}"
        );
    }
}

/// An entity's box that reaches through a short corridor from one room into the next, its
/// corners and centre all in the rooms: the corner-and-centre rule misses the corridor's leaf,
/// the descent of the tree finds it (and every leaf a point of the box lies in).
#[test]
fn a_box_through_a_corridor_reaches_the_corridor_leaf_though_no_corner_is_in_it() {
    // Rooms x 0–6 and 7–13 joined by a 1 m corridor through both walls (y 2.2–3.8, z 0–2.2).
    let w = rooms_with_corridors(&[room(0.0, 0.0), room(7.0, 0.0)], &[(0, 1, 0, 3.0)])
        .compile()
        .unwrap();
    let corridor = w.leaf_of(DVec3::new(6.5, 3.0, 1.0));
    let b = Aabb {
        min: DVec3::new(4.0, 2.5, 0.5),
        max: DVec3::new(7.5, 3.5, 1.5),
    };
    let mut old_rule: Vec<LeafId> = (0..9)
        .map(|i| {
            if i == 8 {
                b.center()
            } else {
                DVec3::new(
                    if i & 1 == 0 { b.min.x } else { b.max.x },
                    if i & 2 == 0 { b.min.y } else { b.max.y },
                    if i & 4 == 0 { b.min.z } else { b.max.z },
                )
            }
        })
        .map(|p| w.leaf_of(p))
        .collect();
    old_rule.sort_unstable();
    old_rule.dedup();
    assert!(
        !w.is_solid(corridor) && !old_rule.contains(&corridor),
        "the corner-and-centre rule gets {old_rule:?}, corridor leaf {corridor}"
    );
    let reached = w.box_leaves(&b);
    assert!(
        reached.contains(&corridor),
        "{reached:?} lacks the corridor leaf {corridor}"
    );
    assert!(
        old_rule.iter().all(|l| reached.contains(l)),
        "{reached:?} ⊉ {old_rule:?}"
    );
    // Conservative: every empty leaf holding a point of the box is reached.
    let mut rng = Rng::new(3);
    for _ in 0..2000 {
        let l = w.leaf_of(rng.point_in(&b));
        assert!(
            w.is_solid(l) || reached.contains(&l),
            "leaf {l} holds a point of the box but is not in {reached:?}"
        );
    }
    // A box inside one room reaches that room's leaf alone.
    let inside = Aabb {
        min: DVec3::new(1.0, 1.0, 0.5),
        max: DVec3::new(2.0, 2.0, 1.5),
    };
    assert_eq!(w.box_leaves(&inside), vec![w.leaf_of(inside.center())]);
}
