//! Where the chart's marks go, in pixels, shared by the PNG and the report's SVG: log axes whose
//! range comes from the bulk of the data (values outside it are drawn at the edge with their
//! number), and labels placed so that none overlaps another label or a marker.

use super::Chart;

/// A rectangle in pixels (y down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl Rect {
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.x + o.w && o.x < self.x + self.w && self.y < o.y + o.h && o.y < self.y + self.h
    }

    fn contains(&self, o: &Rect) -> bool {
        o.x >= self.x && o.y >= self.y && o.x + o.w <= self.x + self.w && o.y + o.h <= self.y + self.h
    }
}

/// A log axis over [10^lo, 10^hi].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogAxis {
    pub lo: f64,
    pub hi: f64,
}

/// Where a value sits against its axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Inside,
    Below,
    Above,
}

/// The `q` quantile (0–1) of sorted values, interpolated linearly.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let (i, t) = (pos.floor() as usize, pos.fract());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    sorted[i] + (next - sorted[i]) * t
}

impl LogAxis {
    /// The range of the bulk of `values` (positive and finite ones): within Tukey's fences on
    /// the logarithms, the quartiles ± 1.5 interquartile ranges (at least half a decade), so one
    /// outlier decades away does not squeeze the rest; padded a little, and a decade wide at least.
    pub fn robust(values: impl Iterator<Item = f64>) -> LogAxis {
        let mut logs: Vec<f64> = values.filter(|v| v.is_finite() && *v > 0.0).map(f64::log10).collect();
        if logs.is_empty() {
            return LogAxis { lo: -1.0, hi: 0.0 };
        }
        logs.sort_by(f64::total_cmp);
        let (q1, q3) = (quantile(&logs, 0.25), quantile(&logs, 0.75));
        let fence = (1.5 * (q3 - q1)).max(0.5);
        let lo = logs.iter().copied().find(|&l| l >= q1 - fence).unwrap_or(q1);
        let hi = logs.iter().rev().copied().find(|&l| l <= q3 + fence).unwrap_or(q3);
        let pad = 0.08 * (hi - lo).max(1.0);
        let (mut lo, mut hi) = (lo - pad, hi + pad);
        if hi - lo < 1.0 {
            let mid = 0.5 * (lo + hi);
            (lo, hi) = (mid - 0.5, mid + 0.5);
        }
        LogAxis { lo, hi }
    }

    /// The position of `v` from 0 (low end) to 1 (high end), clamped, and where it is. Zero and
    /// negative values are below any log axis; NaN is treated as above.
    pub fn place(&self, v: f64) -> (f64, Side) {
        if v.is_nan() {
            return (1.0, Side::Above);
        }
        if v <= 0.0 {
            return (0.0, Side::Below);
        }
        let t = (v.log10() - self.lo) / (self.hi - self.lo);
        if t < 0.0 {
            (0.0, Side::Below)
        } else if t > 1.0 {
            (1.0, Side::Above)
        } else {
            (t, Side::Inside)
        }
    }

    /// Tick values: every decade, with 2 and 5 in between when the axis spans few decades.
    pub fn ticks(&self) -> Vec<f64> {
        let steps: &[f64] = if self.hi - self.lo <= 2.5 {
            &[1.0, 2.0, 5.0]
        } else {
            &[1.0]
        };
        let mut out = Vec::new();
        for decade in self.lo.floor() as i32..=self.hi.ceil() as i32 {
            for s in steps {
                let v = s * 10f64.powi(decade);
                let l = v.log10();
                if l >= self.lo - 1e-9 && l <= self.hi + 1e-9 {
                    out.push(v);
                }
            }
        }
        out
    }
}

/// A value in a few characters: `0.35`, `12.5`, `3.1e-4`.
pub fn short_value(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() {
        format!("{v}")
    } else if a == 0.0 {
        "0".into()
    } else if !(1e-2..1e4).contains(&a) {
        format!("{v:.1e}")
    } else if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

/// One configuration's marker.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    pub row: usize,
    pub x: f64,
    pub y: f64,
    pub x_side: Side,
    pub y_side: Side,
    /// The marker's number (1-based row) and, off an axis, the value drawn at its edge.
    pub label: String,
    /// Where the label is drawn; None when no free place was found (the table and the
    /// tooltip still name it).
    pub label_box: Option<Rect>,
    /// Whether the label is far enough from its marker to need a line to it.
    pub leader: bool,
    pub on_front: bool,
}

/// Everything drawn inside and along the plot area.
#[derive(Clone, Debug)]
pub struct Layout {
    pub plot: Rect,
    pub x_axis: LogAxis,
    pub y_axis: LogAxis,
    /// (pixel position, text).
    pub x_ticks: Vec<(f64, String)>,
    pub y_ticks: Vec<(f64, String)>,
    pub markers: Vec<Marker>,
    /// The Pareto front's markers, fastest first.
    pub front: Vec<usize>,
}

/// Text metrics the placement assumes: a character's width and a line's height, in pixels.
#[derive(Clone, Copy, Debug)]
pub struct Font {
    pub char_w: f64,
    pub line_h: f64,
}

