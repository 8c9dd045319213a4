//! The report's pages as HTML text.

use std::fmt::Write as _;

use super::analysis::{best_within, failures, faithful_pairs};
use super::images::{magma_gradient, Files, REL_LOG_HI, REL_LOG_LO};
use super::{svg, ScenePage, BUDGETS_MS};
use crate::commands::chart::layout::short_value;
use crate::commands::chart::{Chart, ChartRun};

/// Text made safe for HTML content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

pub(super) fn head(title: &str) -> String {
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{}</title><link rel=\"stylesheet\" href=\"report.css\"></head>\n<body>\n",
        escape(title)
    )
}

pub(super) const TAIL: &str = "<script src=\"report.js\"></script>\n</body></html>\n";

/// The index: one line per page, with what it holds.
pub fn index(pages: &[ScenePage]) -> String {
    let mut s = head("penumbra report");
    s.push_str("<h1>penumbra report</h1>\n<p>Every lighting configuration of each scene, measured against the path-traced reference.</p>\n");
    s.push_str("<table class=\"sortable\"><thead><tr><th>scene</th><th data-type=\"num\">configurations</th><th data-type=\"num\">failure cases</th><th>most accurate within 10 ms</th></tr></thead><tbody>\n");
    for p in pages {
        let _ = writeln!(
            s,
            "<tr><td><a href=\"{}\">{}</a></td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&p.page),
            escape(&p.scene),
            p.configurations,
            p.failures,
            escape(p.best_within_10ms.as_deref().unwrap_or("none"))
        );
    }
    s.push_str("</tbody></table>\n");
    s + TAIL
}

/// One scene's page.
pub fn scene(run: &ChartRun, files: &Files, stem: &str) -> String {
    let chart = &run.chart;
    let mut s = head(&format!("penumbra report: {}", chart.scene));
    let _ = writeln!(
        s,
        "<nav><a href=\"index.html\">&larr; all scenes</a></nav>\n<h1>{}</h1>",
        escape(&chart.scene)
    );
    let references: Vec<String> = run.references.iter().map(|r| escape(&r.label)).collect();
    let _ = writeln!(
        s,
        "<p class=\"meta\">{}&times;{} pixels &middot; camera: {} &middot; {} &middot; reference: {} &middot; {} &middot; {} configurations &middot; data: <a href=\"{stem}/chart.csv\">chart.csv</a> &middot; <a href=\"{stem}/chart.png\">chart.png</a></p>",
        chart.size.0,
        chart.size.1,
        escape(&chart.camera_name()),
        escape(&chart.device),
        references.join("; "),
        escape(&chart.comparison()),
        chart.rows.len()
    );
    budget_section(&mut s, chart);
    chart_section(&mut s, chart);
    table_section(&mut s, chart);
    viewer_section(&mut s, run, files);
    pairs_section(&mut s, chart, files);
    images_section(&mut s, run, files);
    passes_section(&mut s, chart);
    bake_section(&mut s, chart);
    failures_section(&mut s, chart);
    data_script(&mut s, run, files);
    s + TAIL
}

fn budget_section(s: &mut String, chart: &Chart) {
    s.push_str("<section id=\"budget\"><h2>Best within a time budget</h2>\n<p>Most accurate configuration within ");
    for b in BUDGETS_MS {
        let _ = write!(s, "<button class=\"budget\" data-budget=\"{b}\">{b} ms</button> ");
    }
    s.push_str("or <input id=\"budget-ms\" type=\"number\" min=\"0\" step=\"any\" value=\"10\"> ms</p>\n");
    let best = match best_within(chart, 10.0) {
        Some(i) => format!(
            "Within 10 ms: #{} <b>{}</b>, {} ms, relative MSE {}.",
            i + 1,
            escape(&chart.rows[i].config),
            short_value(chart.rows[i].frame_ms),
            short_value(chart.rows[i].lighting_metrics().rel_mse)
        ),
        None => "No configuration runs within 10 ms.".into(),
    };
    let _ = writeln!(s, "<p id=\"best-result\">{best}</p></section>");
}

