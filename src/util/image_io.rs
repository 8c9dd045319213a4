//! Writing and reading captures: EXR holds linear radiance exactly as rendered (no exposure, no
//! clamping); PNG holds the display image (exposure, the ACES fit of `glsl/common/tonemap.glsl`,
//! sRGB encoding).

use std::path::Path;

/// A linear RGBA float image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    #[error("{path}: {message}")]
    Io { path: String, message: String },
}

/// The most pixels on a side of any image penumbra reads (textures, height images,
/// environments; also the largest `--size`).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The most memory one decoded image may take (a 16384² RGBA32F image is 4 GiB).
const MAX_DECODE_BYTES: u64 = 4 << 30;

/// The format and size of an image file from its header alone: a format penumbra reads (PNG,
/// OpenEXR, Radiance HDR), and at most [`MAX_IMAGE_SIDE`] on a side. The message names no file.
pub fn image_header(path: &Path) -> Result<(image::ImageFormat, u32, u32), String> {
    let reader = image::ImageReader::open(path)
        .map_err(|e| format!("cannot read: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read: {e}"))?;
    let Some(format) = reader.format().filter(|f| {
        matches!(
            f,
            image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::OpenExr | image::ImageFormat::Hdr
        )
    }) else {
        return Err("not an image penumbra reads (PNG, JPEG, OpenEXR or Radiance HDR)".into());
    };
    let (w, h) = reader.into_dimensions().map_err(describe_image_error)?;
    if w == 0 || h == 0 {
        return Err(format!("the header says {w}×{h} pixels"));
    }
    if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(format!(
            "the header says {w}×{h} pixels; penumbra reads images of at most {MAX_IMAGE_SIDE} on a side"
        ));
    }
    Ok((format, w, h))
}

/// Decodes an image file after checking its header ([`image_header`]). A failure is one line
/// without the decoder's internals, naming no file (the caller says which file and field).
pub fn open_image(path: &Path) -> Result<image::DynamicImage, String> {
    image_header(path)?;
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| format!("cannot read: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read: {e}"))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_DECODE_BYTES);
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    reader.limits(limits);
    reader.decode().map_err(describe_image_error)
}

fn format_name(f: image::ImageFormat) -> &'static str {
    match f {
        image::ImageFormat::Png => "a PNG image",
        image::ImageFormat::Hdr => "a Radiance HDR image",
        image::ImageFormat::OpenExr => "an OpenEXR image",
        _ => "another image format",
    }
}

/// One line for a decoding failure: what is wrong, without Debug dumps of decoder state.
fn describe_image_error(e: image::ImageError) -> String {
    use image::ImageError;
    let text = match &e {
        ImageError::Decoding(d) => {
            let format: &str = match d.format_hint() {
                image::error::ImageFormatHint::Exact(image::ImageFormat::Png) => "PNG",
                image::error::ImageFormatHint::Exact(image::ImageFormat::OpenExr) => "OpenEXR",
                image::error::ImageFormatHint::Exact(image::ImageFormat::Hdr) => "Radiance HDR",
                _ => "image",
            };
            let why = std::error::Error::source(d)
                .map(|s| s.to_string())
                .unwrap_or_else(|| d.to_string());
            format!("corrupt or truncated {format} data: {why}")
        }
        ImageError::Limits(_) => format!("too large to decode (more than {} GiB)", MAX_DECODE_BYTES >> 30),
        ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "truncated: the file ends early".into()
        }
        other => other.to_string(),
    };
    without_debug_dumps(&text)
}

