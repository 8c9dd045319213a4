//! Alpha cut-outs made geometry: a glTF MASK material whose base colour texture carries alpha,
//! or an OBJ material with `map_d` (leaves, chains, fences, grilles).
//!
//! penumbra's material has one opacity, and every method and the reference path tracer draw or
//! trace meshes; so the mask is applied once, when the asset is read. Each triangle is cut along
//! the rows and columns of the mask's cells (in texture space), and only the cells whose alpha
//! reaches the cutoff keep their piece of the triangle. Every method and the reference then see
//! the same leaves. The mask is read at the finest box-filtered level whose cells the part's
//! triangles cover at most [`CELL_BUDGET`] times in all, so a cut edge lies within one cell of
//! that level from the texture's own edge; the level and the triangle counts are reported.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use crate::scene::mesh::Mesh;

/// Most mask cells one part's triangles may cover, summed over the triangles. It bounds the
/// work and the output: a cell contributes at most a polygon of a few triangles.
pub const CELL_BUDGET: f64 = (1u32 << 18) as f64;

/// Most bounding-box cells the cut walks over, summed over a part's triangles. [`CELL_BUDGET`]
/// bounds the area cut, not the walk: a sliver across many rows, or uvs of a broken asset's wild
/// size, would walk its whole box. Past this a triangle is kept or dropped whole by the texel
/// under its centre, and the report counts it.
pub const WALK_BUDGET: f64 = 64.0 * CELL_BUDGET;

/// A texture's coverage: alpha in [0, 1] per texel, row 0 at the top (uv (0, 0)), as penumbra
/// samples maps: repeat wrapping.
pub struct Mask {
    width: usize,
    height: usize,
    alpha: Vec<f32>,
}

impl Mask {
    /// `alpha` has `width * height` values, row by row from the top.
    pub fn new(width: usize, height: usize, alpha: Vec<f32>) -> Option<Mask> {
        (width > 0 && height > 0 && alpha.len() == width * height).then_some(Mask { width, height, alpha })
    }

    /// Whether any texel is under `cutoff`: if none is, nothing needs cutting.
    pub fn hides_any(&self, cutoff: f32) -> bool {
        self.alpha.iter().any(|&a| a < cutoff)
    }

    /// The mask box-filtered over `side` × `side` texel blocks (the last block of a row or column
    /// takes what is left).
    fn reduced(&self, side: usize) -> Mask {
        if side == 1 {
            return Mask {
                width: self.width,
                height: self.height,
                alpha: self.alpha.clone(),
            };
        }
        let (w, h) = (self.width.div_ceil(side), self.height.div_ceil(side));
        let mut alpha = vec![0.0f32; w * h];
        for (cy, row) in alpha.chunks_mut(w).enumerate() {
            for (cx, out) in row.iter_mut().enumerate() {
                let (x0, y0) = (cx * side, cy * side);
                let (x1, y1) = ((x0 + side).min(self.width), (y0 + side).min(self.height));
                let mut sum = 0.0f64;
                for y in y0..y1 {
                    sum += self.alpha[y * self.width + x0..y * self.width + x1]
                        .iter()
                        .map(|&a| f64::from(a))
                        .sum::<f64>();
                }
                *out = (sum / ((x1 - x0) * (y1 - y0)) as f64) as f32;
            }
        }
        Mask {
            width: w,
            height: h,
            alpha,
        }
    }
}

/// What [`cut`] did, for the line it prints.
#[derive(Debug, Clone, PartialEq)]
pub struct CutReport {
    /// Texels per cell side (a power of two).
    pub cell_texels: usize,
    pub triangles_before: usize,
    pub triangles_after: usize,
    /// Triangles kept or dropped whole by the texel under their centre: no extent in texture
    /// space, or past [`WALK_BUDGET`].
    pub whole_by_centre: usize,
}

/// One corner of a clipped polygon: its point in cell units and its barycentric weights in the
/// source triangle.
#[derive(Clone, Copy)]
struct Corner {
    p: Vec2,
    bary: Vec3,
}

/// Keeps the part of `poly` where `axis` (0: x, 1: y) times `sign` is at least `sign * at`
/// (Sutherland-Hodgman against one axis-aligned line).
fn clip(poly: &[Corner], axis: usize, at: f32, sign: f32) -> Vec<Corner> {
    let inside = |c: &Corner| sign * (c.p[axis] - at) >= 0.0;
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (i, a) in poly.iter().enumerate() {
        let b = &poly[(i + 1) % poly.len()];
        let (ia, ib) = (inside(a), inside(b));
        if ia {
            out.push(*a);
        }
        if ia != ib {
            let t = (at - a.p[axis]) / (b.p[axis] - a.p[axis]);
            let mut p = a.p.lerp(b.p, t);
            p[axis] = at;
            out.push(Corner {
                p,
                bary: a.bary.lerp(b.bary, t),
            });
        }
    }
    out
}

/// Twice the signed area of a polygon.
fn doubled_area(poly: &[Corner]) -> f32 {
    (0..poly.len())
        .map(|i| poly[i].p.perp_dot(poly[(i + 1) % poly.len()].p))
        .sum()
}

