//! Surfaces cut along the thin walls that stand on them. One light-map texel covers one patch;
//! where a wall thinner than a patch stands across a floor, a ceiling or a wall, patches straddle
//! it with light on one side and none on the other. A straddling patch keeps one side
//! ([`super::buried::one_side`]), and its texel paints that side's light over the other's strip:
//! a dark room showed the lit room's floor along its wall, and the lit room lost the light that
//! landed on the strip. Cut along the wall's midline, each side becomes a chart of its own, with
//! its own texels and border, and the border passes keep the wall between them
//! ([`super::border`]'s anti-bleeding check).
//!
//! A wall is a pair of faces standing on the chart (steep, crossing a plane a little above it)
//! that face away from each other across a gap narrower than a patch, over a common stretch.
//! Walls as thick as a patch or more need no cut: no patch reaches both of their sides. A wall of
//! one face (no thickness) is not cut.

use glam::{DVec2, DVec3};

use super::geometry::StaticGeometry;
use super::patches::{group_charts, Chart, Triangle};

/// A face stands on a chart when its normal is this close to lying in the chart's plane.
const STEEP: f64 = 0.2;
/// The height above the chart where standing faces are cut, in patches: above the coincident
/// bottom faces of solids resting on it.
const PROBE_HEIGHT: f64 = 0.05;
/// A cut through a triangle this close to a corner (in metres per metre of patch) keeps it whole.
const SNAP: f64 = 1e-6;

/// A standing face's trace on a chart's plane: a segment in the chart's frame, and its in-plane
/// normal (pointing out of the solid).
#[derive(Clone, Copy, Debug)]
struct Trace {
    a: DVec2,
    b: DVec2,
    out: DVec2,
}

/// A cut line in a chart's frame: the points `x` with `normal · x = offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Line {
    pub normal: DVec2,
    pub offset: f64,
}

/// Cuts `g`'s triangles along the midlines of the walls thinner than `size` that stand on them,
/// and numbers each piece's side ([`Triangle::part`]) so that each side groups into its own chart.
/// Every per-triangle list of `g` follows (positions, object-space corners and uvs interpolated
/// along the cut edges). Returns the number of cut lines.
pub fn along_thin_walls(g: &mut StaticGeometry, size: f64) -> usize {
    let charts = group_charts(&g.triangles);
    let mut lines_of = vec![Vec::new(); g.triangles.len()];
    let mut count = 0;
    // A chart smaller than a patch's area (a curved mesh's triangles) holds little light across
    // any wall, and skipping it keeps the scan over every triangle to the few large charts.
    let large = |c: &&Chart| c.triangles.iter().map(|&t| g.triangles[t].area()).sum::<f64>() >= size * size;
    for c in charts.iter().filter(|c| !c.sky).filter(large) {
        let lines = wall_lines(c, &g.triangles, size);
        count += lines.len();
        for &t in &c.triangles {
            lines_of[t].clone_from(&lines);
        }
    }
    if count == 0 {
        return 0;
    }
    let entities = std::mem::take(&mut g.entities);
    let old = std::mem::replace(
        g,
        StaticGeometry {
            triangles: Vec::new(),
            draw: Vec::new(),
            object_space: Vec::new(),
            uvs: Vec::new(),
            material: Vec::new(),
            entities,
        },
    );
    let frame = |t: &Triangle| chart_frame(t.normal());
    for (t, lines) in lines_of.iter().enumerate() {
        let corners = Corners {
            p: old.triangles[t].p,
            object: old.object_space[t].map(|q| DVec3::from(q.map(f64::from))),
            uv: old.uvs[t].map(|q| DVec2::new(q[0] as f64, q[1] as f64)),
        };
        let (u, v) = frame(&old.triangles[t]);
        let mut pieces = vec![(corners, 0u64)];
        for (bit, line) in lines.iter().enumerate().take(64) {
            let side = |p: DVec3| line.normal.dot(DVec2::new(p.dot(u), p.dot(v))) - line.offset;
            pieces = pieces
                .into_iter()
                .flat_map(|(c, part)| {
                    split(&c, side, size * SNAP)
                        .into_iter()
                        .map(move |(piece, above)| (piece, part | (u64::from(above) << bit)))
                })
                .collect();
        }
        for (c, part) in pieces {
            g.triangles.push(Triangle {
                p: c.p,
                part,
                ..old.triangles[t]
            });
            g.draw.push(old.draw[t]);
            g.object_space.push(c.object.map(|q| q.as_vec3().to_array()));
            g.uvs.push(c.uv.map(|q| [q.x as f32, q.y as f32]));
            g.material.push(old.material[t]);
        }
    }
    count
}