/// Removes `Name { … }` groups (Rust Debug output some decoders put in their messages), keeping
/// a `type: X` inside one as X; folds the text onto one line.
fn without_debug_dumps(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(open) = rest.find('{') {
        let Some(close) = rest[open..].find('}').map(|c| open + c) else {
            break;
        };
        let before = &rest[..open];
        // Drop the type name in front of the braces too.
        let kept = before.trim_end().rsplit_once(' ').map_or("", |(k, _)| k);
        out.push_str(kept);
        if let Some(t) = rest[open + 1..close].trim().strip_prefix("type:") {
            out.push(' ');
            out.push_str(t.split(',').next().unwrap_or("").trim());
        }
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    let one_line = out.split_whitespace().collect::<Vec<_>>().join(" ");
    one_line.trim_end_matches('.').to_string()
}

/// Writes `bytes` to `path` so that no reader, and no crash, ever sees a partial file there: the
/// bytes go to a hidden `.NAME.partial-PID` file in the same folder, are synced, and the file is
/// renamed over `path` (atomic on one filesystem). On failure the partial file is removed and
/// `path` keeps what it held before. Captures, references, the chart and its cache are written
/// through here.
///
/// Fault injection for tests: `PENUMBRA_FAULT_ABORT_WRITE=N` aborts the process halfway
/// through the N-th file written (1 = the first).
pub fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    use std::sync::atomic::{AtomicUsize, Ordering};
    static WRITES: AtomicUsize = AtomicUsize::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let partial = path.with_file_name(format!(".{name}.partial-{}", std::process::id()));
    let abort_at: Option<usize> = std::env::var("PENUMBRA_FAULT_ABORT_WRITE")
        .ok()
        .and_then(|v| v.parse().ok());
    let nth = WRITES.fetch_add(1, Ordering::SeqCst) + 1;
    let result = (|| {
        let mut f = std::fs::File::create(&partial)?;
        if abort_at == Some(nth) {
            f.write_all(&bytes[..bytes.len() / 2])?;
            f.sync_all()?;
            std::process::abort();
        }
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&partial, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    result
}

/// Encodes `image` in `format` in memory and writes it with [`write_file`].
pub fn save_image(path: &Path, image: image::DynamicImage, format: image::ImageFormat) -> Result<(), ImageIoError> {
    let err = |message: String| ImageIoError::Io {
        path: path.display().to_string(),
        message,
    };
    let mut out = std::io::Cursor::new(Vec::new());
    image.write_to(&mut out, format).map_err(|e| err(e.to_string()))?;
    write_file(path, out.get_ref()).map_err(|e| err(e.to_string()))
}

impl HdrImage {
    pub fn new(width: u32, height: u32) -> Self {
        HdrImage {
            width,
            height,
            pixels: vec![[0.0; 4]; (width * height) as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// From tightly packed RGBA32F bytes as read back from the GPU.
    pub fn from_rgba32f_bytes(width: u32, height: u32, bytes: &[u8]) -> Option<Self> {
        if bytes.len() != (width * height * 16) as usize {
            return None;
        }
        let pixels = bytes
            .chunks_exact(16)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                [f(0), f(4), f(8), f(12)]
            })
            .collect();
        Some(HdrImage { width, height, pixels })
    }

    pub fn write_exr(&self, path: &Path) -> Result<(), ImageIoError> {
        let raw: Vec<f32> = self.pixels.iter().flat_map(|p| *p).collect();
        let img = image::Rgba32FImage::from_raw(self.width, self.height, raw).ok_or_else(|| ImageIoError::Io {
            path: path.display().to_string(),
            message: "pixel buffer does not match the size".into(),
        })?;
        save_image(path, img.into(), image::ImageFormat::OpenExr)
    }

    /// Reads an OpenEXR image (linear radiance). Any other format is refused: an 8-bit PNG holds
    /// display values, and reading it as radiance would compare the wrong quantities.
    pub fn read_exr(path: &Path) -> Result<Self, ImageIoError> {
        let err = |message: String| ImageIoError::Io {
            path: path.display().to_string(),
            message,
        };
        let (format, _, _) = image_header(path).map_err(err)?;
        if format != image::ImageFormat::OpenExr {
            return Err(err(format!("is {}, not OpenEXR: linear radiance is read from EXR files only (a PNG holds tone-mapped display values)", format_name(format))));
        }
        let img = open_image(path).map_err(err)?;
        let rgba = img.to_rgba32f();
        Ok(HdrImage {
            width: rgba.width(),
            height: rgba.height(),
            pixels: rgba.pixels().map(|p| p.0).collect(),
        })
    }

    /// The display image as 8-bit sRGB.
    pub fn to_display(&self, exposure: f32) -> image::RgbaImage {
        let mut out = image::RgbaImage::new(self.width, self.height);
        for (o, p) in out.pixels_mut().zip(&self.pixels) {
            let c = [0, 1, 2].map(|i| (srgb_encode(aces_fit(p[i] * exposure)) * 255.0 + 0.5).clamp(0.0, 255.0) as u8);
            *o = image::Rgba([c[0], c[1], c[2], 255]);
        }
        out
    }

    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<(), ImageIoError> {
        save_image(path, self.to_display(exposure).into(), image::ImageFormat::Png)
    }
}

/// Narkowicz's fit of the ACES filmic curve (same constants as the GLSL).
pub fn aces_fit(x: f32) -> f32 {
    let x = x.max(0.0);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The sRGB transfer function (linear → encoded).
pub fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The sRGB transfer function's inverse, exactly as an `_SRGB` format decodes a byte.
pub fn srgb_decode(byte: u8) -> f32 {
    let c = byte as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact() {
        let mut img = HdrImage::new(3, 2);
        img.pixels[0] = [1e-6, 123.5, 7.25, 1.0];
        img.pixels[5] = [65504.0, 0.1, 3.0, 1.0];
        let dir = crate::util::test_files::TestDir::new("io");
        let p = dir.join("round-trip.exr");
        img.write_exr(&p).unwrap();
        let back = HdrImage::read_exr(&p).unwrap();
        assert_eq!(back, img);
    }

    #[test]
    fn display_curve_known_values() {
        assert_eq!(aces_fit(0.0), 0.0);
        assert!((aces_fit(1.0) - 0.8038).abs() < 1e-3);
        assert_eq!(aces_fit(1e6), 1.0);
        assert!((srgb_encode(0.5) - 0.7354).abs() < 1e-3);
        let mut img = HdrImage::new(1, 1);
        img.pixels[0] = [0.0, 1.0, 100.0, 1.0];
        let d = img.to_display(1.0);
        assert_eq!(d.get_pixel(0, 0).0, [0, 232, 255, 255]);
    }
}