/// The triangles of `mesh` where `mask` reaches `cutoff`, cut along the mask's cells; normals and
/// uvs interpolated, tangents left for the caller to derive.
pub fn cut(mesh: &Mesh, mask: &Mask, cutoff: f32) -> (Mesh, CutReport) {
    let texel = Vec2::new(mask.width as f32, mask.height as f32);
    let footprint: f64 = mesh
        .triangles()
        .map(|[a, b, c]| {
            let (ua, ub, uc) = (mesh.uvs[a] * texel, mesh.uvs[b] * texel, mesh.uvs[c] * texel);
            f64::from((ub - ua).perp_dot(uc - ua).abs()) * 0.5
        })
        .sum();
    let mut side = 1usize;
    while footprint / (side * side) as f64 > CELL_BUDGET && side < mask.width.max(mask.height) {
        side *= 2;
    }
    let level = mask.reduced(side);
    let scale = texel / side as f32;
    // Whether the cell (i, j) in unwrapped cell units is kept: its centre, wrapped into the
    // texture, falls in a level cell at or above the cutoff.
    let kept = |i: i64, j: i64| {
        let u = ((i as f32 + 0.5) / scale.x).rem_euclid(1.0);
        let v = ((j as f32 + 0.5) / scale.y).rem_euclid(1.0);
        let x = ((u * mask.width as f32) as usize).min(mask.width - 1) / side;
        let y = ((v * mask.height as f32) as usize).min(mask.height - 1) / side;
        level.alpha[y * level.width + x] >= cutoff
    };
    let mut out = Builder::new(mesh);
    let (mut walked, mut whole_by_centre) = (0.0f64, 0usize);
    for tri in mesh.triangles() {
        let corners: Vec<Corner> = tri
            .iter()
            .zip([Vec3::X, Vec3::Y, Vec3::Z])
            .map(|(&v, bary)| Corner {
                p: mesh.uvs[v] * scale,
                bary,
            })
            .collect();
        let (lo, hi) = corners
            .iter()
            .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(c.p), hi.max(c.p))
            });
        let walk = f64::from(hi.x.ceil() - lo.x.floor()) * f64::from(hi.y.ceil() - lo.y.floor());
        if doubled_area(&corners).abs() < 1e-9 || !walk.is_finite() || walked + walk > WALK_BUDGET {
            // No extent in texture space, or too much of it to walk: the texel under the centre
            // decides for the whole triangle.
            let centre = (corners[0].p + corners[1].p + corners[2].p) / 3.0;
            if kept(centre.x.floor() as i64, centre.y.floor() as i64) {
                out.polygon(tri, &corners);
            }
            whole_by_centre += 1;
            continue;
        }
        walked += walk;
        match kept_pieces(&corners, (lo, hi), &kept) {
            None => out.polygon(tri, &corners),
            Some(pieces) => pieces.iter().for_each(|piece| out.polygon(tri, piece)),
        }
    }
    let report = CutReport {
        cell_texels: side,
        triangles_before: mesh.triangle_count(),
        triangles_after: out.mesh.triangle_count(),
        whole_by_centre,
    };
    (out.mesh, report)
}

/// The pieces of a triangle (`corners` in cell units, bounded by `lo`..`hi`) over kept cells, row
/// by row, runs of kept cells merged; `None` when every cell it touches is kept (it stays whole).
fn kept_pieces(
    corners: &[Corner],
    (lo, hi): (Vec2, Vec2),
    kept: &impl Fn(i64, i64) -> bool,
) -> Option<Vec<Vec<Corner>>> {
    let mut pieces = Vec::new();
    let mut whole = true;
    for j in lo.y.floor() as i64..hi.y.ceil() as i64 {
        let strip = clip(&clip(corners, 1, j as f32, 1.0), 1, (j + 1) as f32, -1.0);
        if strip.len() < 3 {
            continue;
        }
        let (x0, x1) = strip.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), c| {
            (a.min(c.p.x), b.max(c.p.x))
        });
        let (i0, i1) = (x0.floor() as i64, x1.ceil() as i64);
        let mut i = i0;
        while i < i1 {
            if !kept(i, j) {
                whole = false;
                i += 1;
                continue;
            }
            let start = i;
            while i < i1 && kept(i, j) {
                i += 1;
            }
            if start == i0 && i == i1 {
                pieces.push(strip.clone());
            } else {
                let run = clip(&clip(&strip, 0, start as f32, 1.0), 0, i as f32, -1.0);
                if run.len() >= 3 {
                    pieces.push(run);
                }
            }
        }
    }
    (!whole).then_some(pieces)
}

/// Collects polygons as triangle fans, sharing corners that land on the same point.
struct Builder<'a> {
    source: &'a Mesh,
    mesh: Mesh,
    seen: HashMap<([u32; 3], [u32; 2]), u32>,
}

impl<'a> Builder<'a> {
    fn new(source: &'a Mesh) -> Self {
        let mesh = Mesh {
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            tangents: Vec::new(),
            indices: Vec::new(),
        };
        Builder {
            source,
            mesh,
            seen: HashMap::new(),
        }
    }