/// [`along_thin_walls`], keeping the geometry as it was: `None` where nothing was cut.
pub fn cut_copy(g: &mut StaticGeometry, size: f64) -> Option<StaticGeometry> {
    let before = g.clone();
    (along_thin_walls(g, size) > 0).then_some(before)
}

/// The in-plane frame of a chart of normal `n`, as [`group_charts`] picks it.
fn chart_frame(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = helper.cross(n).normalize();
    (u, n.cross(u))
}

/// The midlines of the thin walls standing on chart `c`, in its frame, without repeats.
pub(crate) fn wall_lines(c: &Chart, triangles: &[Triangle], size: f64) -> Vec<Line> {
    let plane = c.normal.dot(triangles[c.triangles[0]].p[0]);
    let flat: Vec<[DVec2; 3]> = c
        .triangles
        .iter()
        .map(|&t| triangles[t].p.map(|q| DVec2::new(q.dot(c.u), q.dot(c.v))))
        .collect();
    let on_chart = |x: DVec2| flat.iter().any(|t| super::patches::inside_triangle(x, t));
    let probe = PROBE_HEIGHT * size;
    let mut traces = Vec::new();
    for t in triangles {
        let n = t.normal();
        if t.object == c.object || t.sky || n.dot(c.normal).abs() > STEEP {
            continue;
        }
        let h = t.p.map(|q| c.normal.dot(q) - plane);
        if h.iter().all(|&x| x > probe) || h.iter().all(|&x| x <= probe) || h.iter().any(|&x| x < -size) {
            continue;
        }
        // The trace at `probe`: where the edges cross that height.
        let mut ends = Vec::new();
        for k in 0..3 {
            let (p, q, hp, hq) = (t.p[k], t.p[(k + 1) % 3], h[k], h[(k + 1) % 3]);
            if (hp - probe) * (hq - probe) < 0.0 {
                let x = p + (q - p) * ((probe - hp) / (hq - hp));
                ends.push(DVec2::new(x.dot(c.u), x.dot(c.v)));
            }
        }
        let out = DVec2::new(n.dot(c.u), n.dot(c.v)).normalize_or_zero();
        if ends.len() == 2 && out != DVec2::ZERO && (ends[1] - ends[0]).length() > 1e-9 {
            let (a, b) = (ends[0], ends[1]);
            // Only traces over the chart's own surface divide it.
            if (0..=8).any(|s| on_chart(a + (b - a) * (s as f64 / 8.0))) {
                traces.push(Trace { a, b, out });
            }
        }
    }
    let mut lines: Vec<Line> = Vec::new();
    for (i, f) in traces.iter().enumerate() {
        for g in &traces[i + 1..] {
            if f.out.dot(g.out) > -0.999 {
                continue;
            }
            // f's solid lies where out_f · x < f's offset, g's where out_f · x > −g's offset.
            let (cf, cg) = (f.out.dot(f.a), g.out.dot(g.a));
            let thickness = cf + cg;
            let along = f.out.perp();
            let (f0, f1) = min_max(along.dot(f.a), along.dot(f.b));
            let (g0, g1) = min_max(along.dot(g.a), along.dot(g.b));
            let overlap = f1.min(g1) - f0.max(g0);
            if thickness > 1e-6 * size && thickness < size && overlap > 1e-6 * size {
                let line = canonical(f.out, (cf - cg) / 2.0);
                let known = lines.iter().any(|l| {
                    l.normal.dot(line.normal) > 1.0 - 1e-9 && (l.offset - line.offset).abs() < 1e-6 * size.max(1.0)
                });
                if !known {
                    lines.push(line);
                }
            }
        }
    }
    lines
}

