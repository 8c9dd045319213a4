//! Image-comparison metrics behind `penumbra compare TEST.exr REF.exr [--diff diff.png]`.
//!
//! Two families of numbers are reported, because they answer different questions:
//!
//! * radiance statistics ([`stats`]) on the linear RGB values as rendered, which say how far the
//!   estimate is from the path-traced reference in physical terms (RMSE, relative MSE, bias,
//!   p99 and max of the per-pixel error);
//! * LDR-ꟻLIP (`flip`), which says how visible the difference is on a display after the same
//!   exposure and ACES fit that `penumbra` uses for its PNGs.
//!
//! Only the RGB channels are compared; alpha is ignored everywhere (including the finiteness
//! check), since penumbra's captures carry no meaningful coverage.

pub(crate) mod color;
pub(crate) mod diff;
pub(crate) mod flip;
pub mod stats;

#[cfg(test)]
mod tests;

use crate::util::image_io::HdrImage;

pub use diff::{colorize, diff_image, magma};
pub use flip::{flip_error_map, FlipMap};

/// Viewing conditions of the FLIP defaults: a 0.7 m wide monitor with 3840 pixels across, seen
/// from 0.7 m.
pub const DEFAULT_DISTANCE_M: f32 = 0.7;
pub const DEFAULT_MONITOR_WIDTH_M: f32 = 0.7;
pub const DEFAULT_MONITOR_WIDTH_PX: f32 = 3840.0;

/// Pixels per degree of visual angle for an observer `distance_m` from a monitor `width_m`
/// wide showing `width_px` pixels across (the small-angle form FLIP uses).
pub fn pixels_per_degree(distance_m: f32, width_m: f32, width_px: f32) -> f32 {
    distance_m * (width_px / width_m) * std::f32::consts::PI / 180.0
}

/// ≈ 67.02 pixels per degree.
pub fn default_pixels_per_degree() -> f32 {
    pixels_per_degree(DEFAULT_DISTANCE_M, DEFAULT_MONITOR_WIDTH_M, DEFAULT_MONITOR_WIDTH_PX)
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CompareOptions {
    /// Linear multiplier applied to both images before the ACES fit, as in
    /// `HdrImage::to_display`. Only FLIP depends on it; the radiance statistics do not.
    pub exposure: f32,
    /// Observer's pixels per degree of visual angle; sets the FLIP filter widths.
    pub pixels_per_degree: f32,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            exposure: 1.0,
            pixels_per_degree: default_pixels_per_degree(),
        }
    }
}

/// Which of the two inputs an error is about; its `Display` is the name used in messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Test,
    Reference,
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Role::Test => "test image",
            Role::Reference => "reference",
        })
    }
}

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MetricsError {
    #[error("test image {}x{} and reference {}x{} differ in size", test.0, test.1, reference.0, reference.1)]
    SizeMismatch { test: (u32, u32), reference: (u32, u32) },
    #[error("{role} has a non-finite value at pixel ({x}, {y})")]
    NonFinite { role: Role, x: u32, y: u32 },
    #[error("{role} holds {len} pixels but its size {width}x{height} needs {expected}")]
    BufferSize {
        role: Role,
        width: u32,
        height: u32,
        len: usize,
        expected: usize,
    },
    #[error("images are empty ({width}x{height}): nothing to compare")]
    Empty { width: u32, height: u32 },
    #[error("invalid option: {0}")]
    InvalidOption(String),
}

/// The result of [`compare`]. All radiance statistics are over the RGB channels of linear
/// radiance; see [`stats`] for the exact definitions.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// sqrt(mean over pixels and channels of (t − r)²).
    pub rmse: f64,
    /// mean over pixels and channels of (t − r)² / (r² + 0.01).
    pub rel_mse: f64,
    /// mean over pixels and channels of (t − r); negative when the test image is darker.
    pub mean_bias: f64,
    /// Nearest-rank 99th percentile of the per-pixel error e = (|Δr| + |Δg| + |Δb|) / 3.
    pub p99_abs_error: f64,
    /// Largest per-pixel error e.
    pub max_abs_error: f64,
    /// Mean over pixels of the LDR-ꟻLIP error, in [0, 1].
    pub flip_mean: f64,
    /// Σ t / Σ r over pixels and channels: the global bias as a factor.
    pub mean_ratio: f64,
    /// The relative RMSE left after scaling the test image by its best-fit factor: the error
    /// in shape, apart from the level.
    pub scaled_rel_rmse: f64,
    /// Number of pixels compared (width × height).
    pub pixels: usize,
}

