//! False-colour difference images of the per-pixel FLIP error.
//!
//! The colour map is matplotlib's *magma* (perceptually uniform, ordered dark to light, and
//! readable in greyscale and by colour-blind viewers), the map ꟻLIP's own tool uses: 0 (no
//! visible difference) is near-black, 0.5 magenta-red, 1 (the largest difference) pale
//! yellow. The table below holds 17 of magma's 256 entries (indices 0, 16, …, 240, 255,
//! already sRGB-encoded); values in between are interpolated linearly in sRGB, which stays
//! within about 1/255 of the full table.

use super::flip::FlipMap;
use super::{CompareOptions, MetricsError};
use crate::util::image_io::HdrImage;

/// (position in [0, 1], sRGB colour) knots of magma: entry i of the 256-entry map sits at i/255.
const MAGMA: [(f32, [f32; 3]); 17] = [
    (0.0 / 255.0, [0.001462, 0.000466, 0.013866]),
    (16.0 / 255.0, [0.039608, 0.031090, 0.133515]),
    (32.0 / 255.0, [0.113094, 0.065492, 0.276784]),
    (48.0 / 255.0, [0.211718, 0.061992, 0.418647]),
    (64.0 / 255.0, [0.316654, 0.071690, 0.485380]),
    (80.0 / 255.0, [0.414709, 0.110431, 0.504662]),
    (96.0 / 255.0, [0.512831, 0.148179, 0.507648]),
    (112.0 / 255.0, [0.613617, 0.181811, 0.498536]),
    (128.0 / 255.0, [0.716387, 0.214982, 0.475290]),
    (144.0 / 255.0, [0.816914, 0.255895, 0.436461]),
    (160.0 / 255.0, [0.904281, 0.319610, 0.388137]),
    (176.0 / 255.0, [0.960949, 0.418323, 0.359630]),
    (192.0 / 255.0, [0.986700, 0.535582, 0.382210]),
    (208.0 / 255.0, [0.996096, 0.653659, 0.446213]),
    (224.0 / 255.0, [0.996898, 0.769591, 0.534892]),
    (240.0 / 255.0, [0.992440, 0.884330, 0.640099]),
    (1.0, [0.987053, 0.991438, 0.749504]),
];

/// Magma colour of `v`, clamped to [0, 1] (NaN maps to 0), as 8-bit sRGB.
pub fn magma(v: f32) -> [u8; 3] {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    // The first knot whose position is ≥ v ends the segment holding v.
    let hi = MAGMA
        .iter()
        .position(|(p, _)| *p >= v)
        .unwrap_or(MAGMA.len() - 1)
        .max(1);
    let (p0, c0) = MAGMA[hi - 1];
    let (p1, c1) = MAGMA[hi];
    let t = ((v - p0) / (p1 - p0)).clamp(0.0, 1.0);
    [0, 1, 2].map(|i| ((c0[i] + (c1[i] - c0[i]) * t) * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
}

/// The FLIP map in magma colours, opaque.
pub fn colorize(map: &FlipMap) -> image::RgbaImage {
    let mut out = image::RgbaImage::new(map.width, map.height);
    for (o, &v) in out.pixels_mut().zip(&map.values) {
        let [r, g, b] = magma(v);
        *o = image::Rgba([r, g, b, 255]);
    }
    out
}

/// The false-colour FLIP difference image of `test` against `reference`. Fails on the same
/// inputs as `compare`; use `compare_with_map` + [`colorize`] to get metrics and image from
/// one FLIP evaluation.
pub fn diff_image(
    test: &HdrImage,
    reference: &HdrImage,
    opts: &CompareOptions,
) -> Result<image::RgbaImage, MetricsError> {
    super::flip::flip_error_map(test, reference, opts).map(|m| colorize(&m))
}
