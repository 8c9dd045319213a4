//! Procedurally generated material maps for `scenes/bsp_rooms.toml`: albedo (sRGB), tangent-
//! space normal (OpenGL convention, from a height field) and specular maps, deterministic, so
//! the PNGs under `scenes/textures/` can be checked against this generator.

use glam::Vec3;
use image::{Rgba, RgbaImage};

/// Every generated map: file name (under `scenes/textures/`) and its image.
pub fn all(size: u32) -> Vec<(&'static str, RgbaImage)> {
    vec![
        ("bricks_albedo.png", bricks(size).0),
        ("bricks_normal.png", normal_from_height(&bricks(size).1, 3.0)),
        ("bricks_specular.png", bricks(size).2),
        ("tiles_albedo.png", tiles(size).0),
        ("tiles_normal.png", normal_from_height(&tiles(size).1, 2.0)),
        ("plaster_albedo.png", plaster(size)),
        ("brushed_specular.png", brushed(size)),
    ]
}

/// The size of the checked-in maps.
pub const SIZE: u32 = 128;

/// A small integer hash, uniform in [0, 1).
fn hash(x: u32, y: u32, seed: u32) -> f32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0x00ff_ffff) as f32 / 16_777_216.0
}

/// Smooth value noise with `cells` cells per side, tiling.
fn noise(x: f32, y: f32, cells: u32, seed: u32) -> f32 {
    let (fx, fy) = (x * cells as f32, y * cells as f32);
    let (ix, iy) = (fx.floor() as i64, fy.floor() as i64);
    let (tx, ty) = (fx - ix as f32, fy - iy as f32);
    let s = |t: f32| t * t * (3.0 - 2.0 * t);
    let at = |i: i64, j: i64| {
        hash(
            i.rem_euclid(cells as i64) as u32,
            j.rem_euclid(cells as i64) as u32,
            seed,
        )
    };
    let a = at(ix, iy) + (at(ix + 1, iy) - at(ix, iy)) * s(tx);
    let b = at(ix, iy + 1) + (at(ix + 1, iy + 1) - at(ix, iy + 1)) * s(tx);
    a + (b - a) * s(ty)
}

