//! The hemisphere-to-tile mappings of the raster baker and their quadrature weights (digest
//! §1.3–1.4, §3.2 items 1–2). `glsl/prt/mapping.glsl` is the GPU twin of [`project`] and
//! [`unproject`]; the weights are computed here and uploaded.
//!
//! A tile is T×T pixels over the square [−1, 1]²; pixel (i, j) has its centre at
//! `s = −1 + (2i + 1)/T`, `t = −1 + (2j + 1)/T`. Directions are in the vertex camera's frame:
//! x along the tangent, y along the bitangent, z along the normal.

use glam::{DVec2, DVec3};

use super::config::{Mapping, Weights};

/// Where the unit direction `d` (z ≥ 0 in front) lands in the tile square.
pub fn project(mapping: Mapping, d: DVec3) -> DVec2 {
    let d = d.normalize_or_zero();
    match mapping {
        Mapping::Orthographic => DVec2::new(d.x, d.y),
        Mapping::Stereographic => DVec2::new(d.x, d.y) / (1.0 + d.z).max(1e-12),
        Mapping::EqualArea => {
            let r_xy = (d.x * d.x + d.y * d.y).sqrt();
            if r_xy <= 0.0 {
                return DVec2::ZERO;
            }
            DVec2::new(d.x, d.y) / r_xy * (1.0 - d.z).max(0.0).sqrt()
        }
    }
}

/// The direction that lands at `st`, `None` outside the unit disk (no hemisphere direction).
pub fn unproject(mapping: Mapping, st: DVec2) -> Option<DVec3> {
    let r2 = st.length_squared();
    if r2 >= 1.0 {
        return None;
    }
    Some(match mapping {
        Mapping::Orthographic => DVec3::new(st.x, st.y, (1.0 - r2).sqrt()),
        Mapping::Stereographic => {
            let k = 2.0 / (1.0 + r2);
            DVec3::new(st.x * k, st.y * k, (1.0 - r2) / (1.0 + r2))
        }
        Mapping::EqualArea => {
            let k = (2.0 - r2).sqrt();
            DVec3::new(st.x * k, st.y * k, 1.0 - r2)
        }
    })
}

/// [`unproject`], with points outside the disk taken to the horizon in their direction (the
/// legacy weights reach a little past the disk, digest §3.2 item 2).
pub fn unproject_clamped(mapping: Mapping, st: DVec2) -> DVec3 {
    unproject(mapping, st).unwrap_or_else(|| {
        let r = st.length();
        if r > 0.0 {
            DVec3::new(st.x / r, st.y / r, 0.0)
        } else {
            DVec3::Z
        }
    })
}

/// The centre of pixel (i, j) of a T×T tile.
pub fn pixel_center(tile: u32, i: u32, j: u32) -> DVec2 {
    let t = tile as f64;
    DVec2::new(-1.0 + (2.0 * i as f64 + 1.0) / t, -1.0 + (2.0 * j as f64 + 1.0) / t)
}

/// Solid angle per unit tile area at `st` (the mapping's Jacobian): 1/cos θ orthographic,
/// 4/(1 + r²)² stereographic, 2 equal-area.
pub fn solid_angle_density(mapping: Mapping, st: DVec2) -> f64 {
    let r2 = st.length_squared();
    match mapping {
        Mapping::Orthographic => 1.0 / (1.0 - r2).max(1e-12).sqrt(),
        Mapping::Stereographic => 4.0 / ((1.0 + r2) * (1.0 + r2)),
        Mapping::EqualArea => 2.0,
    }
}

/// Listing 2.1: `tex[j·T + i] = (u8)(√(1 − s² − t²)·255)` on the grid `s, t = −1 + 2k/(T − 1)`
/// (both ends included), 0 where `1 − s² − t² < 0`.
pub fn legacy_cosine_texture(tile: u32) -> Vec<u8> {
    let step = 2.0 / (tile as f64 - 1.0).max(1.0);
    let mut out = Vec::with_capacity((tile * tile) as usize);
    for j in 0..tile {
        for i in 0..tile {
            let (s, t) = (-1.0 + step * i as f64, -1.0 + step * j as f64);
            let u = 1.0 - s * s - t * t;
            out.push(if u < 0.0 { 0 } else { (u.sqrt() * 255.0) as u8 });
        }
    }
    out
}

