//! Drawing the chart: error (log) against GPU time (log), one marker series per method, the
//! Pareto front, the device in the title.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::Chart;
use crate::error::{Error, Result};

/// TrueType fonts looked for, in order (Debian: fonts-dejavu-core, installed by tools/setup.sh).
const FONT_PATHS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

fn register_font() -> Result<()> {
    static FONT: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let bytes = FONT_PATHS.iter().find_map(|p| std::fs::read(p).ok()).ok_or_else(|| {
            format!(
                "chart: no TrueType font found (looked for {}); apt-get install fonts-dejavu-core",
                FONT_PATHS.join(", ")
            )
        })?;
        // plotters keeps fonts for the life of the program.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .map_err(|_| "chart: the font file is not a valid TrueType font".to_string())
    })
    .clone()
    .map_err(Error::Usage)
}

fn plot_err<E: std::fmt::Debug>(e: E) -> Error {
    Error::Internal(format!("chart: drawing failed: {e:?}"))
}

/// Log-axis range covering `values` with some margin; non-positive values are clamped.
fn log_range(values: impl Iterator<Item = f64>, floor: f64) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values {
        let v = v.max(floor);
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return floor..floor * 10.0;
    }
    lo / 2.0..(hi * 2.0).max(lo * 4.0)
}

const COLOURS: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x17, 0xbe, 0xcf),
];

pub fn draw(chart: &Chart, path: &Path) -> Result<()> {
    register_font()?;
    let (w, h) = (1000u32, 700u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        const FLOOR: f64 = 1e-7;
        let x = log_range(chart.rows.iter().map(|r| r.frame_ms), 1e-4);
        let y = log_range(chart.rows.iter().map(|r| r.lighting_metrics().rel_mse), FLOOR);
        let reference = chart.rows.first().map(|r| r.reference.as_str()).unwrap_or("");
        let mut c = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{} — {}×{} — {} — reference: {} — {}",
                    chart.scene,
                    chart.size.0,
                    chart.size.1,
                    chart.device,
                    reference,
                    chart.short_comparison()
                ),
                ("sans-serif", 16),
            )
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x.log_scale(), y.log_scale())
            .map_err(plot_err)?;
        c.configure_mesh()
            .x_desc("GPU time per frame, ms (median of timestamp queries)")
            .y_desc(format!(
                "relative MSE against the reference ({})",
                chart.short_comparison()
            ))
            .label_style(("sans-serif", 14))
            .x_labels(12)
            .y_labels(12)
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .draw()
            .map_err(plot_err)?;
        let mut methods: Vec<&str> = Vec::new();
        for r in &chart.rows {
            if !methods.contains(&r.method.as_str()) {
                methods.push(&r.method);
            }
        }
        for (i, m) in methods.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points: Vec<(f64, f64)> = chart
                .rows
                .iter()
                .filter(|r| r.method == *m)
                .map(|r| (r.frame_ms.max(1e-4), r.lighting_metrics().rel_mse.max(FLOOR)))
                .collect();
            c.draw_series(points.iter().map(|&p| Circle::new(p, 6, colour.filled())))
                .map_err(plot_err)?
                .label(*m)
                .legend(move |(x, y)| Circle::new((x + 10, y), 6, colour.filled()));
            // Each point labelled with its configuration.
            for r in chart.rows.iter().filter(|r| r.method == *m) {
                c.draw_series(std::iter::once(Text::new(
                    r.config.clone(),
                    (r.frame_ms.max(1e-4), r.lighting_metrics().rel_mse.max(FLOOR)),
                    ("sans-serif", 12),
                )))
                .map_err(plot_err)?;
            }
        }
        let front: Vec<(f64, f64)> = chart
            .pareto_front()
            .iter()
            .map(|&i| {
                (
                    chart.rows[i].frame_ms.max(1e-4),
                    chart.rows[i].lighting_metrics().rel_mse.max(FLOOR),
                )
            })
            .collect();
        if front.len() > 1 {
            c.draw_series(LineSeries::new(front, BLACK.stroke_width(2)))
                .map_err(plot_err)?
                .label("Pareto front")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(plot_err)?;
        root.present().map_err(plot_err)?;
    }
    let img =
        image::RgbImage::from_raw(w, h, buf).ok_or_else(|| Error::Internal("chart: bitmap size mismatch".into()))?;
    Ok(crate::util::image_io::save_image(
        path,
        img.into(),
        image::ImageFormat::Png,
    )?)
}

/// Axis text with as many decimals as the value's size needs (log axes span decades, and
/// "1000.000" next to "900.000" overlaps).
fn short_number(v: f64) -> String {
    let a = v.abs();
    if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}