/// The chart's marks in `plot`, markers of radius `radius`.
pub fn layout(chart: &Chart, plot: Rect, radius: f64, font: Font) -> Layout {
    let x_axis = LogAxis::robust(chart.rows.iter().map(|r| r.frame_ms));
    let y_axis = LogAxis::robust(chart.rows.iter().map(|r| r.lighting_metrics().rel_mse));
    let front = chart.pareto_front();
    let mut markers: Vec<Marker> = chart
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let (e, ms) = (r.lighting_metrics().rel_mse, r.frame_ms);
            let (tx, x_side) = x_axis.place(ms);
            let (ty, y_side) = y_axis.place(e);
            let mut label = (i + 1).to_string();
            if x_side != Side::Inside {
                label += &format!(" ({} ms)", short_value(ms));
            }
            if y_side != Side::Inside {
                label += &format!(" ({})", short_value(e));
            }
            Marker {
                row: i,
                x: plot.x + tx * plot.w,
                y: plot.y + (1.0 - ty) * plot.h,
                x_side,
                y_side,
                label,
                label_box: None,
                leader: false,
                on_front: front.contains(&i),
            }
        })
        .collect();
    place_labels(&mut markers, plot, radius, font);
    let ticks = |axis: &LogAxis, horizontal: bool| -> Vec<(f64, String)> {
        axis.ticks()
            .into_iter()
            .map(|v| {
                let t = axis.place(v).0;
                let p = if horizontal {
                    plot.x + t * plot.w
                } else {
                    plot.y + (1.0 - t) * plot.h
                };
                (p, short_value(v))
            })
            .collect()
    };
    Layout {
        x_ticks: ticks(&x_axis, true),
        y_ticks: ticks(&y_axis, false),
        plot,
        x_axis,
        y_axis,
        markers,
        front,
    }
}

/// Puts each label at the first free place around its marker, nearest first (eight directions
/// at growing distances; the farther ones get a leader line): free means inside the plot and
/// clear of every marker and every label already placed. A label with no free place is left
/// out rather than drawn over another.
fn place_labels(markers: &mut [Marker], plot: Rect, radius: f64, font: Font) {
    let discs: Vec<Rect> = markers
        .iter()
        .map(|m| Rect {
            x: m.x - radius,
            y: m.y - radius,
            w: 2.0 * radius,
            h: 2.0 * radius,
        })
        .collect();
    let mut taken: Vec<Rect> = Vec::new();
    const DIRECTIONS: [(f64, f64); 8] = [
        (1.0, -1.0),
        (1.0, 1.0),
        (-1.0, -1.0),
        (-1.0, 1.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, -1.0),
        (0.0, 1.0),
    ];
    for m in markers.iter_mut() {
        let (w, h) = (font.char_w * m.label.chars().count() as f64 + 2.0, font.line_h);
        'search: for (ring, gap) in [1.0, 10.0, 24.0, 44.0, 70.0].into_iter().enumerate() {
            for (dx, dy) in DIRECTIONS {
                let d = radius + gap;
                // The box's nearest corner or edge centre sits at distance d in direction (dx, dy).
                let cx = m.x + dx * d + dx * w / 2.0;
                let cy = m.y + dy * d + dy * h / 2.0;
                let b = Rect {
                    x: cx - w / 2.0,
                    y: cy - h / 2.0,
                    w,
                    h,
                };
                if plot.contains(&b) && !discs.iter().any(|c| c.overlaps(&b)) && !taken.iter().any(|t| t.overlaps(&b)) {
                    m.label_box = Some(b);
                    m.leader = ring > 1;
                    taken.push(b);
                    break 'search;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_outlier_decades_away_does_not_set_the_range() {
        let mut values = vec![1e-2, 2e-2, 3e-2, 5e-2, 8e-2, 0.1, 0.15, 0.2, 0.3];
        values.push(5e2);
        let axis = LogAxis::robust(values.iter().copied());
        assert!(axis.hi < 0.5 && axis.lo < -2.0, "{axis:?}");
        assert_eq!(axis.place(5e2).1, Side::Above);
        assert_eq!(axis.place(0.0).1, Side::Below);
        assert_eq!(axis.place(0.05).1, Side::Inside);
        // Without outliers every value is inside.
        let axis = LogAxis::robust(values[..9].iter().copied());
        assert!(values[..9].iter().all(|&v| axis.place(v).1 == Side::Inside), "{axis:?}");
    }

    #[test]
    fn crowded_labels_never_overlap_each_other_or_markers() {
        let plot = Rect {
            x: 0.0,
            y: 0.0,
            w: 300.0,
            h: 200.0,
        };
        let mut markers: Vec<Marker> = (0..30)
            .map(|i| Marker {
                row: i,
                x: 140.0 + (i % 5) as f64 * 4.0,
                y: 90.0 + (i / 5) as f64 * 4.0,
                x_side: Side::Inside,
                y_side: Side::Inside,
                label: format!("{}", i + 1),
                label_box: None,
                leader: false,
                on_front: false,
            })
            .collect();
        let font = Font {
            char_w: 7.0,
            line_h: 12.0,
        };
        place_labels(&mut markers, plot, 4.0, font);
        let boxes: Vec<Rect> = markers.iter().filter_map(|m| m.label_box).collect();
        assert!(boxes.len() >= 20, "most labels find a place: {}", boxes.len());
        for (i, a) in boxes.iter().enumerate() {
            assert!(plot.contains(a));
            assert!(
                boxes[i + 1..].iter().all(|b| !a.overlaps(b)),
                "{a:?} overlaps another label"
            );
            assert!(
                markers.iter().all(|m| !a.overlaps(&Rect {
                    x: m.x - 4.0,
                    y: m.y - 4.0,
                    w: 8.0,
                    h: 8.0
                })),
                "{a:?} covers a marker"
            );
        }
    }
}