/// Per pixel of a tile, the weight the multiplicative stage multiplies `V · y_i(ω)` by, so that
/// the tile's sum is `∫ V max(0, n·ω) y_i dω`:
/// * `Exact`: ∫ cos θ dω over the pixel's part of the disk (cos θ · Ω_pixel), by a midpoint rule
///   of 8 × 8 points per pixel;
/// * `Legacy`: the 8-bit cosine texture / 255 × 2π / T² (Listing 2.1 and §2.2.4's scale).
pub fn weights(mapping: Mapping, kind: Weights, tile: u32) -> Vec<f32> {
    let area = (2.0 / tile as f64).powi(2);
    match kind {
        Weights::Legacy => {
            let scale = 2.0 * std::f64::consts::PI / (tile * tile) as f64;
            legacy_cosine_texture(tile)
                .into_iter()
                .map(|c| (c as f64 / 255.0 * scale) as f32)
                .collect()
        }
        Weights::Exact => {
            // ∫ cos θ dω over the part of the pixel inside the disk, by a SUB × SUB midpoint rule
            // over the pixel: the rim pixels, partly outside the disk, get their share (at the
            // pixel centre alone the orthographic disk's T00 is 1 % high, digest §3.2).
            const SUB: u32 = 8;
            let sub_area = area / (SUB * SUB) as f64;
            let mut out = Vec::with_capacity((tile * tile) as usize);
            for j in 0..tile {
                for i in 0..tile {
                    let mut w = 0.0;
                    for b in 0..SUB {
                        for a in 0..SUB {
                            let st = pixel_center(tile * SUB, i * SUB + a, j * SUB + b);
                            if let Some(d) = unproject(mapping, st) {
                                w += d.z * solid_angle_density(mapping, st) * sub_area;
                            }
                        }
                    }
                    out.push(w as f32);
                }
            }
            out
        }
    }
}

/// The transfer an unoccluded vertex with normal `n` (world) gets from the tile quadrature, with
/// the tangent frame `(t, b)`: the CPU mirror of the multiplicative and integration stages for
/// V ≡ 1 (digest §3.2's table, test 1).
pub fn unoccluded_transfer(
    mapping: Mapping,
    kind: Weights,
    tile: u32,
    frame: (DVec3, DVec3, DVec3),
    bands: usize,
) -> crate::sh::ShResult<Vec<f64>> {
    crate::sh::check_bands(bands)?;
    let w = weights(mapping, kind, tile);
    let (t, b, n) = frame;
    let dim = bands * bands;
    let mut out = vec![0.0; dim];
    let mut y = vec![0.0; dim];
    for j in 0..tile {
        for i in 0..tile {
            let wk = w[(j * tile + i) as usize] as f64;
            if wk == 0.0 {
                continue;
            }
            let d = unproject_clamped(mapping, pixel_center(tile, i, j));
            let world = t * d.x + b * d.y + n * d.z;
            let sh = DVec3::new(world.x, -world.z, world.y);
            crate::sh::eval_basis_f64(sh, bands, &mut y)?;
            for (o, yi) in out.iter_mut().zip(&y) {
                *o += wk * yi;
            }
        }
    }
    Ok(out)
}

/// Listing 2.3's colour-coded unit sphere as triangles: `SPHERE_THETA` = 16 rings of
/// `SPHERE_PHI` = 32 quads, the φ seam column duplicated (17 × 33 grid vertices), each vertex
/// its world-space direction and colour (φ/2π, θ/π) in the SH frame (θ from world up).
pub fn colour_sphere() -> Vec<[f32; 5]> {
    const PHI: usize = 32;
    const THETA: usize = 16;
    let vertex = |i: usize, j: usize| {
        let (theta, phi) = (
            std::f64::consts::PI * i as f64 / THETA as f64,
            std::f64::consts::TAU * j as f64 / PHI as f64,
        );
        let sh = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        // The SH frame's (x, y, z) is world (x, −z, y).
        [
            sh.x as f32,
            sh.z as f32,
            -sh.y as f32,
            (j as f64 / PHI as f64) as f32,
            (i as f64 / THETA as f64) as f32,
        ]
    };
    let mut out = Vec::with_capacity(THETA * PHI * 6);
    for i in 0..THETA {
        for j in 0..PHI {
            let (a, b, c, d) = (vertex(i, j), vertex(i, j + 1), vertex(i + 1, j + 1), vertex(i + 1, j));
            out.extend([a, b, c, a, c, d]);
        }
    }
    out
}

/// Listing 2.2's basis textures: 4 layers (coefficients 4g … 4g + 3 in RGBA) of 64 × 32 texels,
/// texel (l, k) holding y_i at θ = kπ/31, φ = l·2π/63 (both ends included, as the listing has
/// them), RGBA f32, layer-major, row-major.
pub fn basis_textures() -> Vec<f32> {
    let mut out = Vec::with_capacity(4 * 32 * 64 * 4);
    let mut y = [0.0f64; 16];
    for layer in 0..4 {
        for k in 0..32 {
            for l in 0..64 {
                let (theta, phi) = (
                    std::f64::consts::PI * k as f64 / 31.0,
                    std::f64::consts::TAU * l as f64 / 63.0,
                );
                let sh = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                if crate::sh::eval_basis_f64(sh, 4, &mut y).is_err() {
                    y = [0.0; 16];
                }
                out.extend((0..4).map(|c| y[4 * layer + c] as f32));
            }
        }
    }
    out
}
