//! Procedural meshes. All are counter-clockwise seen from the side their normals point to, have
//! unit normals, uvs in [0, 1] (v down) and tangents.
//!
//! Closed generators (box, sphere) produce bit-identical positions wherever two faces meet, so
//! [`Mesh::is_closed_manifold`] (which welds by exact position) sees them as closed.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::mesh::Mesh;
use super::types::Light;

/// Largest accepted `subdivisions` of planes, quads and boxes (larger values are clamped).
pub const MAX_SUBDIVISIONS: u32 = 512;
/// Largest accepted sphere `segments` (larger values are clamped).
pub const MAX_SEGMENTS: u32 = 2048;
/// Largest accepted sphere `rings` (larger values are clamped).
pub const MAX_RINGS: u32 = 1024;

/// Appends a `(nu+1) × (nv+1)`-vertex grid: `pos(i, j)` for i along the face's "right", j along
/// its "up" (right × up = normal, so the triangles are counter-clockwise seen from the normal).
/// uv = (i/nu, 1 − j/nv): the image's top row lies at j = nv.
fn push_grid(mesh: &mut Mesh, nu: u32, nv: u32, normal: Vec3, pos: impl Fn(u32, u32) -> Vec3) {
    let base = mesh.positions.len() as u32;
    for j in 0..=nv {
        for i in 0..=nu {
            mesh.positions.push(pos(i, j));
            mesh.normals.push(normal);
            mesh.uvs
                .push(Vec2::new(i as f32 / nu as f32, 1.0 - j as f32 / nv as f32));
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let a = base + j * row + i;
            let (b, c, d) = (a + 1, a + row + 1, a + row);
            mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
}

/// `lo + (hi − lo)·k/n`, computed so that k = 0 and k = n give exactly `lo` and `hi`.
fn lerp_exact(lo: f32, hi: f32, k: u32, n: u32) -> f32 {
    if k == 0 {
        lo
    } else if k >= n {
        hi
    } else {
        lo + (hi - lo) * (k as f32 / n as f32)
    }
}

/// Square grid in the xz-plane (y = 0) facing +y, centred on the origin: x ∈ ±size.x/2,
/// z ∈ ±size.y/2, `subdivisions` (1 to [`MAX_SUBDIVISIONS`]) cells per side. u grows with x, v with z.
pub fn plane(size: Vec2, subdivisions: u32) -> Mesh {
    let n = subdivisions.clamp(1, MAX_SUBDIVISIONS);
    let h = size * 0.5;
    let mut m = Mesh::default();
    // right = +x, up = −z: (+x) × (−z) = +y.
    push_grid(&mut m, n, n, Vec3::Y, |i, j| {
        Vec3::new(lerp_exact(-h.x, h.x, i, n), 0.0, lerp_exact(h.y, -h.y, j, n))
    });
    m.compute_tangents();
    m
}

/// Parallelogram `corner + s·edge_u + t·edge_v` facing `normalize(edge_u × edge_v)`;
/// uv = (s, 1 − t). A degenerate (zero-area) quad gets normal +y.
pub fn quad(corner: Vec3, edge_u: Vec3, edge_v: Vec3, subdivisions: u32) -> Mesh {
    let n = subdivisions.clamp(1, MAX_SUBDIVISIONS);
    let normal = edge_u.cross(edge_v).try_normalize().unwrap_or(Vec3::Y);
    let mut m = Mesh::default();
    push_grid(&mut m, n, n, normal, |i, j| {
        corner + edge_u * (i as f32 / n as f32) + edge_v * (j as f32 / n as f32)
    });
    m.compute_tangents();
    m
}

/// Axis-aligned box centred on the origin, 6 separately-textured faces (uvs cover 0..1 on each,
/// upright for the side faces), each split into `subdivisions²` cells. Closed 2-manifold.
pub fn cuboid(size: Vec3, subdivisions: u32) -> Mesh {
    let n = subdivisions.clamp(1, MAX_SUBDIVISIONS);
    let h = (size * 0.5).to_array();
    // (normal axis, normal sign, right axis, right sign, up axis, up sign), right × up = normal.
    const FACES: [(usize, f32, usize, f32, usize, f32); 6] = [
        (0, 1.0, 2, -1.0, 1, 1.0),  // +x
        (0, -1.0, 2, 1.0, 1, 1.0),  // −x
        (1, 1.0, 0, 1.0, 2, -1.0),  // +y
        (1, -1.0, 0, 1.0, 2, 1.0),  // −y
        (2, 1.0, 0, 1.0, 1, 1.0),   // +z
        (2, -1.0, 0, -1.0, 1, 1.0), // −z
    ];
    let mut m = Mesh::default();
    for (na, ns, ra, rs, ua, us) in FACES {
        let mut normal = [0.0f32; 3];
        normal[na] = ns;
        // Every face computes a coordinate from the same integer lattice index along that axis,
        // so shared edges get bit-identical positions.
        let coord = |axis: usize, k: u32| lerp_exact(-h[axis], h[axis], k, n);
        push_grid(&mut m, n, n, Vec3::from(normal), |i, j| {
            let mut lattice = [0u32; 3];
            lattice[na] = if ns > 0.0 { n } else { 0 };
            lattice[ra] = if rs > 0.0 { i } else { n - i };
            lattice[ua] = if us > 0.0 { j } else { n - j };
            Vec3::new(coord(0, lattice[0]), coord(1, lattice[1]), coord(2, lattice[2]))
        });
    }
    m.compute_tangents();
    m
}

/// UV sphere centred on the origin: `segments` (≥ 3) slices around +y, `rings` (≥ 2) stacks from
/// the north pole (+y, v = 0) to the south pole (v = 1); u grows eastward, starting (u = 0) at
/// +x and reaching −z at u = 0.25. The seam column and the pole vertices are duplicated for uvs
/// but share exact positions, so the sphere is a closed 2-manifold. No degenerate triangles.
pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let (segs, rings) = (segments.clamp(3, MAX_SEGMENTS), rings.clamp(2, MAX_RINGS));
    let mut m = Mesh::default();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segs {
            // The seam column reuses column 0's angle so its positions are identical.
            let phi = TAU * (s % segs) as f32 / segs as f32;
            let n = if r == 0 {
                Vec3::Y
            } else if r == rings {
                Vec3::NEG_Y
            } else {
                Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
            };
            m.positions.push(n * radius);
            m.normals.push(n);
            m.uvs.push(Vec2::new(s as f32 / segs as f32, r as f32 / rings as f32));
        }
    }
    let row = segs + 1;
    for r in 0..rings {
        for s in 0..segs {
            let a = r * row + s; // (r, s), top-left seen from outside
            let (b, c, d) = (a + row, a + row + 1, a + 1); // below, below-right, right
            if r != rings - 1 {
                m.indices.extend_from_slice(&[a, b, c]);
            }
            if r != 0 {
                m.indices.extend_from_slice(&[a, c, d]);
            }
        }
    }
    m.compute_tangents();
    m
}

