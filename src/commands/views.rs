//! The ways a method's image is shown beside its reference: the method, the reference, a split
//! with a divider, a false-colour error map over the method, and the difference. The demo and
//! `capture --view` compose them with the same code, so a script can check what the window shows.

use crate::error::{Error, Result};
use crate::metrics::{magma, CompareOptions};
use crate::util::image_io::HdrImage;

/// What is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    #[default]
    Method,
    Reference,
    /// The method left of the divider, the reference right of it.
    Split,
    /// The per-pixel error in false colour over a grey copy of the method.
    Error,
    /// Method minus reference: red where the method is brighter, blue where darker.
    Difference,
}

impl View {
    pub const ALL: [View; 5] = [
        View::Method,
        View::Reference,
        View::Split,
        View::Error,
        View::Difference,
    ];

    pub fn name(self) -> &'static str {
        match self {
            View::Method => "method",
            View::Reference => "reference",
            View::Split => "split",
            View::Error => "error",
            View::Difference => "difference",
        }
    }

    pub fn parse(s: &str) -> Result<View> {
        View::ALL.into_iter().find(|v| v.name() == s).ok_or_else(|| {
            Error::Usage(format!(
                "unknown view `{s}`: expected method, reference, split, error or difference"
            ))
        })
    }
}

/// The per-pixel error the error view maps to colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ErrorMap {
    /// sqrt of the pixel's relative squared error, as the relative MSE weighs it:
    /// mean over RGB of (t − r)² / (r² + 0.01).
    #[default]
    Relative,
    /// NVIDIA's FLIP on the tone-mapped pair, in [0, 1].
    Flip,
}

/// How a view is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewSettings {
    pub view: View,
    pub exposure: f32,
    /// The divider's position as a fraction of the width (split view).
    pub split: f32,
    pub error_map: ErrorMap,
    /// The error drawn at the top of the colour scale (error view); the difference view's
    /// full red or blue is this much radiance times the reference's mean.
    pub scale: f32,
}

impl Default for ViewSettings {
    fn default() -> Self {
        ViewSettings {
            view: View::Method,
            exposure: 1.0,
            split: 0.5,
            error_map: ErrorMap::Relative,
            scale: 1.0,
        }
    }
}

/// A composed view: what is displayed (8-bit sRGB) and the linear values it shows (radiance for
/// the method, reference and split views; the error or the signed difference otherwise).
pub struct Composed {
    pub display: image::RgbaImage,
    pub values: HdrImage,
}

/// The height in pixels of the error view's colour bar along the bottom edge.
pub const SCALE_BAR_HEIGHT: u32 = 4;

/// Composes `settings.view` of `method` against `reference` (which every view but the method's
/// needs, at the same size).
pub fn compose(method: &HdrImage, reference: Option<&HdrImage>, settings: &ViewSettings) -> Result<Composed> {
    let exposure = settings.exposure;
    let reference = || -> Result<&HdrImage> {
        let r =
            reference.ok_or_else(|| Error::Usage(format!("the {} view needs a reference", settings.view.name())))?;
        if (method.width, method.height) != (r.width, r.height) {
            return Err(Error::Usage(format!(
                "the method is {}x{} and the reference {}x{}",
                method.width, method.height, r.width, r.height
            )));
        }
        Ok(r)
    };
    Ok(match settings.view {
        View::Method => Composed {
            display: method.to_display(exposure),
            values: method.clone(),
        },
        View::Reference => {
            let r = reference()?;
            Composed {
                display: r.to_display(exposure),
                values: r.clone(),
            }
        }
        View::Split => split(method, reference()?, settings),
        View::Error => error_view(method, reference()?, settings)?,
        View::Difference => difference(method, reference()?, settings),
    })
}

fn split(method: &HdrImage, reference: &HdrImage, settings: &ViewSettings) -> Composed {
    let divider = (settings.split.clamp(0.0, 1.0) * method.width as f32).round() as u32;
    let mut values = method.clone();
    for (i, p) in values.pixels.iter_mut().enumerate() {
        if (i as u32 % method.width) >= divider {
            *p = reference.pixels[i];
        }
    }
    let mut display = values.to_display(settings.exposure);
    if divider < method.width {
        for y in 0..method.height {
            display.put_pixel(divider, y, image::Rgba([255, 255, 255, 255]));
        }
    }
    Composed { display, values }
}

/// Per-pixel error values of `method` against `reference` under `map`.
pub fn error_values(method: &HdrImage, reference: &HdrImage, map: ErrorMap, exposure: f32) -> Result<Vec<f32>> {
    Ok(match map {
        ErrorMap::Relative => {
            let eps = crate::metrics::stats::REL_MSE_EPSILON;
            method
                .pixels
                .iter()
                .zip(&reference.pixels)
                .map(|(t, r)| {
                    let sum: f64 = (0..3)
                        .map(|c| (t[c] as f64 - r[c] as f64).powi(2) / ((r[c] as f64).powi(2) + eps))
                        .sum();
                    (sum / 3.0).sqrt() as f32
                })
                .collect()
        }
        ErrorMap::Flip => {
            let opts = CompareOptions {
                exposure,
                ..CompareOptions::default()
            };
            crate::metrics::flip::flip_error_map(method, reference, &opts)
                .map_err(|e| Error::Usage(e.to_string()))?
                .values
        }
    })
}

