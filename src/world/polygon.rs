//! Planes, axis-aligned boxes and convex polygons: the geometric vocabulary of the world compiler.
//!
//! Everything is `f64`: a BSP compiler splits polygons again and again, and `f32` drift across
//! a few dozen splits is of the order of the epsilon below, which is what makes float BSP
//! compilers leak. The renderer converts with `as_vec3()` when it uploads.

use glam::DVec3;

use super::{MIN_POLYGON_AREA, PLANE_EPSILON};

/// The plane `normal · p = dist`, with a unit normal. The *front* is the side the normal points
/// to. For a brush side the normal points out of the solid; for a world face it points into the
/// empty space the face is seen from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: DVec3,
    pub dist: f64,
}

/// Where a point or polygon lies relative to a plane, with [`PLANE_EPSILON`] of thickness.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Front,
    Back,
    /// Every vertex within [`PLANE_EPSILON`] of the plane: the polygon lies in it.
    On,
    /// Vertices clearly on both sides.
    Spanning,
}

/// How thick a plane is for side tests, and whether coordinates are rounded: the numeric policy
/// of a BSP build. [`Tolerance::EXACT`] is the world compiler's (f64 throughout, planes
/// [`PLANE_EPSILON`] thick); [`Tolerance::THESIS`] is Ridderhof 2002's (§5.6.1: every double rounded to
/// four decimal places, points that close to a plane on it), kept so its faithful mode can be
/// compared with the exact one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Half-thickness of a plane: a point this close to it is on it.
    pub plane: f64,
    /// The grid new and input coordinates are rounded to, if any.
    pub grid: Option<f64>,
    /// Polygons of less area are degenerate and dropped.
    pub min_area: f64,
}

impl Tolerance {
    pub const EXACT: Tolerance = Tolerance {
        plane: PLANE_EPSILON,
        grid: None,
        min_area: MIN_POLYGON_AREA,
    };
    /// The thesis's, with polygons dropped only when the grid would collapse them (under a
    /// cell's area): a scanned mesh's millimetre triangles stay.
    pub const THESIS: Tolerance = Tolerance {
        plane: 1e-4,
        grid: Some(1e-4),
        min_area: 1e-8,
    };
    /// [`Tolerance::EXACT`] for meshes: a polygon is degenerate only under the plane's
    /// thickness squared, not under [`MIN_POLYGON_AREA`], which is a brush world's scale (1 mm²)
    /// and would drop most of a scanned mesh's triangles (the Stanford bunny's average 0.8 mm²).
    pub const MESH: Tolerance = Tolerance {
        plane: PLANE_EPSILON,
        grid: None,
        min_area: PLANE_EPSILON * PLANE_EPSILON,
    };

    /// `p` rounded to the grid (unchanged without one).
    pub fn round(&self, p: DVec3) -> DVec3 {
        match self.grid {
            Some(g) => (p / g).round() * g,
            None => p,
        }
    }

    fn side(&self, d: f64) -> Side {
        if d > self.plane {
            Side::Front
        } else if d < -self.plane {
            Side::Back
        } else {
            Side::On
        }
    }
}

impl Plane {
    /// A plane from a (not necessarily unit) normal and a point on it; `None` for a zero normal.
    pub fn from_normal_point(normal: DVec3, point: DVec3) -> Option<Plane> {
        let n = normal.try_normalize()?;
        Some(Plane {
            normal: n,
            dist: n.dot(point),
        })
    }

    /// The plane through three points, front side where `(b − a) × (c − a)` points, i.e. the
    /// points run counter-clockwise seen from the front. `None` if they are collinear.
    pub fn from_points(a: DVec3, b: DVec3, c: DVec3) -> Option<Plane> {
        Plane::from_normal_point((b - a).cross(c - a), a)
    }