/// Largest accepted bush `leaves` (larger values are clamped).
pub const MAX_LEAVES: u32 = 100_000;
/// Triangles of a bush's wood (trunk and branches), whatever its keys: seven tapered hexagonal
/// prisms with capped tips.
pub const BUSH_WOOD_TRIANGLES: usize = BUSH_PRISMS * (2 * PRISM_SIDES + PRISM_SIDES - 2);
/// Vertices and triangles of one leaf.
pub const LEAF_VERTICES: usize = 5;
pub const LEAF_TRIANGLES: usize = 4;
/// The crown's vertical semi-axis as a fraction of its horizontal radius.
pub const CROWN_FLATTENING: f32 = 0.75;
/// The trunk and the branches.
const BUSH_PRISMS: usize = 7;
const PRISM_SIDES: usize = 6;
/// Where the wood's uvs lie in the leaf texture: a bark patch in its lower-left corner, away
/// from the leaf's outline (`tools/make_leaf_textures.py` paints it).
const BARK_UV: (Vec2, Vec2) = (Vec2::new(0.03, 0.88), Vec2::new(0.17, 0.97));
/// A leaf's outline in its own frame (x toward +u, y toward the tip, units of leaf length):
/// the tip at y = 0.6, the stem at y = −0.4, the widest point at the centre (y = 0), where the
/// uvs have v = 0.6.
const LEAF_TIP: f32 = 0.6;
const LEAF_STEM: f32 = 0.4;