fn error_view(method: &HdrImage, reference: &HdrImage, settings: &ViewSettings) -> Result<Composed> {
    let errors = error_values(method, reference, settings.error_map, settings.exposure)?;
    let grey = method.to_display(settings.exposure);
    let scale = settings.scale.max(1e-6);
    let (w, h) = (method.width, method.height);
    let mut display = image::RgbaImage::new(w, h);
    let mut values = HdrImage::new(w, h);
    for (i, (o, e)) in display.pixels_mut().zip(&errors).enumerate() {
        let g = grey.as_raw()[i * 4..i * 4 + 3].iter().map(|&c| c as f32).sum::<f32>() / 3.0;
        let c = magma((e / scale).clamp(0.0, 1.0));
        // The colour carries the error; a faint copy of the method keeps the picture readable.
        let mix = |c: u8| (0.25 * g + 0.75 * c as f32).round().clamp(0.0, 255.0) as u8;
        *o = image::Rgba([mix(c[0]), mix(c[1]), mix(c[2]), 255]);
        values.pixels[i] = [*e, *e, *e, 1.0];
    }
    // The colour scale, 0 at the left to `scale` at the right, along the bottom edge.
    for y in h.saturating_sub(SCALE_BAR_HEIGHT)..h {
        for x in 0..w {
            let c = magma(x as f32 / (w.max(2) - 1) as f32);
            display.put_pixel(x, y, image::Rgba([c[0], c[1], c[2], 255]));
        }
    }
    Ok(Composed { display, values })
}

fn difference(method: &HdrImage, reference: &HdrImage, settings: &ViewSettings) -> Composed {
    let n = (3 * reference.pixels.len().max(1)) as f64;
    let mean = reference
        .pixels
        .iter()
        .map(|p| (p[0] + p[1] + p[2]) as f64)
        .sum::<f64>()
        / n;
    let full = (settings.scale as f64 * mean.max(1e-6)) as f32;
    let (w, h) = (method.width, method.height);
    let mut display = image::RgbaImage::new(w, h);
    let mut values = HdrImage::new(w, h);
    for (i, o) in display.pixels_mut().enumerate() {
        let (t, r) = (method.pixels[i], reference.pixels[i]);
        let d = [t[0] - r[0], t[1] - r[1], t[2] - r[2]];
        values.pixels[i] = [d[0], d[1], d[2], 1.0];
        let s = ((d[0] + d[1] + d[2]) / 3.0 / full).clamp(-1.0, 1.0);
        let a = (s.abs() * 255.0).round() as u8;
        *o = if s >= 0.0 {
            image::Rgba([a, 0, 0, 255])
        } else {
            image::Rgba([0, 0, a, 255])
        };
    }
    Composed { display, values }
}

/// Writes a composed view as `png` (what is displayed) and its linear values as the EXR beside it.
pub fn save(composed: &Composed, png: &std::path::Path) -> Result<std::path::PathBuf> {
    crate::util::image_io::save_image(png, composed.display.clone().into(), image::ImageFormat::Png)?;
    let exr = png.with_extension("exr");
    composed.values.write_exr(&exr)?;
    Ok(exr)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(w: u32, h: u32, v: f32) -> HdrImage {
        let mut i = HdrImage::new(w, h);
        i.pixels.iter_mut().for_each(|p| *p = [v, v, v, 1.0]);
        i
    }

    #[test]
    fn relative_error_is_the_relative_mse_per_pixel() {
        let (t, r) = (flat(2, 1, 0.6), flat(2, 1, 0.5));
        let e = error_values(&t, &r, ErrorMap::Relative, 1.0).unwrap();
        let expected = (0.01f64 / (0.25 + 0.01)).sqrt() as f32;
        assert!((e[0] - expected).abs() < 1e-6, "{} vs {expected}", e[0]);
    }

    #[test]
    fn split_takes_the_reference_right_of_the_divider() {
        let (t, r) = (flat(4, 1, 1.0), flat(4, 1, 2.0));
        let s = ViewSettings {
            view: View::Split,
            split: 0.5,
            ..ViewSettings::default()
        };
        let c = compose(&t, Some(&r), &s).unwrap();
        let v: Vec<f32> = c.values.pixels.iter().map(|p| p[0]).collect();
        assert_eq!(v, [1.0, 1.0, 2.0, 2.0]);
        assert_eq!(c.display.get_pixel(2, 0).0, [255, 255, 255, 255], "the divider");
    }

    #[test]
    fn difference_is_signed() {
        let (t, r) = (flat(1, 1, 1.0), flat(1, 1, 0.5));
        let s = ViewSettings {
            view: View::Difference,
            ..ViewSettings::default()
        };
        let c = compose(&t, Some(&r), &s).unwrap();
        assert_eq!(c.values.pixels[0][0], 0.5);
        assert_eq!(c.display.get_pixel(0, 0).0, [255, 0, 0, 255]);
        let c = compose(&r, Some(&t), &s).unwrap();
        assert_eq!(c.display.get_pixel(0, 0).0[2], 128);
    }
}
