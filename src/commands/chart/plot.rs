//! Drawing the chart as a PNG: error (log) against GPU time (log), numbered markers coloured by
//! method with a table naming each number, the Pareto front, the device in the title.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::layout::{layout, Font, Layout, Rect, Side};
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

pub(crate) const COLOURS: [RGBColor; 8] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x17, 0xbe, 0xcf),
];

/// The methods in the order they first appear; a row's colour is its method's index.
pub(crate) fn methods(chart: &Chart) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for r in &chart.rows {
        if !out.contains(&r.method.as_str()) {
            out.push(&r.method);
        }
    }
    out
}

const SIZE: (u32, u32) = (1600, 820);
const RADIUS: f64 = 6.0;
const PLOT: Rect = Rect {
    x: 100.0,
    y: 60.0,
    w: 850.0,
    h: 670.0,
};
/// The legend table's left edge and line height.
const TABLE_X: i32 = 975;
const LINE: i32 = 15;

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn px(x: f64, y: f64) -> (i32, i32) {
    (x.round() as i32, y.round() as i32)
}

/// Error (log) against GPU time (log): numbered markers coloured by method, labels placed
/// clear of each other, values beyond the bulk of the data at the axis edge with their number,
/// the Pareto front as a line, and a table naming every number.
pub fn draw(chart: &Chart, path: &Path) -> Result<()> {
    register_font()?;
    let (w, h) = SIZE;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let font = Font {
            char_w: 7.5,
            line_h: 14.0,
        };
        let lay = layout(chart, PLOT, RADIUS, font);
        draw_axes(&root, chart, &lay)?;
        draw_marks(&root, chart, &lay)?;
        draw_table(&root, chart, &lay)?;
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

fn draw_axes(root: &Area, chart: &Chart, lay: &Layout) -> Result<()> {
    let p = lay.plot;
    let mut references: Vec<&str> = Vec::new();
    for r in &chart.rows {
        if !references.contains(&r.reference.as_str()) {
            references.push(&r.reference);
        }
    }
    let reference = references.join("; ");
    let title = format!(
        "{} \u{2014} {}\u{d7}{} \u{2014} {} \u{2014} reference: {}",
        chart.scene, chart.size.0, chart.size.1, chart.device, reference
    );
    root.draw(&Text::new(title, (20, 12), ("sans-serif", 16).into_font()))
        .map_err(plot_err)?;
    let grid = RGBColor(0xdd, 0xdd, 0xdd);
    let small = ("sans-serif", 13).into_font();
    for (x, t) in &lay.x_ticks {
        root.draw(&PathElement::new(vec![px(*x, p.y), px(*x, p.y + p.h)], grid))
            .map_err(plot_err)?;
        let tw = (t.len() as f64 * 7.0 / 2.0) as i32;
        root.draw(&Text::new(
            t.clone(),
            (x.round() as i32 - tw, (p.y + p.h) as i32 + 6),
            small.clone(),
        ))
        .map_err(plot_err)?;
    }
    for (y, t) in &lay.y_ticks {
        root.draw(&PathElement::new(vec![px(p.x, *y), px(p.x + p.w, *y)], grid))
            .map_err(plot_err)?;
        let tw = (t.len() as f64 * 7.0) as i32;
        root.draw(&Text::new(
            t.clone(),
            (p.x as i32 - 8 - tw, y.round() as i32 - 7),
            small.clone(),
        ))
        .map_err(plot_err)?;
    }
    root.draw(&Rectangle::new([px(p.x, p.y), px(p.x + p.w, p.y + p.h)], BLACK))
        .map_err(plot_err)?;
    let x_title = "GPU time per frame, ms (median of timestamp queries; log)";
    root.draw(&Text::new(
        x_title,
        (p.x as i32 + 200, (p.y + p.h) as i32 + 30),
        ("sans-serif", 14).into_font(),
    ))
    .map_err(plot_err)?;
    let y_title = format!(
        "relative MSE against the reference (log) \u{2014} {}",
        chart.short_comparison()
    );
    let rotated = ("sans-serif", 14).into_font().transform(FontTransform::Rotate270);
    root.draw(&Text::new(y_title, (22, (p.y + p.h) as i32 - 60), rotated))
        .map_err(plot_err)
}

fn draw_marks(root: &Area, chart: &Chart, lay: &Layout) -> Result<()> {
    let front: Vec<(i32, i32)> = lay
        .front
        .iter()
        .map(|&i| px(lay.markers[i].x, lay.markers[i].y))
        .collect();
    if front.len() > 1 {
        root.draw(&PathElement::new(front, BLACK.stroke_width(2)))
            .map_err(plot_err)?;
    }
    let methods = methods(chart);
    for m in &lay.markers {
        let colour = COLOURS[methods.iter().position(|x| *x == chart.rows[m.row].method).unwrap_or(0) % COLOURS.len()];
        let (x, y) = px(m.x, m.y);
        let r = RADIUS as i32;
        if m.x_side == Side::Inside && m.y_side == Side::Inside {
            root.draw(&Circle::new((x, y), r, colour.filled())).map_err(plot_err)?;
        } else {
            // Off an axis: a triangle at the edge pointing the way the value lies.
            let (dx, dy) = match (m.x_side, m.y_side) {
                (_, Side::Above) => (0, -1),
                (_, Side::Below) => (0, 1),
                (Side::Above, _) => (1, 0),
                _ => (-1, 0),
            };
            let tip = (x + dx * r, y + dy * r);
            let base = [
                (x - dy * r - dx * r, y - dx * r - dy * r),
                (x + dy * r - dx * r, y + dx * r - dy * r),
            ];
            root.draw(&Polygon::new(vec![tip, base[0], base[1]], colour.filled()))
                .map_err(plot_err)?;
        }
        if m.on_front {
            root.draw(&Circle::new((x, y), r + 3, BLACK.stroke_width(1)))
                .map_err(plot_err)?;
        }
        if let Some(b) = m.label_box {
            if m.leader {
                let (cx, cy) = (b.x + b.w / 2.0, b.y + b.h / 2.0);
                let grey = RGBColor(0x88, 0x88, 0x88);
                root.draw(&PathElement::new(vec![(x, y), px(cx, cy)], grey))
                    .map_err(plot_err)?;
                root.draw(&Rectangle::new(
                    [px(b.x, b.y), px(b.x + b.w, b.y + b.h)],
                    WHITE.filled(),
                ))
                .map_err(plot_err)?;
            }
            root.draw(&Text::new(
                m.label.clone(),
                px(b.x + 1.0, b.y),
                ("sans-serif", 13).into_font(),
            ))
            .map_err(plot_err)?;
        }
    }
    Ok(())
}

/// The legend: each method's colour, the front's line, then one line per marker number.
fn draw_table(root: &Area, chart: &Chart, lay: &Layout) -> Result<()> {
    let font = ("sans-serif", 12).into_font();
    let mut y = PLOT.y as i32;
    for (i, m) in methods(chart).iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        root.draw(&Circle::new((TABLE_X + 6, y + 7), 5, colour.filled()))
            .map_err(plot_err)?;
        root.draw(&Text::new(m.to_string(), (TABLE_X + 18, y), font.clone()))
            .map_err(plot_err)?;
        y += LINE;
    }
    root.draw(&PathElement::new(
        vec![(TABLE_X, y + 7), (TABLE_X + 14, y + 7)],
        BLACK.stroke_width(2),
    ))
    .map_err(plot_err)?;
    let front_text = "Pareto front (ringed): nothing both faster and more accurate";
    root.draw(&Text::new(front_text, (TABLE_X + 18, y), font.clone()))
        .map_err(plot_err)?;
    y += LINE + 6;
    let header = "  #     ms      rel MSE   configuration";
    root.draw(&Text::new(header, (TABLE_X, y), font.clone()))
        .map_err(plot_err)?;
    y += LINE;
    let last_line = SIZE.1 as i32 - 2 * LINE;
    for (i, r) in chart.rows.iter().enumerate() {
        if y > last_line {
            let more = format!("\u{2026} {} more in the CSV", chart.rows.len() - i);
            root.draw(&Text::new(more, (TABLE_X, y), font.clone()))
                .map_err(plot_err)?;
            break;
        }
        let star = if lay.front.contains(&i) { "*" } else { " " };
        let cells = [
            format!("{star}{}", i + 1),
            short_number(r.frame_ms),
            format!("{:.2e}", r.lighting_metrics().rel_mse),
            truncated(&r.config, 64),
        ];
        for (text, dx) in cells.into_iter().zip([0, 30, 90, 160]) {
            root.draw(&Text::new(text, (TABLE_X + dx, y), font.clone()))
                .map_err(plot_err)?;
        }
        y += LINE;
    }
    Ok(())
}

/// `text` cut to `n` characters, with an ellipsis when cut.
fn truncated(text: &str, n: usize) -> String {
    if text.chars().count() <= n {
        return text.to_string();
    }
    text.chars().take(n - 1).chain(std::iter::once('\u{2026}')).collect()
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
