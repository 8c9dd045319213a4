//! The generated-scene suite as one page of the report: where its table came from, each
//! configuration's summary over the scenes, the targets with the scenes that miss them, the
//! failures and refusals, and every row.

use std::fmt::Write as _;

use super::html::{escape, head, TAIL};
use crate::commands::suite::table::{fixed, parse_csv, sci, summarise, Status, Summary};
use crate::error::Result;

/// The page for a suite table `text` read from `source`: the HTML and how many configurations
/// it summarises. Leading `#` lines (the data file's device, driver, commit and date) are shown as
/// written.
pub fn page(source: &str, text: &str) -> Result<(String, usize)> {
    let comments: Vec<&str> = text.lines().take_while(|l| l.starts_with('#')).collect();
    let table: String = text.lines().skip(comments.len()).map(|l| format!("{l}\n")).collect();
    let summary = summarise(parse_csv(&table, source)?);
    let mut s = head(&format!("penumbra report: {source}"));
    let _ = writeln!(
        s,
        "<nav><a href=\"index.html\">&larr; all scenes</a></nav>\n<h1>Generated-scene suite</h1>"
    );
    let scenes: std::collections::BTreeSet<(u64, u64)> = summary.rows.iter().map(|r| (r.seed, r.index)).collect();
    let _ = writeln!(
        s,
        "<p class=\"meta\">{} scenes, {} rows, from {}</p>",
        scenes.len(),
        summary.rows.len(),
        escape(source)
    );
    match (comments.is_empty(), summary.rows.first()) {
        (false, _) => {
            let lines: Vec<String> = comments
                .iter()
                .map(|c| escape(c.trim_start_matches('#').trim()))
                .collect();
            let _ = writeln!(s, "<p class=\"meta\">{}</p>", lines.join("<br>"));
        }
        (true, Some(r)) => {
            let p = &r.provenance;
            let _ = writeln!(
                s,
                "<p class=\"meta\">device {} &middot; driver {} &middot; commit {} &middot; {}</p>",
                escape(&p.device),
                escape(&p.driver),
                escape(&p.commit),
                escape(&p.date)
            );
        }
        (true, None) => {}
    }
    methods_table(&mut s, &summary);
    targets(&mut s, &summary);
    rows_table(&mut s, &summary);
    Ok((s + TAIL, summary.methods.len()))
}

fn methods_table(s: &mut String, summary: &Summary) {
    s.push_str("<h2>Per configuration</h2>\n<p>Relative MSE and mean ratio (&Sigma; method / &Sigma; reference) against the path-traced reference each configuration models; frame and bake times are medians over the scenes.</p>\n");
    s.push_str("<table class=\"sortable\" id=\"suite-methods\"><thead><tr><th>configuration</th>");
    for h in ["scenes", "ok", "refused", "failed", "rel MSE median", "p90"] {
        let _ = write!(s, "<th data-type=\"num\">{h}</th>");
    }
    s.push_str("<th>worst (scene)</th><th data-type=\"num\">mean ratio median</th><th>[min, max]</th><th data-type=\"num\">frame ms</th><th data-type=\"num\">bake ms</th></tr></thead><tbody>\n");
    for m in &summary.methods {
        let worst = m
            .worst
            .as_ref()
            .map_or("-".into(), |(scene, v)| format!("{} ({})", sci(*v), escape(scene)));
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td data-value=\"{}\">{}</td><td data-value=\"{}\">{}</td><td>{worst}</td><td>{}</td><td>[{}, {}]</td><td>{}</td><td>{}</td></tr>",
            escape(&m.config),
            m.scenes,
            m.ok,
            m.refused,
            m.failures.len(),
            m.rel_mse_median,
            sci(m.rel_mse_median),
            m.rel_mse_p90,
            sci(m.rel_mse_p90),
            fixed(m.mean_ratio_median, 3),
            fixed(m.mean_ratio_range.0, 3),
            fixed(m.mean_ratio_range.1, 3),
            fixed(m.frame_ms_median, 2),
            fixed(m.bake_ms_median, 0),
        );
    }
    s.push_str("</tbody></table>\n");
}

fn targets(s: &mut String, summary: &Summary) {
    s.push_str("<h2>Targets</h2>\n<ul id=\"suite-targets\">\n");
    for t in &summary.targets {
        let (class, verdict) = match (t.applies, t.met()) {
            (0, _) => ("", "no scene applies"),
            (_, true) => ("met", "met"),
            (_, false) => ("failure", "NOT met"),
        };
        let _ = write!(
            s,
            "<li class=\"{class}\">{}: holds on {} of {}: <b>{verdict}</b>",
            escape(&t.name),
            t.holds,
            t.applies
        );
        if !t.misses.is_empty() {
            s.push_str("<ul>");
            for miss in &t.misses {
                let _ = write!(s, "<li>{}</li>", escape(miss));
            }
            s.push_str("</ul>");
        }
        s.push_str("</li>\n");
    }
    s.push_str("</ul>\n");
}

fn rows_table(s: &mut String, summary: &Summary) {
    s.push_str("<h2>Every scene and configuration</h2>\n<table class=\"sortable\" id=\"suite-rows\"><thead><tr><th>scene</th><th>theme</th><th>configuration</th><th>status</th><th data-type=\"num\">rel MSE</th><th data-type=\"num\">mean ratio</th><th data-type=\"num\">reference noise</th><th data-type=\"num\">frame ms</th><th data-type=\"num\">bake ms</th><th>reference</th><th>detail and warnings</th></tr></thead><tbody>\n");
    for r in &summary.rows {
        let failed = r.status.is_failure() || matches!(r.status, Status::Refused(_));
        let notes: Vec<String> = std::iter::once(r.status.detail().to_owned())
            .chain(r.warnings.iter().cloned())
            .filter(|n| !n.is_empty())
            .map(|n| escape(&n))
            .collect();
        let _ = writeln!(
            s,
            "<tr{}><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td data-value=\"{}\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            if failed { " class=\"failure\"" } else { "" },
            escape(&r.scene),
            escape(&r.theme),
            escape(&r.config),
            r.status.name(),
            r.rel_mse().unwrap_or(f64::NAN),
            r.rel_mse().map_or("-".into(), sci),
            r.mean_ratio().map_or("-".into(), |v| fixed(v, 3)),
            sci(r.noise_rel_mse),
            fixed(r.frame_ms, 2),
            fixed(r.bake_ms, 0),
            escape(&r.reference),
            notes.join("<br>"),
        );
    }
    s.push_str("</tbody></table>\n");
}
