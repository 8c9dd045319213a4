//! Generated test worlds: rooms on a grid joined by corridors through door openings, with
//! pillars ([`generate_rooms`]), and the seed's Fig. 8(c) configuration ([`fig8c_case`]).
//! Everything is axis-aligned brushes and deterministic from the seed.

use glam::DVec3;

use super::polygon::Aabb;
use super::{Brush, MaterialId, World};

/// Materials the generators assign.
pub mod materials {
    use super::MaterialId;
    pub const FLOOR: MaterialId = 0;
    pub const CEILING: MaterialId = 1;
    pub const WALL: MaterialId = 2;
    pub const PILLAR: MaterialId = 3;
    pub const CORRIDOR: MaterialId = 4;
}

/// SplitMix64: a tiny deterministic generator, so levels and tests need no `rand`.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    pub fn point_in(&mut self, b: &Aabb) -> DVec3 {
        DVec3::new(
            self.range(b.min.x, b.max.x),
            self.range(b.min.y, b.max.y),
            self.range(b.min.z, b.max.z),
        )
    }
}

/// A hole cut into one face of a hollow box: `face` as in [`Aabb::planes`] (0 = +x, 1 = −x,
/// 2 = +y, 3 = −y, 4 = +z, 5 = −z); `rect` gives the hole's extent along the two other axes.
#[derive(Clone, Copy, Debug)]
pub struct Opening {
    pub face: usize,
    pub rect: Aabb,
}

/// Collects brushes for boxes of empty space with walls around them.
#[derive(Clone, Debug)]
pub struct LevelBuilder {
    pub brushes: Vec<Brush>,
    pub wall_thickness: f64,
}

impl LevelBuilder {
    pub fn new(wall_thickness: f64) -> LevelBuilder {
        LevelBuilder {
            brushes: Vec::new(),
            wall_thickness,
        }
    }

    /// Walls, floor and ceiling around the empty box `interior`, each a slab of the wall
    /// thickness. Faces marked in `open` get no slab (a corridor's ends); slabs reach over the
    /// corners only towards closed faces, so nothing pokes into what an open end joins. Each
    /// opening is cut out of its slab, which becomes up to four brushes around the hole.
    pub fn hollow_box(&mut self, interior: Aabb, openings: &[Opening], open: [bool; 6], wall: MaterialId) {
        let t = self.wall_thickness;
        for face in 0..6 {
            if open[face] {
                continue;
            }
            let axis = face / 2;
            let (mut min, mut max) = (interior.min, interior.max);
            if face % 2 == 0 {
                min[axis] = interior.max[axis];
                max[axis] = interior.max[axis] + t;
            } else {
                min[axis] = interior.min[axis] - t;
                max[axis] = interior.min[axis];
            }
            for other in (0..3).filter(|&a| a != axis) {
                if !open[2 * other + 1] {
                    min[other] -= t;
                }
                if !open[2 * other] {
                    max[other] += t;
                }
            }
            let material = match face {
                4 => super::level_gen::materials::CEILING,
                5 => super::level_gen::materials::FLOOR,
                _ => wall,
            };
            let mut pieces = vec![Aabb { min, max }];
            for hole in openings.iter().filter(|o| o.face == face) {
                pieces = pieces
                    .into_iter()
                    .flat_map(|p| box_minus_hole(p, &hole.rect, axis))
                    .collect();
            }
            self.brushes
                .extend(pieces.into_iter().map(|b| Brush::cuboid(b.min, b.max, material)));
        }
    }

    pub fn solid_box(&mut self, min: DVec3, max: DVec3, material: MaterialId) {
        self.brushes.push(Brush::cuboid(min, max, material));
    }

    pub fn into_world(self, start: DVec3) -> World {
        World {
            brushes: self.brushes,
            start,
        }
    }
}