    /// Signed distance: positive in front.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.dist
    }

    pub fn flipped(&self) -> Plane {
        Plane {
            normal: -self.normal,
            dist: -self.dist,
        }
    }

    pub fn side_of_point(&self, p: DVec3) -> Side {
        self.side_of_point_in(p, &Tolerance::EXACT)
    }

    pub fn side_of_point_in(&self, p: DVec3, tolerance: &Tolerance) -> Side {
        tolerance.side(self.distance(p))
    }

    /// `Some(true)` if `other` is the same plane, `Some(false)` if it is the same plane facing
    /// the other way, `None` otherwise.
    pub fn coplanar_facing(&self, other: &Plane) -> Option<bool> {
        let dot = self.normal.dot(other.normal);
        if dot > 1.0 - NORMAL_EPSILON && (self.dist - other.dist).abs() < PLANE_EPSILON {
            Some(true)
        } else if dot < -(1.0 - NORMAL_EPSILON) && (self.dist + other.dist).abs() < PLANE_EPSILON {
            Some(false)
        } else {
            None
        }
    }

    /// The axis (0, 1, 2) if the normal is ±x, ±y or ±z.
    pub fn axis(&self) -> Option<usize> {
        (0..3).find(|&i| self.normal[i].abs() > 1.0 - NORMAL_EPSILON)
    }
}

/// Two unit normals count as parallel when their dot product is within this of ±1
/// (about 0.03° apart).
pub const NORMAL_EPSILON: f64 = 1e-7;

/// An axis-aligned box. `Aabb::EMPTY` is the identity for [`Aabb::include`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.include(*p);
        }
        b
    }

    pub fn include(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn expanded(&self, by: f64) -> Aabb {
        Aabb {
            min: self.min - DVec3::splat(by),
            max: self.max + DVec3::splat(by),
        }
    }

    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    pub fn contains(&self, p: DVec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Whether the sphere touches the box (closed sets).
    pub fn touches_sphere(&self, center: DVec3, radius: f64) -> bool {
        let nearest = center.max(self.min).min(self.max); // clamp, without panicking on EMPTY
        nearest.distance_squared(center) <= radius * radius
    }

    /// The six bounding planes, normals pointing out of the box.
    pub fn planes(&self) -> [Plane; 6] {
        let mut out = [Plane {
            normal: DVec3::ZERO,
            dist: 0.0,
        }; 6];
        for axis in 0..3 {
            let mut n = DVec3::ZERO;
            n[axis] = 1.0;
            out[2 * axis] = Plane {
                normal: n,
                dist: self.max[axis],
            };
            out[2 * axis + 1] = Plane {
                normal: -n,
                dist: -self.min[axis],
            };
        }
        out
    }
}

/// A planar convex polygon. Vertices run counter-clockwise seen from the front of `plane`; the
/// plane is kept from the polygon's origin rather than recomputed, so splitting never tilts it.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    pub vertices: Vec<DVec3>,
    pub plane: Plane,
}

/// The result of cutting a polygon by a plane.
#[derive(Clone, Debug)]
pub enum Split {
    Front(Polygon),
    Back(Polygon),
    /// The polygon lies in the plane; `true` if it faces the same way as the plane.
    On(Polygon, bool),
    /// Both pieces; either may be `None` when it came out degenerate (thinner than the epsilon).
    Spanning {
        front: Option<Polygon>,
        back: Option<Polygon>,
    },
}

impl Polygon {
    /// A square of half-size `half_size` in `plane`, centred on the point of the plane closest
    /// to the origin: the starting winding that brushes and portals are clipped out of.
    pub fn base_winding(plane: &Plane, half_size: f64) -> Polygon {
        let n = plane.normal;
        // Any vector not parallel to n; the choice only rotates the square.
        let helper = if n.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
        let u = helper.cross(n).normalize();
        let v = n.cross(u); // u × v = n, so (−,−),(+,−),(+,+),(−,+) is counter-clockwise.
        let c = n * plane.dist;
        let (u, v) = (u * half_size, v * half_size);
        Polygon {
            vertices: vec![c - u - v, c + u - v, c + u + v, c - u + v],
            plane: *plane,
        }
    }

    /// A polygon from vertices, taking the plane from Newell's normal. `None` if degenerate.
    pub fn from_vertices(vertices: Vec<DVec3>) -> Option<Polygon> {
        Polygon::from_vertices_in(vertices, &Tolerance::EXACT)
    }

