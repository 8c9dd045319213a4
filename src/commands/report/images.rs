//! The report's pictures: tone-mapped PNGs with their EXRs, and false-colour error maps.

use std::path::Path;

use crate::commands::chart::ChartRun;
use crate::error::{Error, Result};
use crate::metrics::{self, magma, stats::REL_MSE_EPSILON, CompareOptions};
use crate::util::image_io::HdrImage;

/// The relative-error map's colour scale: log10 of the error from [`REL_LOG_LO`] (black) to
/// [`REL_LOG_HI`] (pale yellow), i.e. 1 % to 1,000 %.
pub const REL_LOG_LO: f64 = -2.0;
pub const REL_LOG_HI: f64 = 1.0;

/// One picture's files, relative to the report's directory.
#[derive(Clone, Debug)]
pub struct Picture {
    pub png: String,
    pub exr: String,
}

/// A configuration's files.
#[derive(Clone, Debug)]
pub struct RowFiles {
    pub image: Picture,
    pub flip: String,
    pub rel: String,
}

pub struct Files {
    /// One per reference of the chart.
    pub references: Vec<Picture>,
    /// One per row.
    pub rows: Vec<RowFiles>,
}

/// A pixel's relative error: the root of the mean over channels of (t − r)² / (r² + ε), the
/// per-pixel term of the chart's relative MSE.
pub fn relative_error(t: [f32; 4], r: [f32; 4]) -> f64 {
    let sum: f64 = (0..3)
        .map(|c| {
            let (t, r) = (t[c] as f64, r[c] as f64);
            (t - r).powi(2) / (r * r + REL_MSE_EPSILON)
        })
        .sum();
    (sum / 3.0).sqrt()
}

/// The relative error in false colour (magma over log10 from [`REL_LOG_LO`] to [`REL_LOG_HI`]).
pub fn relative_error_map(test: &HdrImage, reference: &HdrImage) -> image::RgbaImage {
    let mut out = image::RgbaImage::new(test.width, test.height);
    for ((o, t), r) in out.pixels_mut().zip(&test.pixels).zip(&reference.pixels) {
        let e = relative_error(*t, *r).max(1e-30).log10();
        let [cr, cg, cb] = magma(((e - REL_LOG_LO) / (REL_LOG_HI - REL_LOG_LO)) as f32);
        *o = image::Rgba([cr, cg, cb, 255]);
    }
    out
}

fn save(image: image::RgbaImage, path: &Path) -> Result<()> {
    Ok(crate::util::image_io::save_image(
        path,
        image.into(),
        image::ImageFormat::Png,
    )?)
}

fn picture(image: &HdrImage, dir: &Path, stem: &str, name: &str) -> Result<Picture> {
    image.write_png(&dir.join(format!("{name}.png")), 1.0)?;
    image.write_exr(&dir.join(format!("{name}.exr")))?;
    Ok(Picture {
        png: format!("{stem}/{name}.png"),
        exr: format!("{stem}/{name}.exr"),
    })
}

/// Writes every reference and every row's image, FLIP map and relative-error map into `dir`
/// (the report's `stem` folder).
pub fn write_all(run: &ChartRun, dir: &Path, stem: &str) -> Result<Files> {
    let mut references = Vec::new();
    for (i, r) in run.references.iter().enumerate() {
        references.push(picture(&r.image.mean, dir, stem, &format!("reference{i}"))?);
    }
    let mut rows = Vec::new();
    for (i, image) in run.images.iter().enumerate() {
        let reference = &run.references[run.reference_of[i]].image.mean;
        let name = format!("config{:02}", i + 1);
        let (_, flip) = metrics::compare_with_map(image, reference, &CompareOptions::default())
            .map_err(|e| Error::Usage(format!("report: {}: {e}", run.chart.rows[i].config)))?;
        let (flip_path, rel_path) = (format!("{name}-flip.png"), format!("{name}-rel.png"));
        save(metrics::colorize(&flip), &dir.join(&flip_path))?;
        save(relative_error_map(image, reference), &dir.join(&rel_path))?;
        rows.push(RowFiles {
            image: picture(image, dir, stem, &name)?,
            flip: format!("{stem}/{flip_path}"),
            rel: format!("{stem}/{rel_path}"),
        });
    }
    Ok(Files { references, rows })
}

/// A CSS gradient through magma, for the maps' scale bars.
pub fn magma_gradient() -> String {
    let stops: Vec<String> = (0..=8)
        .map(|i| {
            let [r, g, b] = magma(i as f32 / 8.0);
            format!("rgb({r},{g},{b}) {}%", i * 100 / 8)
        })
        .collect();
    format!("linear-gradient(to right, {})", stops.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_is_the_per_pixel_term_of_the_relative_mse() {
        let (t, r) = ([1.5, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.0]);
        let expected = (0.25 / 1.01 / 3.0f64).sqrt();
        assert!((relative_error(t, r) - expected).abs() < 1e-12);
        let (mut a, mut b) = (HdrImage::new(2, 1), HdrImage::new(2, 1));
        a.pixels = vec![[1.0; 4], [20.0, 20.0, 20.0, 1.0]];
        b.pixels = vec![[1.0; 4], [1.0; 4]];
        let map = relative_error_map(&a, &b);
        assert_eq!(map.get_pixel(0, 0).0[..3], magma(0.0), "exact: the scale's low end");
        assert_eq!(map.get_pixel(1, 0).0[..3], magma(1.0), "1,900 %: beyond the high end");
    }
}