    fn corner(&mut self, tri: [usize; 3], c: &Corner) -> u32 {
        let s = self.source;
        let w = c.bary / (c.bary.x + c.bary.y + c.bary.z);
        let position = s.positions[tri[0]] * w.x + s.positions[tri[1]] * w.y + s.positions[tri[2]] * w.z;
        let uv = s.uvs[tri[0]] * w.x + s.uvs[tri[1]] * w.y + s.uvs[tri[2]] * w.z;
        let key = (position.to_array().map(f32::to_bits), uv.to_array().map(f32::to_bits));
        if let Some(&i) = self.seen.get(&key) {
            return i;
        }
        let i = self.mesh.positions.len() as u32;
        self.mesh.positions.push(position);
        self.mesh.uvs.push(uv);
        if !s.normals.is_empty() {
            let n = s.normals[tri[0]] * w.x + s.normals[tri[1]] * w.y + s.normals[tri[2]] * w.z;
            let face = (s.positions[tri[1]] - s.positions[tri[0]]).cross(s.positions[tri[2]] - s.positions[tri[0]]);
            self.mesh
                .normals
                .push(n.try_normalize().or(face.try_normalize()).unwrap_or(Vec3::Y));
        }
        self.seen.insert(key, i);
        i
    }

    /// A convex polygon as a fan; corners in the source triangle's winding order.
    fn polygon(&mut self, tri: [usize; 3], poly: &[Corner]) {
        let ids: Vec<u32> = poly.iter().map(|c| self.corner(tri, c)).collect();
        let p = &self.mesh.positions;
        for k in 1..ids.len() - 1 {
            let t = [ids[0], ids[k], ids[k + 1]];
            let [a, b, c] = t.map(|i| p[i as usize]);
            // Clipping leaves slivers where a cell border grazes a corner: no area, no triangle.
            if (b - a).cross(c - a).length_squared() > 0.0 {
                self.mesh.indices.extend_from_slice(&t);
            }
        }
    }
}

/// Which channel of a mask image holds the coverage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Channel {
    /// The alpha channel (a glTF base colour texture).
    Alpha,
    /// The alpha channel where the image has any transparency, else its first (grey) channel:
    /// an OBJ `map_d`, which exporters write either way.
    AlphaOrGrey,
}

/// The coverage mask of an image file, each value times `factor`.
pub fn mask_of_image(path: &std::path::Path, channel: Channel, factor: f32) -> Result<Mask, String> {
    let img = crate::util::image_io::open_image(path)?.to_rgba8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let has_alpha = img.pixels().any(|p| p.0[3] < 255);
    let pick = if channel == Channel::Alpha || has_alpha { 3 } else { 0 };
    let alpha = img.pixels().map(|p| f32::from(p.0[pick]) / 255.0 * factor).collect();
    Mask::new(w, h, alpha).ok_or_else(|| "the image is empty".to_string())
}

/// An emission map told apart into texels that glow and texels that do not.
pub struct EmissionSplit {
    /// 1 on glowing texels, 0 elsewhere.
    pub lit: Mask,
    /// Its complement.
    pub dark: Mask,
    /// The glowing texels' mean linear colour.
    pub mean: Vec3,
    /// The share of the map's summed light on the texels counted dark.
    pub dropped: f32,
}

/// Splits an sRGB emission map at 1% of its brightest texel's luminance: the glowing texels keep
/// their mean colour (so the light they emit in all is kept), the dim rest is dark. JPEG noise
/// around black stays dark instead of spreading a faint glow over the whole part.
pub fn emission_split(path: &std::path::Path) -> Result<EmissionSplit, String> {
    let img = crate::util::image_io::open_image(path)?.to_rgba8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let linear: Vec<Vec3> = img
        .pixels()
        .map(|p| Vec3::from_array([0, 1, 2].map(|c| crate::util::image_io::srgb_decode(p.0[c]))))
        .collect();
    let luminance = |c: &Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let brightest = linear.iter().map(luminance).fold(0.0f32, f32::max);
    let lit: Vec<f32> = linear
        .iter()
        .map(|c| {
            if brightest > 0.0 && luminance(c) >= 0.01 * brightest {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    let count = lit.iter().sum::<f32>().max(1.0);
    let mean = linear.iter().zip(&lit).map(|(c, &l)| *c * l).sum::<Vec3>() / count;
    let total: f32 = linear.iter().map(luminance).sum();
    let kept: f32 = linear.iter().zip(&lit).map(|(c, &l)| luminance(c) * l).sum();
    let dropped = if total > 0.0 { 1.0 - kept / total } else { 0.0 };
    let dark = lit.iter().map(|l| 1.0 - l).collect();
    let empty = || "the image is empty".to_string();
    Ok(EmissionSplit {
        lit: Mask::new(w, h, lit).ok_or_else(empty)?,
        dark: Mask::new(w, h, dark).ok_or_else(empty)?,
        mean,
        dropped,
    })
}
