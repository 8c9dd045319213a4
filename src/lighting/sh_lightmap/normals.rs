//! Normal-mapped transfer (the Ca3D-Engine thesis §5.7, digest §1.7): each patch takes the mean of K random
//! normal-map samples inside its square, rotated from tangent to world space; CaSHL then uses it
//! for every cosine (with the plane normal as a second cut-off) and blocks shoot along their
//! patches' renormalised mean. Nothing changes in the renderer: it is baked into the transfer.

use glam::{DVec2, DVec3};

use crate::lighting::lightmap::patches::{self, Patches, Triangle};

/// A normal map's texels, decoded to tangent-space unit vectors (x toward +u, y toward the
/// bitangent, z along the surface normal), row-major from the top.
pub struct NormalImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<DVec3>,
}

impl NormalImage {
    /// From 8-bit RGB, decoded as the raster methods decode their normal maps: `2·c/255 − 1`.
    pub fn from_rgb8(width: usize, height: usize, rgb: &[u8]) -> NormalImage {
        let texels = rgb
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) / 255.0 * 2.0 - DVec3::ONE)
            .collect();
        NormalImage { width, height, texels }
    }

    /// Nearest texel at `uv`, repeating (as the scene's sampler does).
    pub fn at(&self, uv: DVec2) -> DVec3 {
        let x = ((uv.x - uv.x.floor()) * self.width as f64) as usize;
        let y = ((uv.y - uv.y.floor()) * self.height as f64) as usize;
        self.texels[y.min(self.height - 1) * self.width + x.min(self.width - 1)]
    }
}

/// Per triangle: its mesh uvs and its material's normal map (if any).
pub struct Surfaces<'a> {
    pub uvs: &'a [[[f32; 2]; 3]],
    pub maps: Vec<Option<&'a NormalImage>>,
}

/// Sets each inside patch's normal to the mean of `samples` normal-map samples at random points
/// of its square that lie on its chart's triangles (patches without a map keep the plane's).
/// Returns how many patches were perturbed.
pub fn perturb(p: &mut Patches, triangles: &[Triangle], surfaces: &Surfaces<'_>, samples: usize) -> usize {
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut random = move || {
        rng ^= rng >> 12;
        rng ^= rng << 25;
        rng ^= rng >> 27;
        (rng.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut changed = 0;
    for c in 0..p.charts.len() {
        let chart = p.charts[c].clone();
        if chart.sky || !chart.triangles.iter().any(|&t| surfaces.maps[t].is_some()) {
            continue;
        }
        let flat = |q: DVec3| DVec2::new((q - chart.origin).dot(chart.u), (q - chart.origin).dot(chart.v));
        let tris2d: Vec<[DVec2; 3]> = chart.triangles.iter().map(|&t| triangles[t].p.map(flat)).collect();
        for j in 0..chart.height {
            for i in 0..chart.width {
                let k = chart.first + j * chart.width + i;
                if !p.patches[k].inside() {
                    continue;
                }
                let mut sum = DVec3::ZERO;
                for _ in 0..samples {
                    let q = DVec2::new(i as f64 + random(), j as f64 + random()) * p.size;
                    let Some(slot) = tris2d.iter().position(|t| patches::inside_triangle(q, t)) else {
                        continue;
                    };
                    let t = chart.triangles[slot];
                    // A curved chart's triangles each have their own normal; a planar one's
                    // all have the plane's.
                    let n = if chart.curved {
                        triangles[t].normal()
                    } else {
                        chart.normal
                    };
                    if let Some(map) = surfaces.maps[t] {
                        sum += world_normal(&triangles[t], n, surfaces.uvs[t], &tris2d[slot], q, map);
                    } else {
                        sum += n;
                    }
                }
                // A mean that does not face out of the surface would shade nothing: keep the plane's.
                if let Some(n) = sum.try_normalize().filter(|n| n.dot(chart.normal) > 0.0) {
                    p.patches[k].normal = n;
                    changed += 1;
                }
            }
        }
    }
    changed
}

/// The map's normal at `q` (chart coordinates) on triangle `t`, in world space.
fn world_normal(t: &Triangle, n: DVec3, uv: [[f32; 2]; 3], flat: &[DVec2; 3], q: DVec2, map: &NormalImage) -> DVec3 {
    let uv = uv.map(|c| DVec2::new(c[0] as f64, c[1] as f64));
    let (e1, e2) = (flat[1] - flat[0], flat[2] - flat[0]);
    let det = e1.perp_dot(e2);
    let (b1, b2) = if det.abs() > 0.0 {
        ((q - flat[0]).perp_dot(e2) / det, e1.perp_dot(q - flat[0]) / det)
    } else {
        (0.0, 0.0)
    };
    let at = uv[0] + (uv[1] - uv[0]) * b1 + (uv[2] - uv[0]) * b2;
    let m = map.at(at);
    // The tangent toward +u and the bitangent's sign, from the triangle's uv derivatives (as the
    // mesh loader's tangents: b = cross(n, t)·sign).
    let (dp1, dp2) = (t.p[1] - t.p[0], t.p[2] - t.p[0]);
    let (du1, du2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let r = du1.x * du2.y - du2.x * du1.y;
    if r == 0.0 {
        return n;
    }
    let dpdu = (dp1 * du2.y - dp2 * du1.y) / r;
    let dpdv = (dp2 * du1.x - dp1 * du2.x) / r;
    let Some(tangent) = (dpdu - n * n.dot(dpdu)).try_normalize() else {
        return n;
    };
    let sign = if n.cross(tangent).dot(dpdv) < 0.0 { -1.0 } else { 1.0 };
    let bitangent = n.cross(tangent) * sign;
    tangent * m.x + bitangent * m.y + n * m.z
}
