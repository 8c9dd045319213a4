//! The speed/accuracy chart as inline SVG, laid out as the PNG is ([`crate::commands::chart::layout`]):
//! each marker a `.point` naming its configuration (the page's script shows the name on hover
//! and click), numbered labels clear of each other, values beyond the bulk at the edge.

use std::fmt::Write as _;

use super::html::escape;
use crate::commands::chart::layout::{layout, short_value, Font, Layout, Rect, Side};
use crate::commands::chart::Chart;

const WIDTH: f64 = 900.0;
const HEIGHT: f64 = 540.0;
const RADIUS: f64 = 6.0;
const PLOT: Rect = Rect {
    x: 80.0,
    y: 16.0,
    w: 800.0,
    h: 460.0,
};

/// Colours of the methods, in the order [`crate::commands::chart::plot::methods`] gives them.
pub fn method_colour(chart: &Chart, method: &str) -> String {
    let methods = crate::commands::chart::plot::methods(chart);
    let i = methods.iter().position(|m| *m == method).unwrap_or(0);
    let c = crate::commands::chart::plot::COLOURS[i % crate::commands::chart::plot::COLOURS.len()];
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

pub fn chart(chart: &Chart) -> String {
    let font = Font {
        char_w: 7.2,
        line_h: 14.0,
    };
    let lay = layout(chart, PLOT, RADIUS, font);
    let mut s = format!(
        "<svg id=\"chart\" viewBox=\"0 0 {WIDTH} {HEIGHT}\" role=\"img\" aria-label=\"relative MSE against GPU time\">\n"
    );
    axes(&mut s, &lay, chart);
    let front: Vec<String> = lay
        .front
        .iter()
        .map(|&i| format!("{:.1},{:.1}", lay.markers[i].x, lay.markers[i].y))
        .collect();
    if front.len() > 1 {
        let _ = writeln!(s, "<polyline class=\"front\" points=\"{}\"/>", front.join(" "));
    }
    markers(&mut s, &lay, chart);
    let _ = writeln!(
        s,
        "<g id=\"chart-tip\" visibility=\"hidden\"><rect rx=\"3\"/><text></text></g>\n</svg>"
    );
    s
}

fn axes(s: &mut String, lay: &Layout, chart: &Chart) {
    let p = lay.plot;
    for (x, t) in &lay.x_ticks {
        let _ = writeln!(
            s,
            "<line class=\"grid\" x1=\"{x:.1}\" y1=\"{}\" x2=\"{x:.1}\" y2=\"{}\"/><text class=\"tick\" x=\"{x:.1}\" y=\"{}\" text-anchor=\"middle\">{t}</text>",
            p.y,
            p.y + p.h,
            p.y + p.h + 16.0
        );
    }
    for (y, t) in &lay.y_ticks {
        let _ = writeln!(
            s,
            "<line class=\"grid\" x1=\"{}\" y1=\"{y:.1}\" x2=\"{}\" y2=\"{y:.1}\"/><text class=\"tick\" x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{t}</text>",
            p.x,
            p.x + p.w,
            p.x - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        s,
        "<rect class=\"frame\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>",
        p.x, p.y, p.w, p.h
    );
    let _ = writeln!(
        s,
        "<text class=\"axis\" x=\"{}\" y=\"{}\" text-anchor=\"middle\">GPU time per frame, ms (log)</text>",
        p.x + p.w / 2.0,
        p.y + p.h + 40.0
    );
    let _ = writeln!(
        s,
        "<text class=\"axis\" transform=\"translate(18 {}) rotate(-90)\" text-anchor=\"middle\">relative MSE, {} (log)</text>",
        p.y + p.h / 2.0,
        escape(&chart.short_comparison())
    );
}

/// A marker's shape: a disc inside the axes, a triangle at the edge pointing to the value.
fn shape(m: &crate::commands::chart::layout::Marker, colour: &str) -> String {
    let r = RADIUS;
    let (dx, dy) = match (m.x_side, m.y_side) {
        (Side::Inside, Side::Inside) => {
            return format!(
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{r}\" fill=\"{colour}\"/>",
                m.x, m.y
            )
        }
        (_, Side::Above) => (0.0, -1.0),
        (_, Side::Below) => (0.0, 1.0),
        (Side::Above, _) => (1.0, 0.0),
        _ => (-1.0, 0.0),
    };
    let pts = [
        (m.x + dx * r, m.y + dy * r),
        (m.x - dy * r - dx * r, m.y - dx * r - dy * r),
        (m.x + dy * r - dx * r, m.y + dx * r - dy * r),
    ];
    let pts: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
    format!("<polygon points=\"{}\" fill=\"{colour}\"/>", pts.join(" "))
}

fn markers(s: &mut String, lay: &Layout, chart: &Chart) {
    for m in &lay.markers {
        let row = &chart.rows[m.row];
        let colour = method_colour(chart, &row.method);
        let e = row.lighting_metrics().rel_mse;
        let summary = format!(
            "{}: {} ms, relative MSE {}",
            row.config,
            short_value(row.frame_ms),
            short_value(e)
        );
        let ring = if m.on_front {
            format!(
                "<circle class=\"ring\" cx=\"{:.1}\" cy=\"{:.1}\" r=\"{}\"/>",
                m.x,
                m.y,
                RADIUS + 3.0
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "<g class=\"point\" data-row=\"{}\" data-name=\"{}\" data-summary=\"{}\" tabindex=\"0\">{ring}{}<title>{}</title></g>",
            m.row,
            escape(&row.config),
            escape(&summary),
            shape(m, &colour),
            escape(&summary)
        );
        if let Some(b) = m.label_box {
            if m.leader {
                let _ = writeln!(
                    s,
                    "<line class=\"leader\" x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\"/>",
                    m.x,
                    m.y,
                    b.x + b.w / 2.0,
                    b.y + b.h / 2.0
                );
            }
            let _ = writeln!(
                s,
                "<text class=\"label\" data-row=\"{}\" x=\"{:.1}\" y=\"{:.1}\">{}</text>",
                m.row,
                b.x + 1.0,
                b.y + b.h - 3.0,
                escape(&m.label)
            );
        }
    }
}