/// `slab` minus the hole's extent across the two axes other than `axis` (the hole goes all the
/// way through the slab): up to four boxes, left, right, below, above.
fn box_minus_hole(slab: Aabb, hole: &Aabb, axis: usize) -> Vec<Aabb> {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let (u0, u1) = (hole.min[u].max(slab.min[u]), hole.max[u].min(slab.max[u]));
    let (v0, v1) = (hole.min[v].max(slab.min[v]), hole.max[v].min(slab.max[v]));
    if u0 >= u1 || v0 >= v1 {
        return vec![slab];
    }
    let mut out = Vec::new();
    let mut push = |umin: f64, umax: f64, vmin: f64, vmax: f64| {
        if umax > umin && vmax > vmin {
            let (mut min, mut max) = (slab.min, slab.max);
            (min[u], max[u], min[v], max[v]) = (umin, umax, vmin, vmax);
            out.push(Aabb { min, max });
        }
    };
    push(slab.min[u], u0, slab.min[v], slab.max[v]);
    push(u1, slab.max[u], slab.min[v], slab.max[v]);
    push(u0, u1, slab.min[v], v0);
    push(u0, u1, v1, slab.max[v]);
    out
}

/// Parameters of [`generate_rooms`]. Lengths in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomsParams {
    /// Rooms on a `columns × rows` grid, one per cell (at least 4 in all).
    pub columns: usize,
    pub rows: usize,
    pub cell_size: f64,
    /// Half-extent of a room's floor, drawn per axis from this range.
    pub room_half_size: (f64, f64),
    pub room_height: (f64, f64),
    pub wall_thickness: f64,
    pub door_width: f64,
    pub door_height: f64,
    /// Pillars per room, drawn from this inclusive range.
    pub pillars: (usize, usize),
    /// Chance that a grid neighbour pair not on the spanning tree still gets a corridor.
    pub extra_corridor_chance: f64,
}

impl Default for RoomsParams {
    fn default() -> Self {
        RoomsParams {
            columns: 3,
            rows: 2,
            cell_size: 14.0,
            room_half_size: (3.0, 5.0),
            room_height: (3.0, 4.0),
            wall_thickness: 0.3,
            door_width: 1.6,
            door_height: 2.2,
            pillars: (1, 3),
            extra_corridor_chance: 0.3,
        }
    }
}

/// Rooms on a grid, every room reachable through corridors (a random spanning tree plus some
/// extra links, so there are loops), doors where corridors meet rooms, and floor-to-ceiling
/// pillars kept clear of the doors and of the room centre. The start point is the centre of
/// room 0 at eye height. Deterministic in `seed`.
pub fn generate_rooms(seed: u64, params: &RoomsParams) -> World {
    // One generator through every step, in this order: the same seed gives the same world.
    let mut rng = Rng::new(seed);
    let (cols, rows) = (params.columns.max(1), params.rows.max(1));
    let rooms = place_rooms(&mut rng, params, cols, rows);
    let corridors = link_rooms(&mut rng, cols, rows, params.extra_corridor_chance);
    let mut builder = LevelBuilder::new(params.wall_thickness);
    let openings = build_corridors(&mut builder, &mut rng, &rooms, &corridors, params);
    for (room, openings) in rooms.iter().zip(&openings) {
        builder.hollow_box(*room, openings, [false; 6], materials::WALL);
        place_pillars(&mut builder, &mut rng, room, openings, params.pillars);
    }
    builder.into_world(rooms[0].center() + DVec3::Z * 1.0)
}

/// One room per grid cell, row by row: a box of random half-size and height around the cell's
/// centre, standing on z = 0.
fn place_rooms(rng: &mut Rng, params: &RoomsParams, cols: usize, rows: usize) -> Vec<Aabb> {
    (0..cols * rows)
        .map(|i| {
            let (cx, cy) = (i % cols, i / cols);
            let center = DVec3::new(
                (cx as f64 + 0.5) * params.cell_size,
                (cy as f64 + 0.5) * params.cell_size,
                0.0,
            );
            let half = DVec3::new(
                rng.range(params.room_half_size.0, params.room_half_size.1),
                rng.range(params.room_half_size.0, params.room_half_size.1),
                0.0,
            );
            let height = rng.range(params.room_height.0, params.room_height.1);
            Aabb {
                min: center - half,
                max: center + half + DVec3::Z * height,
            }
        })
        .collect()
}

