//! Supersampling a method's image to the reference's pixel footprint (`--supersample N` on
//! `capture` and `chart`): the render size it needs, refused before anything is allocated, and
//! the box filter back down. Its own module so that `capture` and `chart` both use it without
//! depending on each other.

use crate::error::Result;
use crate::util::image_io::HdrImage;

/// The most `--supersample` may be.
pub const MAX_SUPERSAMPLE: u32 = 16;
/// The most pixels a supersampled render may have (4096², 256 MiB of RGBA32F read back).
pub const MAX_SUPERSAMPLED_PIXELS: u64 = 1 << 24;
/// The most pixels per side (as `--size`).
pub const MAX_SUPERSAMPLED_SIDE: u64 = 16384;

/// The size `--supersample n` renders at for an image of `size`, or why it is refused (before
/// anything is allocated): n from 1 to [`MAX_SUPERSAMPLE`], at most [`MAX_SUPERSAMPLED_SIDE`]
/// pixels a side and [`MAX_SUPERSAMPLED_PIXELS`] in all.
pub fn supersampled_size(size: (u32, u32), n: u32) -> Result<(u32, u32)> {
    use crate::error::Error;
    if n == 0 || n > MAX_SUPERSAMPLE {
        return Err(Error::Usage(format!(
            "--supersample {n}: expected a factor from 1 to {MAX_SUPERSAMPLE}"
        )));
    }
    let (w, h) = (size.0 as u64 * n as u64, size.1 as u64 * n as u64);
    if w > MAX_SUPERSAMPLED_SIDE || h > MAX_SUPERSAMPLED_SIDE || w * h > MAX_SUPERSAMPLED_PIXELS {
        return Err(Error::Usage(format!(
            "--supersample {n} at {}x{} renders {w}x{h} ({} pixels); the limit is {MAX_SUPERSAMPLED_SIDE} a side and {MAX_SUPERSAMPLED_PIXELS} pixels (4096x4096) in all",
            size.0,
            size.1,
            w * h
        )));
    }
    Ok((w as u32, h as u32))
}

/// Each n × n block of `image` averaged into one pixel (all four channels): the image a
/// renderer sampling the n² sub-pixel centres of each pixel and a box filter gives. The
/// image's sides must be multiples of n.
pub fn box_filter(image: &HdrImage, n: u32) -> Result<HdrImage> {
    if n == 0 || !image.width.is_multiple_of(n) || !image.height.is_multiple_of(n) {
        return Err(crate::error::Error::Internal(format!(
            "box filter: {}x{} is not a whole number of {n}x{n} blocks",
            image.width, image.height
        )));
    }
    let (w, h) = (image.width / n, image.height / n);
    let mut out = HdrImage::new(w, h);
    let scale = 1.0 / (n as f64 * n as f64);
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0f64; 4];
            for sy in 0..n {
                let row = ((y * n + sy) * image.width + x * n) as usize;
                for p in &image.pixels[row..row + n as usize] {
                    for c in 0..4 {
                        sum[c] += p[c] as f64;
                    }
                }
            }
            out.pixels[(y * w + x) as usize] = sum.map(|v| (v * scale) as f32);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6×4 image of distinct values, box-filtered by 2 and by 1, against each block's average
    /// written out pixel by pixel.
    #[test]
    fn box_filter_is_the_average_of_each_block() {
        let mut img = HdrImage::new(6, 4);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            let v = i as f32;
            *p = [v, 2.0 * v + 1.0, v * v, 1.0 - 0.1 * v];
        }
        let down = box_filter(&img, 2).unwrap();
        assert_eq!((down.width, down.height), (3, 2));
        for y in 0..2u32 {
            for x in 0..3u32 {
                let block = [
                    img.get(2 * x, 2 * y),
                    img.get(2 * x + 1, 2 * y),
                    img.get(2 * x, 2 * y + 1),
                    img.get(2 * x + 1, 2 * y + 1),
                ];
                let got = down.get(x, y);
                for c in 0..4 {
                    let want = block.iter().map(|p| p[c] as f64).sum::<f64>() / 4.0;
                    assert!(
                        (got[c] as f64 - want).abs() <= 1e-6 * want.abs().max(1.0),
                        "pixel ({x},{y}) channel {c}: {} vs {want}",
                        got[c]
                    );
                }
            }
        }
        assert_eq!(box_filter(&img, 1).unwrap(), img);
        let whole = box_filter(
            &HdrImage {
                width: 2,
                height: 2,
                pixels: vec![[1.0; 4], [2.0; 4], [3.0; 4], [6.0; 4]],
            },
            2,
        )
        .unwrap();
        assert_eq!(whole.pixels, vec![[3.0; 4]]);
        assert!(box_filter(&img, 4).is_err(), "6x4 is not a whole number of 4x4 blocks");
    }

    #[test]
    fn large_supersampling_is_refused_before_anything_is_allocated() {
        assert_eq!(supersampled_size((128, 128), 4).unwrap(), (512, 512));
        assert_eq!(supersampled_size((4096, 4096), 1).unwrap(), (4096, 4096));
        for (size, n) in [
            ((640, 360), 16),
            ((4096, 4096), 2),
            ((16384, 1), 2),
            ((8, 8), 0),
            ((8, 8), 17),
        ] {
            let e = supersampled_size(size, n).unwrap_err().to_string();
            assert!(
                e.contains("--supersample") && e.contains("limit") || e.contains("from 1 to"),
                "{size:?} x{n}: {e}"
            );
        }
    }
}