/// PCG32 (O'Neill's `pcg32`, XSH RR): a bush or a light array depends on its seed alone, not on a
/// platform RNG.
struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MUL: u64 = 6_364_136_223_846_793_005;

    fn new(seed: u64, stream: u64) -> Pcg32 {
        let mut rng = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / 16_777_216.0
    }

    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// A uniformly distributed unit vector.
    fn direction(&mut self) -> Vec3 {
        let y = self.range(-1.0, 1.0);
        let phi = TAU * self.unit();
        let r = (1.0 - y * y).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), y, r * phi.sin())
    }
}

/// A leafy bush standing on the origin, y up, deterministic in `seed` (its own PCG32, no platform
/// RNG).
///
/// The crown is the ellipsoid of horizontal radius `radius` and vertical semi-axis
/// [`CROWN_FLATTENING`]·`radius` centred at (0, `height`, 0). Each of the `leaves` (1 to
/// [`MAX_LEAVES`]) leaves has its centre inside it (mostly toward its surface, as on a real bush),
/// a length of 0.8–1.2 × `leaf_size` and a width of 0.5–0.65 × its length, and every point of a
/// leaf lies within 0.63 × its length (so 0.76 × `leaf_size`) of its centre. A leaf is a diamond
/// of 4 triangles around its centre vertex — tip, the two widest points, stem — slightly bent:
/// the halves fold up along the midrib and the tip droops. Its normal leans from +y by 0–65° (toward the outside
/// of the crown, more often a little than much), the tip points roughly outward. The leaf's uvs
/// map the leaf texture's [0, 1]²: tip at (0.5, 0), stem at (0.5, 1), the widest points at
/// (0, 0.6) and (1, 0.6). Leaf `i` is vertices `5i..5i + 5` (centre, tip, left, stem, right) and
/// triangles `4i..4i + 4`; every surface is two-sided, so there are no back faces.
///
/// Then the wood, [`BUSH_WOOD_TRIANGLES`] triangles: a trunk from the origin to the crown's
/// centre and six branches from it into the crown, tapered hexagonal prisms open at the base
/// and capped at the tip, their uvs in a bark patch of the leaf texture's lower-left corner.
/// Sizes the scene format refuses (zero, negative, non-finite) never panic: non-finite ones give
/// non-finite positions, which [`Mesh::validate`] rejects.
pub fn bush(leaves: u32, seed: u32, radius: f32, height: f32, leaf_size: f32) -> Mesh {
    let leaves = leaves.clamp(1, MAX_LEAVES) as usize;
    let centre = Vec3::new(0.0, height, 0.0);
    let semi = Vec3::new(radius, CROWN_FLATTENING * radius, radius);
    let mut m = Mesh::default();
    m.positions.reserve(leaves * LEAF_VERTICES);
    m.indices.reserve(leaves * LEAF_TRIANGLES * 3 + BUSH_WOOD_TRIANGLES * 3);
    let mut rng = Pcg32::new(u64::from(seed), 0x9e37_79b9_7f4a_7c15);
    // A per-seed phase for the crown's lobes.
    let lobe_phase = TAU * rng.unit();
    for _ in 0..leaves {
        // Centre: a direction, then a radial fraction in [0.35, 1) biased toward the surface,
        // times a gentle lobing so the crown is not a perfect ellipsoid (never beyond it).
        let dir = rng.direction();
        let azimuth = dir.z.atan2(dir.x);
        let lobes = 0.92 + 0.08 * (3.0 * azimuth + lobe_phase).sin() * (1.0 - dir.y * dir.y);
        let r = (0.35 + 0.65 * rng.unit().cbrt()) * lobes;
        let c = centre + semi * dir * r;
        // Normal: tilted from +y by up to 65° (small tilts likelier), toward the outside of the
        // crown give or take 90°.
        let tilt = 65f32.to_radians() * rng.unit().powf(1.5);
        let lean = azimuth + (rng.unit() - 0.5) * PI;
        let n = Vec3::new(tilt.sin() * lean.cos(), tilt.cos(), tilt.sin() * lean.sin());
        // Tip direction: outward and a little random, in the leaf's plane.
        let outward = Vec3::new(dir.x, 0.0, dir.z).normalize_or_zero() + rng.direction() * 0.7;
        let a = (outward - n * n.dot(outward))
            .try_normalize()
            .unwrap_or_else(|| n.any_orthonormal_vector());
        let t = a.cross(n); // toward +u; n × t = a points to the tip (−v)
        let length = leaf_size * rng.range(0.8, 1.2);
        let width = rng.range(0.5, 0.65);
        let fold = rng.range(0.0, 0.35) * 0.5 * width;
        let droop = rng.range(0.0, 0.3) * LEAF_TIP;
        push_leaf(&mut m, c, [t, a, n], length, width, fold, droop);
    }

    // The wood (its own stream, so it does not change with the leaf count): the trunk, then six
    // branches leaving it between half and 90% of its height toward points 70% of the way out
    // to the crown's surface.
    let mut rng = Pcg32::new(u64::from(seed), 0x2545_f491_4f6c_dd1d);
    let trunk_r = 0.05 * radius;
    push_prism(&mut m, Vec3::ZERO, centre, trunk_r, 0.4 * trunk_r);
    for k in 0..BUSH_PRISMS - 1 {
        let phi = TAU * (k as f32 + rng.range(-0.3, 0.3)) / (BUSH_PRISMS - 1) as f32;
        let up = rng.range(0.2, 0.7);
        let d = Vec3::new(phi.cos(), up, phi.sin()).normalize();
        let start = Vec3::new(0.0, height * rng.range(0.5, 0.9), 0.0);
        push_prism(&mut m, start, centre + semi * d * 0.7, 0.4 * trunk_r, 0.15 * trunk_r);
    }
    m.compute_tangents();
    m
}