fn srgb_encode(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

fn colour_pixel(c: Vec3) -> Rgba<u8> {
    Rgba([srgb_encode(c.x), srgb_encode(c.y), srgb_encode(c.z), 255])
}

fn grey_pixel(v: f32) -> Rgba<u8> {
    let b = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    Rgba([b, b, b, 255])
}

/// Running-bond bricks, 8 per row and 16 rows per tile: (albedo, height in [0, 1], specular).
fn bricks(size: u32) -> (RgbaImage, Vec<f32>, RgbaImage) {
    let mut albedo = RgbaImage::new(size, size);
    let mut specular = RgbaImage::new(size, size);
    let mut height = vec![0.0; (size * size) as usize];
    let (cols, rows) = (8.0, 16.0);
    for y in 0..size {
        for x in 0..size {
            let (u, v) = ((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
            let row = (v * rows).floor();
            let shift = if row as u32 % 2 == 1 { 0.5 } else { 0.0 };
            let col = (u * cols + shift).floor();
            let (fu, fv) = ((u * cols + shift).fract(), (v * rows).fract());
            // Distance to the mortar, in brick-height units.
            let edge = (fu.min(1.0 - fu) * 2.0).min(fv.min(1.0 - fv));
            let mortar = 0.08;
            let h = ((edge - mortar) / 0.08).clamp(0.0, 1.0);
            let grain = noise(u, v, 32, 7);
            let tint = hash(col as u32 % 8, row as u32, 3);
            let brick = Vec3::new(0.45 + 0.15 * tint, 0.18 + 0.06 * tint, 0.12 + 0.04 * tint) * (0.85 + 0.3 * grain);
            let mortar_c = Vec3::splat(0.55 + 0.1 * grain);
            albedo.put_pixel(x, y, colour_pixel(mortar_c.lerp(brick, h)));
            specular.put_pixel(x, y, grey_pixel(0.05 + 0.3 * h * grain));
            height[(y * size + x) as usize] = h * (0.9 + 0.1 * grain);
        }
    }
    (albedo, height, specular)
}

/// Square floor tiles, 4 per side, with grout: (albedo, height).
fn tiles(size: u32) -> (RgbaImage, Vec<f32>) {
    let mut albedo = RgbaImage::new(size, size);
    let mut height = vec![0.0; (size * size) as usize];
    let n = 4.0;
    for y in 0..size {
        for x in 0..size {
            let (u, v) = ((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
            let (fu, fv) = ((u * n).fract(), (v * n).fract());
            let edge = fu.min(1.0 - fu).min(fv.min(1.0 - fv));
            let h = ((edge - 0.03) / 0.04).clamp(0.0, 1.0);
            let checker = ((u * n).floor() + (v * n).floor()) as u32 % 2;
            let grain = noise(u, v, 16, 11);
            let tile = if checker == 0 {
                Vec3::new(0.62, 0.6, 0.55)
            } else {
                Vec3::new(0.25, 0.27, 0.3)
            } * (0.9 + 0.2 * grain);
            albedo.put_pixel(x, y, colour_pixel(Vec3::splat(0.15).lerp(tile, h)));
            height[(y * size + x) as usize] = h;
        }
    }
    (albedo, height)
}

/// Ceiling plaster: low-contrast noise.
fn plaster(size: u32) -> RgbaImage {
    RgbaImage::from_fn(size, size, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
        let g = 0.5 * noise(u, v, 8, 5) + 0.3 * noise(u, v, 32, 6) + 0.2 * noise(u, v, 64, 9);
        colour_pixel(Vec3::new(0.7, 0.68, 0.62) * (0.85 + 0.2 * g))
    })
}

/// Brushed-metal specular streaks (along u).
fn brushed(size: u32) -> RgbaImage {
    RgbaImage::from_fn(size, size, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / size as f32, (y as f32 + 0.5) / size as f32);
        grey_pixel(0.4 + 0.5 * noise(u * 0.125, v, 64, 13))
    })
}

/// A tangent-space normal map (OpenGL convention: green toward −v, "up" in the image) of a
/// tiling height field: n = normalize(−s·∂h/∂u, s·∂h/∂v, 1), with ∂ per texel.
pub fn normal_from_height(height: &[f32], strength: f32) -> RgbaImage {
    let size = (height.len() as f64).sqrt() as u32;
    let h = |x: i64, y: i64| height[(y.rem_euclid(size as i64) * size as i64 + x.rem_euclid(size as i64)) as usize];
    RgbaImage::from_fn(size, size, |x, y| {
        let (x, y) = (x as i64, y as i64);
        let dx = 0.5 * (h(x + 1, y) - h(x - 1, y));
        let dy = 0.5 * (h(x, y + 1) - h(x, y - 1));
        let n = Vec3::new(-strength * dx, strength * dy, 1.0).normalize();
        let enc = |c: f32| ((c * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        Rgba([enc(n.x), enc(n.y), enc(n.z), 255])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The checked-in PNGs are this generator's output. `PENUMBRA_WRITE_MAPS=1` rewrites them.
    #[test]
    fn checked_in_maps_match_the_generator() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textures");
        let write = std::env::var("PENUMBRA_WRITE_MAPS").is_ok_and(|v| v == "1");
        for (name, img) in all(SIZE) {
            let path = dir.join(name);
            if write {
                std::fs::create_dir_all(&dir).unwrap();
                img.save(&path).unwrap();
            }
            let on_disk = image::open(&path)
                .unwrap_or_else(|e| panic!("{}: {e} (PENUMBRA_WRITE_MAPS=1 writes it)", path.display()))
                .to_rgba8();
            assert!(
                on_disk == img,
                "{}: differs from the generator (PENUMBRA_WRITE_MAPS=1 rewrites it)",
                path.display()
            );
        }
    }

    #[test]
    fn normal_maps_are_unit_and_flat_where_the_height_is() {
        let flat = normal_from_height(&vec![0.5; 16 * 16], 3.0);
        assert!(flat.pixels().all(|p| p.0 == [128, 128, 255, 255]));
        let ramp: Vec<f32> = (0..16 * 16).map(|i| (i % 16) as f32 / 16.0).collect();
        // Rising to the right (+u): the normal leans to −u (red below 128), except at the wrap.
        let n = normal_from_height(&ramp, 3.0);
        assert!(n.get_pixel(5, 5).0[0] < 128 && n.get_pixel(5, 5).0[1] == 128);
    }
}