/// The corridors between grid neighbours (a, b), b the +x or +y neighbour: a randomised
/// spanning tree (union–find over shuffled edges), plus each other link at `extra_chance`.
fn link_rooms(rng: &mut Rng, cols: usize, rows: usize, extra_chance: f64) -> Vec<(usize, usize)> {
    let mut links: Vec<(usize, usize)> = Vec::new();
    for i in 0..cols * rows {
        let (cx, cy) = (i % cols, i / cols);
        if cx + 1 < cols {
            links.push((i, i + 1));
        }
        if cy + 1 < rows {
            links.push((i, i + cols));
        }
    }
    for i in (1..links.len()).rev() {
        links.swap(i, rng.below(i + 1));
    }
    let mut parent: Vec<usize> = (0..cols * rows).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut corridors = Vec::new();
    for (a, b) in links {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra] = rb;
            corridors.push((a, b));
        } else if rng.unit() < extra_chance {
            corridors.push((a, b));
        }
    }
    corridors
}

/// Builds each corridor, a door-sized tube between its rooms' facing walls at a random offset,
/// and returns per room the openings its walls need.
fn build_corridors(
    builder: &mut LevelBuilder,
    rng: &mut Rng,
    rooms: &[Aabb],
    corridors: &[(usize, usize)],
    params: &RoomsParams,
) -> Vec<Vec<Opening>> {
    let mut openings: Vec<Vec<Opening>> = vec![Vec::new(); rooms.len()];
    let half_door = params.door_width * 0.5;
    for &(a, b) in corridors {
        // b is the +x or +y neighbour of a.
        let axis = if b == a + 1 { 0 } else { 1 };
        let across = 1 - axis;
        let center = (rooms[a].center()[across] + rooms[b].center()[across]) * 0.5 + rng.range(-1.0, 1.0);
        let mut interior = Aabb {
            min: DVec3::ZERO,
            max: DVec3::new(0.0, 0.0, params.door_height),
        };
        interior.min[axis] = rooms[a].max[axis];
        interior.max[axis] = rooms[b].min[axis];
        interior.min[across] = center - half_door;
        interior.max[across] = center + half_door;
        let mut open = [false; 6];
        open[2 * axis] = true;
        open[2 * axis + 1] = true;
        builder.hollow_box(interior, &[], open, materials::CORRIDOR);
        openings[a].push(Opening {
            face: 2 * axis,
            rect: interior,
        });
        openings[b].push(Opening {
            face: 2 * axis + 1,
            rect: interior,
        });
    }
    openings
}

/// Floor-to-ceiling pillars in `room`, between `pillars.0` and `pillars.1` of them, each at
/// the first of 20 random spots clear of the room centre (the start point), of the 2 m in
/// front of each door and of the pillars before it.
fn place_pillars(
    builder: &mut LevelBuilder,
    rng: &mut Rng,
    room: &Aabb,
    openings: &[Opening],
    pillars: (usize, usize),
) {
    let mut clear: Vec<Aabb> = vec![Aabb {
        min: room.center() - DVec3::splat(1.2),
        max: room.center() + DVec3::splat(1.2),
    }];
    for o in openings {
        let mut zone = o.rect.expanded(0.6);
        let axis = o.face / 2;
        if o.face % 2 == 0 {
            zone.min[axis] = room.max[axis] - 2.0;
        } else {
            zone.max[axis] = room.min[axis] + 2.0;
        }
        clear.push(zone);
    }
    let count = pillars.0 + rng.below(pillars.1.saturating_sub(pillars.0) + 1);
    for _ in 0..count {
        for _attempt in 0..20 {
            let half = rng.range(0.2, 0.4);
            let x = rng.range(room.min.x + 1.0 + half, room.max.x - 1.0 - half);
            let y = rng.range(room.min.y + 1.0 + half, room.max.y - 1.0 - half);
            let foot = Aabb {
                min: DVec3::new(x - half, y - half, room.min.z),
                max: DVec3::new(x + half, y + half, room.max.z),
            };
            let blocked = |z: &Aabb| {
                foot.expanded(0.3).overlaps(&Aabb {
                    min: z.min.with_z(room.min.z),
                    max: z.max.with_z(room.max.z),
                })
            };
            if clear.iter().any(blocked) {
                continue;
            }
            builder.solid_box(foot.min, foot.max, materials::PILLAR);
            clear.push(foot.expanded(0.5));
            break;
        }
    }
}