impl Metrics {
    /// One line per metric, names padded to a column, for printing to a terminal.
    pub fn table(&self) -> String {
        let rows: [(&str, String, &str); 9] = [
            ("pixels", self.pixels.to_string(), ""),
            ("RMSE", fmt_value(self.rmse), "sqrt mean (t-r)^2 over RGB"),
            (
                "relative MSE",
                fmt_value(self.rel_mse),
                "mean (t-r)^2/(r^2+0.01) over RGB",
            ),
            ("mean bias", fmt_signed(self.mean_bias), "mean (t-r); < 0: test darker"),
            (
                "p99 abs error",
                fmt_value(self.p99_abs_error),
                "per-pixel mean |t-r| over RGB",
            ),
            (
                "max abs error",
                fmt_value(self.max_abs_error),
                "per-pixel mean |t-r| over RGB",
            ),
            (
                "FLIP mean",
                fmt_value(self.flip_mean),
                "LDR-FLIP, 0 = identical, 1 = worst",
            ),
            (
                "mean ratio",
                fmt_value(self.mean_ratio),
                "mean t / mean r over RGB (global bias)",
            ),
            (
                "scaled rel RMSE",
                fmt_value(self.scaled_rel_rmse),
                "RMSE of s*t - r at the best-fit s, / mean r",
            ),
        ];
        let mut out = String::new();
        for (name, value, note) in rows {
            let line = if note.is_empty() {
                format!("{name:<15} {value}")
            } else {
                format!("{name:<15} {value:<14} {note}")
            };
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out
    }
}

// Fixed-point reads best for the usual range; tiny and huge radiance errors would print as
// 0.000000 or as long digit strings, so they switch to scientific notation.
fn fmt_value(v: f64) -> String {
    if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        format!("{v:.6}")
    } else {
        format!("{v:.4e}")
    }
}

fn fmt_signed(v: f64) -> String {
    if v > 0.0 {
        format!("+{}", fmt_value(v))
    } else {
        fmt_value(v)
    }
}

/// All metrics of `test` against `reference`.
pub fn compare(test: &HdrImage, reference: &HdrImage, opts: &CompareOptions) -> Result<Metrics, MetricsError> {
    compare_with_map(test, reference, opts).map(|(m, _)| m)
}

/// [`compare`], also handing back the per-pixel FLIP map so that a caller writing a difference
/// image (see [`colorize`]) does not run FLIP twice.
pub fn compare_with_map(
    test: &HdrImage,
    reference: &HdrImage,
    opts: &CompareOptions,
) -> Result<(Metrics, FlipMap), MetricsError> {
    validate(test, reference, opts)?;
    let s = stats::radiance_stats(&test.pixels, &reference.pixels);
    let map = flip::flip_map_unchecked(test, reference, opts);
    let metrics = Metrics {
        rmse: s.rmse,
        rel_mse: s.rel_mse,
        mean_bias: s.mean_bias,
        p99_abs_error: s.p99_abs_error,
        max_abs_error: s.max_abs_error,
        flip_mean: map.mean(),
        mean_ratio: s.mean_ratio,
        scaled_rel_rmse: s.scaled_rel_rmse,
        pixels: test.pixels.len(),
    };
    Ok((metrics, map))
}

/// Everything that would make the metrics meaningless or panic is rejected here, once, so the
/// numeric code below can index freely.
pub(crate) fn validate(test: &HdrImage, reference: &HdrImage, opts: &CompareOptions) -> Result<(), MetricsError> {
    if !opts.exposure.is_finite() || opts.exposure < 0.0 {
        return Err(MetricsError::InvalidOption(format!(
            "exposure must be finite and non-negative, got {}",
            opts.exposure
        )));
    }
    // Above ~10⁴ ppd the FLIP kernels would span thousands of pixels; nobody views images so.
    if !opts.pixels_per_degree.is_finite() || opts.pixels_per_degree <= 0.0 || opts.pixels_per_degree > 1.0e4 {
        return Err(MetricsError::InvalidOption(format!(
            "pixels per degree must be in (0, 10000], got {}",
            opts.pixels_per_degree
        )));
    }
    if (test.width, test.height) != (reference.width, reference.height) {
        return Err(MetricsError::SizeMismatch {
            test: (test.width, test.height),
            reference: (reference.width, reference.height),
        });
    }
    for (role, img) in [(Role::Test, test), (Role::Reference, reference)] {
        let expected = img.width as usize * img.height as usize;
        if img.pixels.len() != expected {
            return Err(MetricsError::BufferSize {
                role,
                width: img.width,
                height: img.height,
                len: img.pixels.len(),
                expected,
            });
        }
    }
    if test.pixels.is_empty() {
        return Err(MetricsError::Empty {
            width: test.width,
            height: test.height,
        });
    }
    for (role, img) in [(Role::Test, test), (Role::Reference, reference)] {
        if let Some(i) = img.pixels.iter().position(|p| !p[..3].iter().all(|c| c.is_finite())) {
            let w = img.width as usize;
            return Err(MetricsError::NonFinite {
                role,
                x: (i % w) as u32,
                y: (i / w) as u32,
            });
        }
    }
    Ok(())
}