fn chart_section(s: &mut String, chart: &Chart) {
    s.push_str("<section id=\"speed\"><h2>Speed against accuracy</h2>\n<div class=\"chart-wrap\">");
    s.push_str(&svg::chart(chart));
    s.push_str("</div>\n<p class=\"legend\">");
    for m in crate::commands::chart::plot::methods(chart) {
        let _ = write!(
            s,
            "<span class=\"swatch\" style=\"background:{}\"></span>{} &nbsp; ",
            svg::method_colour(chart, m),
            escape(m)
        );
    }
    s.push_str("<span class=\"front-key\"></span>Pareto front (ringed markers: no other configuration is both faster and more accurate) &nbsp; &#9650; beyond the axis, its value in the label. Numbers are the table's.</p>\n");
    s.push_str("<p id=\"chart-selected\">Hover over or click a marker to name it.</p></section>\n");
}

fn table_section(s: &mut String, chart: &Chart) {
    s.push_str("<section id=\"table\"><h2>Configurations</h2><p>Click a heading to sort; click a row to show it in the chart and the comparison.</p>\n");
    s.push_str("<table id=\"configs\" class=\"sortable\"><thead><tr><th data-type=\"num\">#</th><th>method</th><th>configuration</th><th data-type=\"num\">frame ms</th><th data-type=\"num\">relative MSE</th><th data-type=\"num\">mean FLIP</th><th data-type=\"num\">mean ratio</th><th data-type=\"num\">bake ms</th><th>Pareto</th></tr></thead><tbody>\n");
    let front = chart.pareto_front();
    for (i, r) in chart.rows.iter().enumerate() {
        let m = r.lighting_metrics();
        let _ = writeln!(
            s,
            "<tr data-row=\"{i}\"><td>{}</td><td>{}</td><td>{}</td><td data-value=\"{}\">{}</td><td data-value=\"{}\">{:.3e}</td><td data-value=\"{}\">{:.4}</td><td data-value=\"{}\">{:.3}</td><td data-value=\"{}\">{}</td><td>{}</td></tr>",
            i + 1,
            escape(&r.method),
            escape(&r.config),
            r.frame_ms,
            short_value(r.frame_ms),
            m.rel_mse,
            m.rel_mse,
            m.flip_mean,
            m.flip_mean,
            m.mean_ratio,
            m.mean_ratio,
            r.bake_ms,
            short_value(r.bake_ms),
            if front.contains(&i) { "front" } else { "" }
        );
    }
    s.push_str("</tbody></table></section>\n");
}

fn viewer_section(s: &mut String, run: &ChartRun, files: &Files) {
    let Some(first) = files.rows.first() else {
        return;
    };
    s.push_str("<section id=\"compare\"><h2>Compare with the reference</h2>\n<p><select id=\"viewer-pick\">");
    for (i, r) in run.chart.rows.iter().enumerate() {
        let _ = write!(s, "<option value=\"{i}\">#{} {}</option>", i + 1, escape(&r.config));
    }
    s.push_str("</select> <select id=\"viewer-layer\"><option value=\"image\">image</option><option value=\"flip\">FLIP map</option><option value=\"rel\">relative error map</option></select> ");
    s.push_str("<button id=\"viewer-flip\">flip</button> drag the slider: configuration left, reference right</p>\n");
    let reference = &files.references[run.reference_of[0]];
    let _ = writeln!(
        s,
        "<div class=\"viewer\"><img id=\"viewer-ref\" src=\"{}\" alt=\"reference\"><img id=\"viewer-test\" src=\"{}\" alt=\"configuration\"></div>\n<input id=\"viewer-slider\" type=\"range\" min=\"0\" max=\"100\" value=\"50\"><p id=\"viewer-caption\"></p></section>",
        escape(&reference.png),
        escape(&first.image.png)
    );
}

