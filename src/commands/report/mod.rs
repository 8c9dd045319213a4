//! `penumbra report`: a static HTML comparison of every configuration `penumbra chart` measures,
//! one page per scene and an index, that opens from disk with no server and no network.
//!
//! Each scene's page holds the reference, every configuration's image with its FLIP and
//! relative-error maps, a slider and a flip between any configuration and the reference, the
//! faithful and corrected modes side by side, the speed/accuracy chart as an SVG whose markers
//! name their configuration, per-pass GPU times, bake costs, and the failures the data shows.
//! Everything on the page comes from the chart's measurements; the page's script only sorts,
//! highlights and switches between what was written.

mod analysis;
mod html;
mod images;
mod suite_page;
mod svg;

use std::path::{Path, PathBuf};

use crate::commands::chart::{self, ChartOptions, ChartRun};
use crate::error::{Error, Result};

pub use analysis::{best_within, failures, faithful_pairs, Failure};

/// The page's script and style sheet, written beside the pages (no network at view time).
const SCRIPT: &str = include_str!("report.js");
const STYLE: &str = include_str!("report.css");

/// Time budgets offered as one-click choices, in ms (a 60 Hz and a 30 Hz frame, and 10 ms).
pub const BUDGETS_MS: [f64; 4] = [1.0, 10.0, 16.7, 33.3];

#[derive(Clone, Debug)]
pub struct ReportOptions {
    pub scenes: Vec<PathBuf>,
    pub out_dir: PathBuf,
    /// A results table of the generated-scene suite, shown as one more page.
    pub suite: Option<PathBuf>,
    /// The chart's settings; its `scene`, `png` and `csv` are set per scene.
    pub chart: ChartOptions,
}

/// What was written for one scene.
#[derive(Clone, Debug)]
pub struct ScenePage {
    pub scene: String,
    /// The page, relative to the report's directory.
    pub page: String,
    pub configurations: usize,
    pub failures: usize,
    /// The most accurate configuration within 10 ms, if any.
    pub best_within_10ms: Option<String>,
}

/// A page's file stem: the scene file's stem, made safe for a URL and unique in the report.
fn page_stem(scene: &Path, taken: &[ScenePage]) -> String {
    let stem: String = scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let stem = if stem.is_empty() || stem == "index" {
        format!("scene_{stem}")
    } else {
        stem
    };
    let mut candidate = stem.clone();
    let mut n = 2;
    while taken.iter().any(|p| p.page == format!("{candidate}.html")) {
        candidate = format!("{stem}_{n}");
        n += 1;
    }
    candidate
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::util::image_io::write_file(path, bytes).map_err(|e| Error::Usage(format!("{}: {e}", path.display())))
}

/// Charts every scene and writes the report; returns what each page holds.
pub fn run(opts: &ReportOptions) -> Result<Vec<ScenePage>> {
    if opts.scenes.is_empty() {
        return Err(Error::Usage("report: name at least one scene file".into()));
    }
    let out = &opts.out_dir;
    std::fs::create_dir_all(out).map_err(|e| Error::Usage(format!("{}: {e}", out.display())))?;
    write(&out.join("report.js"), SCRIPT.as_bytes())?;
    write(&out.join("report.css"), STYLE.as_bytes())?;
    let mut pages: Vec<ScenePage> = Vec::new();
    for scene in &opts.scenes {
        let stem = page_stem(scene, &pages);
        let dir = out.join(&stem);
        std::fs::create_dir_all(&dir).map_err(|e| Error::Usage(format!("{}: {e}", dir.display())))?;
        let chart_opts = ChartOptions {
            scene: scene.clone(),
            png: Some(dir.join("chart.png")),
            csv: Some(dir.join("chart.csv")),
            ..opts.chart.clone()
        };
        let run = chart::run_keeping_images(&chart_opts)?;
        pages.push(scene_page(&run, out, &stem)?);
    }
    if let Some(csv) = &opts.suite {
        pages.push(suite_page(csv, out)?);
    }
    write(&out.join("index.html"), html::index(&pages).as_bytes())?;
    Ok(pages)
}

/// Writes one scene's images and page.
fn scene_page(run: &ChartRun, out: &Path, stem: &str) -> Result<ScenePage> {
    let files = images::write_all(run, &out.join(stem), stem)?;
    let page = html::scene(run, &files, stem);
    write(&out.join(format!("{stem}.html")), page.as_bytes())?;
    let chart = &run.chart;
    // The index tells a chosen camera's page from the scene's own view.
    let scene = match chart.camera {
        Some(n) => format!("{}, camera {n}", chart.scene),
        None => chart.scene.clone(),
    };
    Ok(ScenePage {
        scene,
        page: format!("{stem}.html"),
        configurations: chart.rows.len(),
        failures: failures(chart).len(),
        best_within_10ms: best_within(chart, 10.0).map(|i| chart.rows[i].config.clone()),
    })
}

/// Where a results table of the generated-scene suite (a CSV with a header row) becomes one more
/// page of the report: the table as written, sortable, linked from the index.
pub fn suite_page(csv: &Path, out_dir: &Path) -> Result<ScenePage> {
    let text = std::fs::read_to_string(csv).map_err(|e| Error::Usage(format!("{}: {e}", csv.display())))?;
    let rows = text.lines().filter(|l| !l.trim().is_empty()).count();
    if rows == 0 {
        return Err(Error::Usage(format!(
            "{}: the suite's results table is empty",
            csv.display()
        )));
    }
    let page = "generated_suite.html".to_string();
    let (html, configurations) = suite_page::page(&csv.display().to_string(), &text)?;
    write(&out_dir.join(&page), html.as_bytes())?;
    Ok(ScenePage {
        scene: csv.display().to_string(),
        page,
        configurations,
        failures: 0,
        best_within_10ms: None,
    })
}