fn min_max(a: f64, b: f64) -> (f64, f64) {
    (a.min(b), a.max(b))
}

/// The line with its normal turned into a half-plane of its own (so a wall's two faces name one
/// line): x, or y where x is zero, non-negative.
fn canonical(normal: DVec2, offset: f64) -> Line {
    if normal.x < -1e-12 || (normal.x.abs() <= 1e-12 && normal.y < 0.0) {
        Line {
            normal: -normal,
            offset: -offset,
        }
    } else {
        Line { normal, offset }
    }
}

/// A triangle's corners in every space the cut carries them through.
#[derive(Clone, Copy, Debug)]
struct Corners {
    p: [DVec3; 3],
    object: [DVec3; 3],
    uv: [DVec2; 3],
}

/// A point in every space the cut carries corners through.
type Vertex = (DVec3, DVec3, DVec2);

impl Corners {
    fn at(&self, k: usize) -> Vertex {
        (self.p[k], self.object[k], self.uv[k])
    }

    /// The point `s` of the way from corner `i` to corner `j`.
    fn between(&self, i: usize, j: usize, s: f64) -> Vertex {
        (
            self.p[i] + (self.p[j] - self.p[i]) * s,
            self.object[i] + (self.object[j] - self.object[i]) * s,
            self.uv[i] + (self.uv[j] - self.uv[i]) * s,
        )
    }

    fn of(v: [Vertex; 3]) -> Corners {
        Corners {
            p: v.map(|x| x.0),
            object: v.map(|x| x.1),
            uv: v.map(|x| x.2),
        }
    }
}

/// `c` split by the line where `side` is zero: its pieces (wound as `c` is), each with whether
/// it lies on the positive side. Corners within `snap` of the line count as on it.
fn split(c: &Corners, side: impl Fn(DVec3) -> f64, snap: f64) -> Vec<(Corners, bool)> {
    let s = c.p.map(|p| {
        let d = side(p);
        if d.abs() <= snap {
            0.0
        } else {
            d
        }
    });
    if s.iter().all(|&d| d >= 0.0) || s.iter().all(|&d| d <= 0.0) {
        return vec![(*c, s.iter().sum::<f64>() > 0.0)];
    }
    let next = |k: usize| ((k + 1) % 3, (k + 2) % 3);
    if let Some(k) = (0..3).find(|&k| s[k] == 0.0) {
        // A corner on the line and the others on either side: two triangles about it.
        let (i, j) = next(k);
        let x = c.between(i, j, s[i] / (s[i] - s[j]));
        return vec![
            (Corners::of([c.at(k), c.at(i), x]), s[i] > 0.0),
            (Corners::of([c.at(k), x, c.at(j)]), s[j] > 0.0),
        ];
    }
    // One corner alone on its side: the tip there, and the quad left in two triangles.
    let k = (0..3)
        .find(|&k| {
            let (i, j) = next(k);
            (s[k] > 0.0) != (s[i] > 0.0) && (s[k] > 0.0) != (s[j] > 0.0)
        })
        .unwrap_or(0);
    let (i, j) = next(k);
    let xi = c.between(k, i, s[k] / (s[k] - s[i]));
    let xj = c.between(k, j, s[k] / (s[k] - s[j]));
    let alone = s[k] > 0.0;
    vec![
        (Corners::of([c.at(k), xi, xj]), alone),
        (Corners::of([xi, c.at(i), c.at(j)]), !alone),
        (Corners::of([xi, c.at(j), xj]), !alone),
    ]
}