    /// [`Polygon::from_vertices`] under `tolerance`.
    pub fn from_vertices_in(vertices: Vec<DVec3>, tolerance: &Tolerance) -> Option<Polygon> {
        let mut normal = DVec3::ZERO;
        for (i, a) in vertices.iter().enumerate() {
            let b = vertices[(i + 1) % vertices.len()];
            normal += a.cross(b);
        }
        let centroid = vertices.iter().copied().sum::<DVec3>() / vertices.len().max(1) as f64;
        let plane = Plane::from_normal_point(normal, centroid)?;
        Polygon { vertices, plane }.cleaned_in(tolerance)
    }

    /// Area, from the vector area projected on the plane normal.
    pub fn area(&self) -> f64 {
        let mut sum = DVec3::ZERO;
        for (i, a) in self.vertices.iter().enumerate() {
            sum += a.cross(self.vertices[(i + 1) % self.vertices.len()]);
        }
        0.5 * sum.dot(self.plane.normal).abs()
    }

    /// Vertex average: inside a convex polygon, which is all this is used for.
    pub fn center(&self) -> DVec3 {
        self.vertices.iter().copied().sum::<DVec3>() / self.vertices.len() as f64
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    pub fn flipped(&self) -> Polygon {
        Polygon {
            vertices: self.vertices.iter().rev().copied().collect(),
            plane: self.plane.flipped(),
        }
    }

    /// Drops consecutive vertices closer than the epsilon; `None` if fewer than three remain or
    /// the area is below [`MIN_POLYGON_AREA`]. Degenerate polygons leave the pipeline here.
    pub fn cleaned(self) -> Option<Polygon> {
        self.cleaned_in(&Tolerance::EXACT)
    }

    /// [`Polygon::cleaned`] with vertices closer than `tolerance.plane` merged, and
    /// `tolerance.min_area` the least area.
    pub fn cleaned_in(mut self, tolerance: &Tolerance) -> Option<Polygon> {
        let mut out: Vec<DVec3> = Vec::with_capacity(self.vertices.len());
        for &v in &self.vertices {
            if out.last().is_none_or(|l| l.distance(v) > tolerance.plane) {
                out.push(v);
            }
        }
        while out.len() > 1 && out[0].distance(out[out.len() - 1]) <= tolerance.plane {
            out.pop();
        }
        self.vertices = out;
        (self.vertices.len() >= 3 && self.area() >= tolerance.min_area).then_some(self)
    }

    pub fn classify(&self, plane: &Plane) -> Side {
        self.classify_in(plane, &Tolerance::EXACT)
    }

    pub fn classify_in(&self, plane: &Plane, tolerance: &Tolerance) -> Side {
        let (mut front, mut back) = (false, false);
        for &v in &self.vertices {
            match plane.side_of_point_in(v, tolerance) {
                Side::Front => front = true,
                Side::Back => back = true,
                _ => {}
            }
        }
        match (front, back) {
            (true, true) => Side::Spanning,
            (true, false) => Side::Front,
            (false, true) => Side::Back,
            (false, false) => Side::On,
        }
    }

    /// Cuts the polygon by `plane`. Vertices within the epsilon of the plane go to both pieces;
    /// edge crossings are computed once and shared, so the two pieces meet exactly and their
    /// areas sum to the original.
    pub fn split(self, plane: &Plane) -> Split {
        self.split_in(plane, &Tolerance::EXACT)
    }

    /// [`Polygon::split`] under `tolerance`: its plane thickness, and the crossings rounded to
    /// its grid.
    pub fn split_in(self, plane: &Plane, tolerance: &Tolerance) -> Split {
        match self.classify_in(plane, tolerance) {
            Side::Front => return Split::Front(self),
            Side::Back => return Split::Back(self),
            Side::On => {
                let same = self.plane.normal.dot(plane.normal) > 0.0;
                return Split::On(self, same);
            }
            Side::Spanning => {}
        }
        let (front, back) = split_points_in(&self.vertices, plane, tolerance);
        let piece = |vertices| {
            Polygon {
                vertices,
                plane: self.plane,
            }
            .cleaned_in(tolerance)
        };
        Split::Spanning {
            front: piece(front),
            back: piece(back),
        }
    }

    /// The part in front of `plane` (on-plane polygons kept when they face the same way).
    pub fn clip_front(self, plane: &Plane) -> Option<Polygon> {
        match self.split(plane) {
            Split::Front(p) => Some(p),
            Split::On(p, same) => same.then_some(p),
            Split::Back(_) => None,
            Split::Spanning { front, .. } => front,
        }
    }

    /// The part behind `plane` (on-plane polygons kept when they face the same way).
    pub fn clip_back(self, plane: &Plane) -> Option<Polygon> {
        self.clip_front(&plane.flipped())
    }

    /// Whether `p` (assumed in or near the plane) is inside the polygon, with `tolerance` of
    /// slack across every edge.
    pub fn contains_point(&self, p: DVec3, tolerance: f64) -> bool {
        let n = self.plane.normal;
        let count = self.vertices.len();
        (0..count).all(|i| {
            let a = self.vertices[i];
            let edge = self.vertices[(i + 1) % count] - a;
            let len = edge.length();
            len == 0.0 || edge.cross(p - a).dot(n) >= -tolerance * len
        })
    }

    /// Distance from `p` to the closest edge of the polygon (in 3-D).
    pub fn distance_to_boundary(&self, p: DVec3) -> f64 {
        let count = self.vertices.len();
        (0..count)
            .map(|i| point_segment_distance(p, self.vertices[i], self.vertices[(i + 1) % count]))
            .fold(f64::INFINITY, f64::min)
    }

    /// Ray–polygon intersection: the `t` along `origin + t·dir` in `(t_min, t_max]`, or `None`.
    /// Both sides of the polygon count.
    pub fn intersect_ray(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        let denom = self.plane.normal.dot(dir);
        if denom.abs() < 1e-15 {
            return None;
        }
        let t = -self.plane.distance(origin) / denom;
        if t <= t_min || t > t_max {
            return None;
        }
        self.contains_point(origin + dir * t, 1e-9).then_some(t)
    }
}

/// Sutherland–Hodgman in both directions at once: the vertex lists of the front and back
/// pieces. On-plane vertices go to both; crossings are snapped onto axis-aligned planes exactly.
pub fn split_points(vertices: &[DVec3], plane: &Plane) -> (Vec<DVec3>, Vec<DVec3>) {
    split_points_in(vertices, plane, &Tolerance::EXACT)
}

/// [`split_points`] under `tolerance` (crossings rounded to its grid after the axis snap).
pub fn split_points_in(vertices: &[DVec3], plane: &Plane, tolerance: &Tolerance) -> (Vec<DVec3>, Vec<DVec3>) {
    let dists: Vec<f64> = vertices.iter().map(|&v| plane.distance(v)).collect();
    let sides: Vec<Side> = dists.iter().map(|&d| tolerance.side(d)).collect();
    let (mut front, mut back) = (Vec::new(), Vec::new());
    let count = vertices.len();
    for i in 0..count {
        let j = (i + 1) % count;
        let v = vertices[i];
        match sides[i] {
            Side::On => {
                front.push(v);
                back.push(v);
                continue;
            }
            Side::Front => front.push(v),
            _ => back.push(v),
        }
        if sides[j] == Side::On || sides[j] == sides[i] {
            continue;
        }
        let t = dists[i] / (dists[i] - dists[j]);
        let mut mid = v + (vertices[j] - v) * t;
        if let Some(axis) = plane.axis() {
            mid[axis] = plane.dist * plane.normal[axis].signum();
        }
        let mid = tolerance.round(mid);
        front.push(mid);
        back.push(mid);
    }
    (front, back)
}

/// Keeps the part of a vertex list with signed distance ≥ −`slack` from `plane`; unlike
/// [`Polygon::clip_front`] it never discards a thin result, which is what an intersection
/// *test* wants (touching counts). Returns the clipped list, possibly empty.
pub fn clip_points_front(vertices: &[DVec3], plane: &Plane, slack: f64) -> Vec<DVec3> {
    let shifted = Plane {
        normal: plane.normal,
        dist: plane.dist - slack,
    };
    if vertices.iter().all(|&v| shifted.distance(v) >= 0.0) {
        return vertices.to_vec();
    }
    let count = vertices.len();
    let mut out = Vec::with_capacity(count + 1);
    for i in 0..count {
        let (a, b) = (vertices[i], vertices[(i + 1) % count]);
        let (da, db) = (shifted.distance(a), shifted.distance(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

pub fn point_segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}
