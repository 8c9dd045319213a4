//! Patches partly buried under a solid standing on their surface keep only their visible part
//! (`lightmap::buried`), judged against the solid's footprint computed from its box; a surface
//! hovering over them buries nothing.

use glam::DVec3;

use crate::lighting::lightmap::buried::{self, SAMPLES};
use crate::lighting::lightmap::patches::{Patch, Patches};
use crate::lighting::lightmap::solve::Occluders;
use crate::scene::Scene;

/// A 4 m floor quad (object 0) with `objects` (TOML) on it, all grey, under radiosity.
fn floor_with(objects: &str) -> Scene {
    let text = format!("{FLOOR}{objects}");
    Scene::from_str(&text, "buried.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// `sc`'s patches at `size` with their buried sub-samples left out, the patches as they were
/// before, and the occluders.
fn excluded(sc: &Scene, size: f64) -> (Patches, Vec<Patch>, Occluders) {
    let geo = crate::lighting::lightmap::geometry::scene_geometry(sc, "radiosity").unwrap();
    let mut p = Patches::build(&geo.triangles, size);
    let before = p.patches.clone();
    let occ = Occluders::new(&geo.triangles);
    buried::exclude(&mut p, &occ, None);
    (p, before, occ)
}

const FLOOR: &str = r#"
methods = ["radiosity"]
[camera]
position = [0, 3, 4]
target = [0, 0, 0]
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
"#;

/// A 1 × 0.5 × 1 m box standing on the floor over x ∈ [0.13, 1.13], z ∈ [-0.47, 0.53] (off the
/// patch grid, so patches straddle its sides), and a single quad hovering 0.8 m up.
const BLOCK_AND_SHELF: &str = r#"
[[objects]]
name = "block"
mesh = "box"
size = [1, 0.5, 1]
translate = [0.63, 0.25, 0.03]
material = "grey"
[[objects]]
name = "shelf"
mesh = "quad"
corner = [-1.37, 0.8, -1.41]
edge_u = [1, 0, 0]
edge_v = [0, 0, 1]
material = "grey"
"#;

fn under_block(x: DVec3) -> bool {
    (0.13..=1.13).contains(&x.x) && (-0.47..=0.53).contains(&x.z)
}

#[test]
fn a_block_standing_on_the_floor_buries_its_footprint_and_a_shelf_buries_nothing() {
    let sc = floor_with(BLOCK_AND_SHELF);
    let size = 0.2;
    let (p, before, occ) = excluded(&sc, size);
    let floor = p.charts.iter().position(|c| c.object == 0).unwrap();
    let c = p.charts[floor].clone();
    let flat = c.flat_triangles(&occ.triangles);
    let (mut whole, mut partial, mut open) = (0, 0, 0);
    for j in 0..c.height {
        for i in 0..c.width {
            let k = c.first + j * c.width + i;
            if !before[k].inside() {
                continue;
            }
            let samples = c.inside_samples(&flat, size, i, j, SAMPLES);
            let seen = samples.iter().filter(|&&x| !under_block(x)).count();
            let share = seen as f64 / samples.len() as f64;
            let (q, was) = (&p.patches[k], &before[k]);
            assert!(
                (q.area - was.area * share).abs() < 1e-12,
                "patch ({i}, {j}): area {} against {} of {}",
                q.area,
                share,
                was.area
            );
            if seen == 0 {
                whole += 1;
                assert!(!q.inside(), "a patch wholly under the block is a border patch");
            } else if seen < samples.len() {
                partial += 1;
                assert!(
                    !under_block(q.centre),
                    "patch ({i}, {j}): its centre moved out from under the block"
                );
            } else {
                open += 1;
                assert_eq!(q.centre, was.centre);
            }
        }
    }
    eprintln!("floor patches: {whole} under the block, {partial} straddling its sides, {open} open");
    // 1 m² at 0.2 m: 16 whole cells inside the footprint, 20 straddling its four sides.
    assert_eq!((whole, partial), (16, 20));
    // The shelf's underside and top, and the block's own faces, lose nothing.
    for (k, q) in p.patches.iter().enumerate().filter(|(_, q)| q.chart != floor) {
        let below = p.charts[q.chart].object;
        assert!(
            (q.area - before[k].area).abs() < 1e-12 || below == 1,
            "object {below}: patch {k} lost area"
        );
    }
}

/// A grey box called "wall" of `size` centred at `at`, as scene TOML.
fn wall(size: [f64; 3], at: [f64; 3]) -> String {
    format!(
        "\n[[objects]]\nname = \"wall\"\nmesh = \"box\"\nsize = {size:?}\ntranslate = {at:?}\nmaterial = \"grey\"\n"
    )
}

/// A 3 cm wall standing across a column of 0.2 m floor patches at x ∈ [0.255, 0.285]: it buries
/// the sub-sample column at x = 0.275 and parts the rest into one column on its −x side and two
/// on its +x side. Each such patch keeps the two columns (half its area, its centre on the +x
/// side), not all three visible ones (three quarters, light from both rooms in one texel).
#[test]
fn a_thin_wall_across_a_patch_keeps_the_larger_side() {
    let sc = floor_with(&wall([0.03, 1.0, 2.0], [0.27, 0.5, 0.1]));
    let size = 0.2;
    let (p, before, _) = excluded(&sc, size);
    let floor = p.charts.iter().position(|c| c.object == 0).unwrap();
    let c = p.charts[floor].clone();
    let mut crossed = 0;
    for j in 0..c.height {
        for i in 0..c.width {
            let k = c.first + j * c.width + i;
            let was = &before[k];
            // The patches of the column the wall crosses, along its length (z ∈ [-0.9, 1.1]).
            if !was.inside() || !(0.2..0.4).contains(&was.centre.x) || !(-0.8..1.0).contains(&was.centre.z) {
                continue;
            }
            crossed += 1;
            let q = &p.patches[k];
            assert!(
                (q.area - 0.5 * was.area).abs() < 1e-12,
                "patch ({i}, {j}): area {} of {}: both sides kept?",
                q.area,
                was.area
            );
            assert!(
                q.centre.x > 0.285,
                "patch ({i}, {j}): centre {} not on the +x side",
                q.centre
            );
        }
    }
    assert_eq!(crossed, 9, "floor patches along the wall");
}

/// A 4 cm wall whose top stops half a millimetre short of a ceiling, as generated rooms and real
/// assets model walls: its top face and the strip of ceiling over it lie in a slit that no room
/// sees, so every sub-sample of either is buried (`buried::SLIT`). Counted as seen, the top face
/// took the ceiling's light over one side and gave it, at a form factor near 1, to the ceiling
/// over the other. The ceiling a patch away keeps every sub-sample.
#[test]
fn a_wall_short_of_the_ceiling_buries_its_top_and_the_ceiling_over_it() {
    let sc = floor_with(
        &(r#"
[[objects]]
name = "ceiling"
mesh = "quad"
corner = [-2, 1, -2]
edge_u = [4, 0, 0]
edge_v = [0, 0, 4]
material = "grey"
"#
        .to_owned()
            + &wall([0.04, 0.9995, 2.0], [0.27, 0.49975, 0.1])),
    );
    let size = 0.2;
    let (p, _, _) = excluded(&sc, size);
    let chart = |object: usize, up: f64| {
        p.charts
            .iter()
            .position(|c| c.object == object && c.normal.y * up > 0.9)
            .unwrap()
    };
    let (ceiling, top) = (chart(1, -1.0), chart(2, 1.0));
    let seen_in = |ci: usize| {
        let c = &p.charts[ci];
        (0..c.width * c.height)
            .map(|n| (n % c.width, n / c.width, &p.patches[c.first + n]))
            .filter(|(_, _, q)| q.inside())
            .flat_map(|(i, j, q)| {
                (0..SAMPLES * SAMPLES)
                    .filter(move |b| q.samples & (1 << b) != 0)
                    .map(move |b| c.sub_sample(size, (i, j), (b % SAMPLES, b / SAMPLES)))
            })
            .collect::<Vec<DVec3>>()
    };
    let top_seen = seen_in(top).len();
    let ceiling_seen = seen_in(ceiling);
    let over_wall = ceiling_seen
        .iter()
        .filter(|x| (0.25..=0.29).contains(&x.x) && (-0.9..=1.1).contains(&x.z))
        .count();
    let a_patch_away = ceiling_seen
        .iter()
        .filter(|x| (0.4..=0.6).contains(&x.x) && (-0.9..=1.1).contains(&x.z))
        .count();
    eprintln!("seen sub-samples: wall top {top_seen}, ceiling over the wall {over_wall}, a patch away {a_patch_away}");
    assert_eq!(top_seen, 0, "the wall's top face in the slit counts as seen");
    assert_eq!(over_wall, 0, "the ceiling over the wall counts as seen");
    // 0.2 m of x (one sub-sample column every 5 cm: 4) by 2 m of z (40): 160.
    assert_eq!(a_patch_away, 160, "the ceiling a patch from the wall lost sub-samples");
}