/// Appends one leaf centred at `c` with frame `[t, a, n]` (toward +u, toward the tip, normal):
/// in leaf units its tip lies at (0, 0.6, −droop), its stem at (0, −0.4, 0) and its widest
/// points at (±width/2, 0, fold). Normals are each vertex's average of its faces' normals,
/// computed in leaf units so that a tiny leaf still gets unit normals.
fn push_leaf(m: &mut Mesh, c: Vec3, [t, a, n]: [Vec3; 3], length: f32, width: f32, fold: f32, droop: f32) {
    let base = m.positions.len() as u32;
    let local = [
        Vec3::ZERO,                         // centre
        Vec3::new(0.0, LEAF_TIP, -droop),   // tip
        Vec3::new(-0.5 * width, 0.0, fold), // left (u = 0)
        Vec3::new(0.0, -LEAF_STEM, 0.0),    // stem
        Vec3::new(0.5 * width, 0.0, fold),  // right (u = 1)
    ];
    let uvs = [
        Vec2::new(0.5, LEAF_TIP),
        Vec2::new(0.5, 0.0),
        Vec2::new(0.0, LEAF_TIP),
        Vec2::new(0.5, 1.0),
        Vec2::new(1.0, LEAF_TIP),
    ];
    // Counter-clockwise seen from +n: (tip, left, centre), (tip, centre, right), (stem, centre,
    // left), (stem, right, centre).
    const TRIS: [[usize; 3]; 4] = [[1, 2, 0], [1, 0, 4], [3, 0, 2], [3, 4, 0]];
    let mut normals = [Vec3::ZERO; 5];
    for tri in TRIS {
        let [p0, p1, p2] = tri.map(|i| local[i]);
        let face = (p1 - p0).cross(p2 - p0).normalize();
        for i in tri {
            normals[i] += face;
        }
    }
    let to_world = |v: Vec3| t * v.x + a * v.y + n * v.z;
    for ((p, nrm), uv) in local.iter().zip(normals).zip(uvs) {
        m.positions.push(c + to_world(*p) * length);
        m.normals.push(to_world(nrm).normalize());
        m.uvs.push(uv);
    }
    for tri in TRIS {
        m.indices.extend(tri.map(|i| base + i as u32));
    }
}