fn metrics_line(chart: &Chart, i: usize) -> String {
    let r = &chart.rows[i];
    let m = r.lighting_metrics();
    format!(
        "{} ms &middot; relative MSE {:.3e} &middot; mean FLIP {:.4} &middot; mean ratio {:.3} &middot; against: {}",
        short_value(r.frame_ms),
        m.rel_mse,
        m.flip_mean,
        m.mean_ratio,
        escape(&r.reference)
    )
}

fn figure(src: &str, caption: &str, class: &str) -> String {
    format!(
        "<figure class=\"{class}\"><img src=\"{}\" alt=\"{}\"><figcaption>{caption}</figcaption></figure>",
        escape(src),
        escape(caption)
    )
}

fn pairs_section(s: &mut String, chart: &Chart, files: &Files) {
    s.push_str("<section id=\"faithful\"><h2>Faithful and corrected</h2>\n");
    let pairs = faithful_pairs(chart);
    if pairs.is_empty() {
        s.push_str("<p>No configuration of this scene has a faithful mode beside another.</p>");
    }
    for (a, b) in pairs {
        s.push_str("<div class=\"pair\">");
        for i in [a, b] {
            let caption = format!(
                "#{} {}<br>{}",
                i + 1,
                escape(&chart.rows[i].config),
                metrics_line(chart, i)
            );
            s.push_str(&figure(&files.rows[i].image.png, &caption, "side"));
        }
        s.push_str("</div>\n");
    }
    s.push_str("</section>\n");
}

fn scale_bar(labels: &[&str]) -> String {
    let spans: String = labels.iter().map(|l| format!("<span>{l}</span>")).collect();
    format!(
        "<div class=\"scale\"><div class=\"bar\" style=\"background:{}\"></div><div class=\"ticks\">{spans}</div></div>",
        magma_gradient()
    )
}

fn images_section(s: &mut String, run: &ChartRun, files: &Files) {
    let chart = &run.chart;
    s.push_str("<section id=\"images\"><h2>Images</h2>\n<div class=\"references\">");
    for (r, p) in run.references.iter().zip(&files.references) {
        let caption = format!(
            "reference: {} &middot; <a href=\"{}\">EXR</a>",
            escape(&r.label),
            escape(&p.exr)
        );
        s.push_str(&figure(&p.png, &caption, "reference"));
    }
    s.push_str("</div>\n");
    let flip_scale = scale_bar(&["0", "0.25", "0.5", "0.75", "1"]);
    let percent = |l: f64| format!("{:.0}%", 100.0 * 10f64.powf(l));
    let rel_labels: Vec<String> = (0..=3)
        .map(|k| percent(REL_LOG_LO + (REL_LOG_HI - REL_LOG_LO) * k as f64 / 3.0))
        .collect();
    let rel_refs: Vec<&str> = rel_labels.iter().map(String::as_str).collect();
    let rel_scale = scale_bar(&rel_refs);
    for (i, f) in files.rows.iter().enumerate() {
        let r = &chart.rows[i];
        let _ = write!(
            s,
            "<div class=\"config\" id=\"config-{}\"><h3>#{} {}</h3><p>{} &middot; <a href=\"{}\">EXR</a></p><div class=\"maps\">",
            i + 1,
            i + 1,
            escape(&r.config),
            metrics_line(chart, i),
            escape(&f.image.exr)
        );
        s.push_str(&figure(&f.image.png, "image (tone-mapped)", "map"));
        s.push_str(&figure(&f.flip, &format!("FLIP{flip_scale}"), "map"));
        s.push_str(&figure(
            &f.rel,
            &format!("relative error (log scale){rel_scale}"),
            "map",
        ));
        s.push_str("</div></div>\n");
    }
    s.push_str("</section>\n");
}