/// The seed's Fig. 8(c) situation, built so that this compiler's BSP produces it: a room with
/// a floor-to-ceiling centre pillar and the light in the slab in front of it. Floor, ceiling and
/// walls are cut along the pillar's four planes, so those planes split nothing and the tree
/// cuts the room into the 3 × 3 columns they make. The leaf E behind the pillar then lies in
/// the pillar's shadow from every point of the light's leaf D (a segment from D to E stays in
/// the pillar's slab and crosses the pillar), so E is not in PVS(D); yet rays from the light
/// leaving through the pillar's back face (whose only leaf is E) diverge out of the slab and
/// reach the back wall in leaves that D sees. Without the PSCS that shadow is missing.
#[derive(Clone, Debug)]
pub struct Fig8Case {
    pub world: World,
    pub light: DVec3,
    /// The centre of the pillar's back face: the caster that (b) misses.
    pub caster_point: DVec3,
    /// A point on the back wall, in a leaf the light's leaf sees, shadowed by that face only.
    pub receiver_point: DVec3,
}

pub fn fig8c_case() -> Fig8Case {
    let (t, h) = (0.3, 3.0);
    let xs = [0.0, 5.0, 7.0, 12.0];
    let ys = [0.0, 4.0, 6.0, 10.0];
    let mut b = LevelBuilder::new(t);
    for i in 0..3 {
        for j in 0..3 {
            let (x0, x1, y0, y1) = (xs[i], xs[i + 1], ys[j], ys[j + 1]);
            b.solid_box(DVec3::new(x0, y0, -t), DVec3::new(x1, y1, 0.0), materials::FLOOR);
            b.solid_box(DVec3::new(x0, y0, h), DVec3::new(x1, y1, h + t), materials::CEILING);
        }
    }
    for i in 0..3 {
        let (x0, x1) = (xs[i], xs[i + 1]);
        b.solid_box(DVec3::new(x0, -t, -t), DVec3::new(x1, 0.0, h + t), materials::WALL);
        b.solid_box(
            DVec3::new(x0, 10.0, -t),
            DVec3::new(x1, 10.0 + t, h + t),
            materials::WALL,
        );
        let (y0, y1) = (ys[i], ys[i + 1]);
        b.solid_box(DVec3::new(-t, y0, -t), DVec3::new(0.0, y1, h + t), materials::WALL);
        b.solid_box(
            DVec3::new(12.0, y0, -t),
            DVec3::new(12.0 + t, y1, h + t),
            materials::WALL,
        );
    }
    // Corner posts close the four vertical corner gaps between the wall runs.
    for (x, y) in [(-t, -t), (12.0, -t), (-t, 10.0), (12.0, 10.0)] {
        b.solid_box(DVec3::new(x, y, -t), DVec3::new(x + t, y + t, h + t), materials::WALL);
    }
    b.solid_box(DVec3::new(5.0, 4.0, 0.0), DVec3::new(7.0, 6.0, h), materials::PILLAR);
    let light = DVec3::new(6.0, 2.0, 1.5);
    // Through the back face near its −x edge, onward to the back wall left of the slab.
    let through = DVec3::new(5.05, 6.0, 1.5);
    let receiver_point = light + (through - light) * ((10.0 - light.y) / (through.y - light.y));
    Fig8Case {
        world: b.into_world(DVec3::new(2.0, 2.0, 1.5)),
        light,
        caster_point: DVec3::new(6.0, 6.0, 1.5),
        receiver_point,
    }
}