/// Appends a tapered prism of [`PRISM_SIDES`] sides from `b0` (radius `r0`, open) to `b1`
/// (radius `r1`, capped), with smooth side normals and uvs in [`BARK_UV`].
fn push_prism(m: &mut Mesh, b0: Vec3, b1: Vec3, r0: f32, r1: f32) {
    let axis_v = b1 - b0;
    let len = axis_v.length();
    let axis = axis_v.try_normalize().unwrap_or(Vec3::Y);
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1); // e1 × e2 = axis: increasing angle is counter-clockwise from the tip
    let (lo, hi) = BARK_UV;
    let ring = |k: usize| {
        let phi = TAU * (k % PRISM_SIDES) as f32 / PRISM_SIDES as f32;
        e1 * phi.cos() + e2 * phi.sin()
    };
    let base = m.positions.len() as u32;
    let sides = PRISM_SIDES as u32;
    // Sides: a column per corner (the seam column repeated for the uvs), bottom then top.
    for k in 0..=PRISM_SIDES {
        let d = ring(k);
        let normal = (d * len + axis * (r0 - r1)).try_normalize().unwrap_or(d);
        let u = lo.x + (hi.x - lo.x) * k as f32 / PRISM_SIDES as f32;
        for (p, r, v) in [(b0, r0, hi.y), (b1, r1, lo.y)] {
            m.positions.push(p + d * r);
            m.normals.push(normal);
            m.uvs.push(Vec2::new(u, v));
        }
    }
    for k in 0..sides {
        let (a, b, c, d) = (base + 2 * k, base + 2 * k + 2, base + 2 * k + 3, base + 2 * k + 1);
        m.indices.extend_from_slice(&[a, b, c, a, c, d]);
    }
    // The cap: a fan facing along the axis.
    let cap = m.positions.len() as u32;
    for k in 0..PRISM_SIDES {
        let d = ring(k);
        m.positions.push(b1 + d * r1);
        m.normals.push(axis);
        let phi = TAU * k as f32 / PRISM_SIDES as f32;
        m.uvs
            .push(lo.lerp(hi, 0.5) + Vec2::new(phi.cos(), -phi.sin()) * 0.5 * (hi - lo));
    }
    for k in 1..sides - 1 {
        m.indices.extend_from_slice(&[cap, cap + k, cap + k + 1]);
    }
}

/// Most lights the `[[light_arrays]]` of one scene may generate, all arrays together. Every
/// method uploads and loops over `scene.lights`, and the stress scenes need 4,096; 65,536 keeps a
/// typo (`grid = [1000, 1, 1000]`) from asking for gigabytes.
pub const MAX_ARRAY_LIGHTS: u32 = 65_536;

/// What kind of light every member of an array is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrayKind {
    Point,
    Spot,
}

/// Where an array's lights sit inside its box `min`..`max`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArrayLayout {
    /// The centres of an `nx × ny × nz` lattice of equal cells filling the box, x fastest, then
    /// y, then z.
    Grid([u32; 3]),
    /// This many points drawn uniformly in the box from the array's seed.
    Scatter(u32),
}

/// Where an array's spot lights point before the jitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArrayAim {
    /// Every axis parallel to this unit vector.
    Direction(Vec3),
    /// Every axis through this point.
    Target(Vec3),
}

/// One `[[light_arrays]]` entry as read from the scene (see `scenes/README.md`).
#[derive(Debug, Clone, PartialEq)]
pub struct LightArray {
    pub name: String,
    pub kind: ArrayKind,
    pub layout: ArrayLayout,
    /// Corners of the axis-aligned box the lights fill (an extent may be zero: a rectangle, a
    /// line).
    pub min: Vec3,
    pub max: Vec3,
    pub aim: ArrayAim,
    /// Largest tilt of a spot's axis away from its aim, degrees; uniform over that cone.
    pub jitter_deg: f32,
    pub seed: u32,
    /// W/sr, times `colours[i % colours.len()]` for light `i` when `colours` is not empty.
    pub intensity: Vec3,
    pub colours: Vec<Vec3>,
    pub inner_deg: f32,
    pub outer_deg: f32,
    pub radius: f32,
}