/// Each configuration's passes as a stacked bar, on one scale for the whole scene.
fn passes_section(s: &mut String, chart: &Chart) {
    s.push_str("<section id=\"passes\"><h2>GPU time per pass</h2><p>Median GPU time of each pass (timestamp queries); hover a segment for its name.</p>\n");
    let mut names: Vec<&str> = Vec::new();
    for r in &chart.rows {
        for (p, _) in &r.passes {
            if !names.contains(&p.as_str()) {
                names.push(p);
            }
        }
    }
    let total = |r: &crate::commands::chart::ChartRow| r.passes.iter().map(|(_, ms)| ms.max(0.0)).sum::<f64>();
    let longest = chart.rows.iter().map(total).fold(0.0f64, f64::max).max(1e-9);
    let hue = |p: &str| names.iter().position(|n| *n == p).unwrap_or(0) * 360 / names.len().max(1);
    s.push_str("<p class=\"legend\">");
    for n in &names {
        let _ = write!(
            s,
            "<span class=\"swatch\" style=\"background:hsl({},55%,55%)\"></span>{} &nbsp; ",
            hue(n),
            escape(n)
        );
    }
    s.push_str("</p><div class=\"bars\">\n");
    for (i, r) in chart.rows.iter().enumerate() {
        let _ = write!(
            s,
            "<div class=\"barrow\"><span class=\"barname\">#{} {}</span><span class=\"bar\">",
            i + 1,
            escape(&r.config)
        );
        for (p, ms) in &r.passes {
            let _ = write!(
                s,
                "<span class=\"seg\" style=\"width:{:.2}%;background:hsl({},55%,55%)\" title=\"{}: {} ms\"></span>",
                100.0 * ms.max(0.0) / longest,
                hue(p),
                escape(p),
                short_value(*ms)
            );
        }
        let _ = writeln!(
            s,
            "</span><span class=\"barval\">{} ms</span></div>",
            short_value(total(r))
        );
    }
    s.push_str("</div></section>\n");
}

fn bake_section(s: &mut String, chart: &Chart) {
    s.push_str("<section id=\"bake\"><h2>Bake cost</h2>\n");
    let baked: Vec<usize> = (0..chart.rows.len())
        .filter(|&i| chart.rows[i].bake_ms > 0.0 || chart.rows[i].bake_bytes > 0)
        .collect();
    if baked.is_empty() {
        s.push_str("<p>No configuration of this scene bakes anything.</p></section>\n");
        return;
    }
    s.push_str("<p>Wall time of the bakes when the configuration was made (0 when read from the bake cache), and their size.</p><table class=\"sortable\"><thead><tr><th data-type=\"num\">#</th><th>configuration</th><th data-type=\"num\">bake ms</th><th data-type=\"num\">size, KiB</th></tr></thead><tbody>\n");
    for i in baked {
        let r = &chart.rows[i];
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.1}</td></tr>",
            i + 1,
            escape(&r.config),
            short_value(r.bake_ms),
            r.bake_bytes as f64 / 1024.0
        );
    }
    s.push_str("</tbody></table></section>\n");
}

fn failures_section(s: &mut String, chart: &Chart) {
    s.push_str("<section id=\"failures\"><h2>Failure cases</h2>\n");
    let list = failures(chart);
    if list.is_empty() {
        s.push_str("<p>None: every configuration ran, gave finite values, and is within a factor of two of the reference's mean with a relative MSE below 1.</p></section>\n");
        return;
    }
    s.push_str("<ul>\n");
    for f in list {
        let _ = writeln!(
            s,
            "<li class=\"failure\"><b>{}</b> {}: {}</li>",
            f.kind,
            escape(&f.config),
            escape(&f.detail)
        );
    }
    s.push_str("</ul></section>\n");
}

/// What the page's script needs, as JSON: each row's name, numbers and pictures.
fn data_script(s: &mut String, run: &ChartRun, files: &Files) {
    let rows: Vec<serde_json::Value> = run
        .chart
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            serde_json::json!({
                "name": r.config,
                "ms": r.frame_ms,
                "rel_mse": r.lighting_metrics().rel_mse,
                "image": files.rows[i].image.png,
                "flip": files.rows[i].flip,
                "rel": files.rows[i].rel,
                "reference": files.references[run.reference_of[i]].png,
            })
        })
        .collect();
    let json = serde_json::json!({ "rows": rows }).to_string().replace("</", "<\\/");
    let _ = writeln!(
        s,
        "<script type=\"application/json\" id=\"report-data\">{json}</script>"
    );
}
