//! The light-map atlas: charts shelf-packed with one-texel gaps, each patch's texel, and each
//! triangle corner's light-map coordinate.

use glam::DVec3;

use super::patches::{Patches, Triangle};

/// Where each chart lies in the atlas: its texel offset, and the atlas size.
#[derive(Clone, Debug)]
pub struct Atlas {
    pub width: u32,
    pub height: u32,
    pub offsets: Vec<(u32, u32)>,
}

/// Shelf packing, tallest first, one empty texel between charts (bilinear filtering must not
/// reach a neighbour: the Ca3D-Engine thesis §3.3.6).
pub fn pack(p: &Patches) -> Atlas {
    let area: usize = p.charts.iter().map(|c| (c.width + 1) * (c.height + 1)).sum();
    let widest = p.charts.iter().map(|c| c.width + 1).max().unwrap_or(1);
    let width = ((area as f64).sqrt().ceil() as usize).max(widest).next_power_of_two() as u32;
    let mut order: Vec<usize> = (0..p.charts.len()).collect();
    order.sort_by_key(|&c| (std::cmp::Reverse(p.charts[c].height), c));
    let mut offsets = vec![(0, 0); p.charts.len()];
    let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
    for c in order {
        let (w, h) = (p.charts[c].width as u32 + 1, p.charts[c].height as u32 + 1);
        if x + w > width {
            x = 0;
            y += shelf;
            shelf = 0;
        }
        offsets[c] = (x, y);
        x += w;
        shelf = shelf.max(h);
    }
    Atlas {
        width,
        height: (y + shelf).max(1),
        offsets,
    }
}

/// The light-map texels (RGBA32F, row-major): each patch's value (after the border passes,
/// [`super::border`]) at its texel.
pub fn texels(p: &Patches, atlas: &Atlas, value: impl Fn(usize) -> DVec3) -> Vec<[f32; 4]> {
    let mut out = vec![[0.0f32; 4]; (atlas.width * atlas.height) as usize];
    for (ci, c) in p.charts.iter().enumerate() {
        let (ox, oy) = atlas.offsets[ci];
        for j in 0..c.height {
            for i in 0..c.width {
                let v = value(c.first + j * c.width + i);
                out[((oy + j as u32) * atlas.width + ox + i as u32) as usize] =
                    [v.x as f32, v.y as f32, v.z as f32, 1.0];
            }
        }
    }
    out
}

/// Texels in [0, 1] as R8G8B8A8_UNORM bytes (alpha 255).
pub fn to_rgb8(texels: &[f32]) -> Vec<u8> {
    texels
        .chunks_exact(4)
        .flat_map(|t| {
            [t[0], t[1], t[2]]
                .map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8)
                .into_iter()
                .chain([255])
        })
        .collect()
}

/// Each triangle corner's light-map coordinate in the atlas (3 per triangle); a sky chart's
/// triangles all read the centre of its one black texel.
pub fn triangle_uvs(triangles: &[Triangle], p: &Patches, atlas: &Atlas) -> Vec<[f32; 2]> {
    let mut uv = vec![[0.0f32; 2]; 3 * triangles.len()];
    for (ci, c) in p.charts.iter().enumerate() {
        let (ox, oy) = atlas.offsets[ci];
        for &t in &c.triangles {
            for (k, q) in triangles[t].p.iter().enumerate() {
                let (s, r) = if c.sky {
                    (ox as f64 + 0.5, oy as f64 + 0.5)
                } else {
                    let d = *q - c.origin;
                    (d.dot(c.u) / p.size + ox as f64, d.dot(c.v) / p.size + oy as f64)
                };
                uv[3 * t + k] = [(s / atlas.width as f64) as f32, (r / atlas.height as f64) as f32];
            }
        }
    }
    uv
}