impl ArrayLayout {
    /// How many lights the layout places (u64: a grid's product may not fit a u32).
    pub fn count(&self) -> u64 {
        match *self {
            ArrayLayout::Grid(n) => n.iter().map(|&k| u64::from(k)).product(),
            ArrayLayout::Scatter(n) => u64::from(n),
        }
    }
}

impl LightArray {
    /// The array's lights, named `"<name>[i]"`. Deterministic in the seed; positions and aims
    /// draw from separate streams, so changing the jitter does not move the lights. Fails (with
    /// the light's index) only when a spot sits exactly on its target.
    pub fn expand(&self) -> Result<Vec<Light>, String> {
        let positions = self.positions();
        let mut aim_rng = Pcg32::new(u64::from(self.seed), 0x5851_f42d_4c95_7f2d);
        let max_tilt = self.jitter_deg.clamp(0.0, 180.0).to_radians();
        let mut out = Vec::with_capacity(positions.len());
        for (i, position) in positions.into_iter().enumerate() {
            let name = format!("{}[{i}]", self.name);
            let tint = if self.colours.is_empty() {
                Vec3::ONE
            } else {
                self.colours[i % self.colours.len()]
            };
            let intensity = self.intensity * tint;
            let light = match self.kind {
                ArrayKind::Point => Light::Point {
                    name,
                    position,
                    intensity,
                    radius: self.radius,
                },
                ArrayKind::Spot => {
                    let axis = match self.aim {
                        ArrayAim::Direction(d) => d.normalize(),
                        ArrayAim::Target(t) => (t - position)
                            .try_normalize()
                            .ok_or_else(|| format!("light {i} of the array sits exactly on the target"))?,
                    };
                    // Uniform over the spherical cap of half-angle max_tilt: cos θ uniform.
                    let (u, v) = (aim_rng.unit(), aim_rng.unit());
                    let cos_t = 1.0 - u * (1.0 - max_tilt.cos());
                    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                    let (e1, e2) = axis.any_orthonormal_pair();
                    let phi = TAU * v;
                    let direction = (axis * cos_t + (e1 * phi.cos() + e2 * phi.sin()) * sin_t).normalize();
                    Light::Spot {
                        name,
                        position,
                        direction,
                        intensity,
                        inner_deg: self.inner_deg,
                        outer_deg: self.outer_deg,
                        radius: self.radius,
                    }
                }
            };
            out.push(light);
        }
        Ok(out)
    }

    fn positions(&self) -> Vec<Vec3> {
        let extent = self.max - self.min;
        match self.layout {
            ArrayLayout::Grid([nx, ny, nz]) => {
                let at = |k: u32, n: u32| (k as f32 + 0.5) / n as f32;
                let mut out = Vec::with_capacity(self.layout.count() as usize);
                for z in 0..nz {
                    for y in 0..ny {
                        for x in 0..nx {
                            out.push(self.min + extent * Vec3::new(at(x, nx), at(y, ny), at(z, nz)));
                        }
                    }
                }
                out
            }
            ArrayLayout::Scatter(n) => {
                let mut rng = Pcg32::new(u64::from(self.seed), 0x1405_7b7e_f767_814f);
                (0..n)
                    .map(|_| self.min + extent * Vec3::new(rng.unit(), rng.unit(), rng.unit()))
                    .collect()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::tests::assert_well_formed;

    /// Every triangle's winding agrees with its vertex normals, and those point away from `centre`.
    fn assert_outward(m: &Mesh, centre: Vec3) {
        for tri in m.triangles() {
            let [a, b, c] = tri.map(|i| m.positions[i]);
            let face_n = (b - a).cross(c - a);
            for i in tri {
                assert!(face_n.dot(m.normals[i]) > 0.0, "winding disagrees with normal");
            }
            assert!(face_n.dot((a + b + c) / 3.0 - centre) > 0.0, "face points inward");
        }
    }

    #[test]
    fn plane_counts_area_orientation() {
        let m = plane(Vec2::new(4.0, 2.0), 3);
        assert_eq!(m.vertex_count(), 16);
        assert_eq!(m.triangle_count(), 18);
        assert_well_formed(&m);
        assert!((m.area() - 8.0).abs() < 1e-4);
        assert_outward(&m, Vec3::new(0.0, -1.0, 0.0));
        assert!(!m.is_closed_manifold());
        assert_eq!(m.boundary_edge_count(), 12);
        assert_eq!(m.bounds(), Some((Vec3::new(-2.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 1.0))));
        // Tangent along +x (u), bitangent toward −z (up in the image): w = +1.
        assert!(m
            .tangents
            .iter()
            .all(|t| (t.truncate() - Vec3::X).length() < 1e-5 && t.w == 1.0));
    }

    #[test]
    fn quad_faces_edge_cross_product() {
        let m = quad(
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.0, 0.0, -2.0),
            Vec3::new(0.0, 3.0, 0.0),
            2,
        );
        assert_eq!((m.vertex_count(), m.triangle_count()), (9, 8));
        assert_well_formed(&m);
        assert!((m.area() - 6.0).abs() < 1e-4);
        assert!(m.normals.iter().all(|&n| (n - Vec3::X).length() < 1e-6));
        assert_outward(&m, Vec3::new(0.0, 3.0, -1.0));
    }

    #[test]
    fn box_is_closed_outward_and_has_right_area() {
        for n in [1u32, 4] {
            let size = Vec3::new(1.0, 2.0, 3.0);
            let m = cuboid(size, n);
            assert_eq!(m.vertex_count(), 6 * ((n + 1) * (n + 1)) as usize);
            assert_eq!(m.triangle_count(), 12 * (n * n) as usize);
            assert_well_formed(&m);
            assert!(m.is_closed_manifold(), "box with {n} subdivisions not closed");
            assert_outward(&m, Vec3::ZERO);
            assert!((m.area() - 2.0 * (2.0 + 3.0 + 6.0)).abs() < 1e-3);
            assert_eq!(m.bounds(), Some((-size * 0.5, size * 0.5)));
            assert!(m.tangents.iter().all(|t| t.w == 1.0));
        }
    }

    #[test]
    fn sphere_is_closed_outward_and_area_converges() {
        let m = sphere(2.0, 16, 8);
        assert_eq!(m.vertex_count(), 17 * 9);
        assert_eq!(m.triangle_count(), 2 * 16 * 7);
        assert_well_formed(&m);
        assert!(m.is_closed_manifold());
        assert_outward(&m, Vec3::ZERO);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((*p / 2.0 - *n).length() < 1e-5);
        }
        let fine = sphere(1.5, 256, 128);
        assert!(fine.is_closed_manifold());
        let exact = 4.0 * PI * 1.5 * 1.5;
        assert!((fine.area() - exact).abs() / exact < 0.01, "{} vs {exact}", fine.area());
        // Minimal sphere is still a closed manifold.
        assert!(sphere(1.0, 3, 2).is_closed_manifold());
    }

    #[test]
    fn sphere_uv_directions() {
        let m = sphere(1.0, 8, 4);
        // Vertex at u = 0.25 on the equator lies at −z.
        let idx = 2 * 9 + 2;
        assert!((m.positions[idx] - Vec3::NEG_Z).length() < 1e-6);
        assert_eq!(m.uvs[idx], Vec2::new(0.25, 0.5));
        // Equator tangents point along +u (eastward), bitangent toward the north pole (−v).
        let t = m.tangents[idx];
        assert!((t.truncate() - Vec3::NEG_X).length() < 1e-3, "{t}");
        assert!(m.normals[idx].cross(t.truncate()).dot(Vec3::Y) * t.w > 0.99);
    }
}
