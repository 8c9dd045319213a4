//! The suite's rows as CSV (written per shard, read back together), the per-method summary,
//! the targets judged over the rows, and the Markdown table.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::Provenance;
use crate::error::{Error, Result};
use crate::metrics::Metrics;
use crate::scene::generate::{Generated, Theme};

/// How one configuration fared on one scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    Ok,
    /// The method declined the scene up front (a need it does not meet), with its reason.
    Refused(String),
    /// An error while creating, baking or rendering, or while comparing.
    Error(String),
    /// A panic.
    Crash(String),
    /// A NaN or an infinity in its image.
    NonFinite(String),
    /// The validation layer reported something while it ran.
    Validation(String),
}

impl Status {
    pub fn name(&self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Refused(_) => "refused",
            Status::Error(_) => "error",
            Status::Crash(_) => "crash",
            Status::NonFinite(_) => "non_finite",
            Status::Validation(_) => "validation",
        }
    }

    pub fn detail(&self) -> &str {
        match self {
            Status::Ok => "",
            Status::Refused(s) | Status::Error(s) | Status::Crash(s) | Status::NonFinite(s) | Status::Validation(s) => {
                s
            }
        }
    }

    /// A failure: anything but success and a refusal.
    pub fn is_failure(&self) -> bool {
        !matches!(self, Status::Ok | Status::Refused(_))
    }

    fn parse(name: &str, detail: String) -> Status {
        match name {
            "ok" => Status::Ok,
            "refused" => Status::Refused(detail),
            "crash" => Status::Crash(detail),
            "non_finite" => Status::NonFinite(detail),
            "validation" => Status::Validation(detail),
            _ => Status::Error(detail),
        }
    }
}

/// One scene × configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub seed: u64,
    pub index: u64,
    pub scene: String,
    pub theme: String,
    pub config: String,
    pub status: Status,
    /// The reference it was judged against (e.g. `direct, sobol, 256 spp`).
    pub reference: String,
    pub frame_ms: f64,
    pub bake_ms: f64,
    /// Against the reference (supersampled when the suite is).
    pub metrics: Option<Metrics>,
    /// The relative MSE an exact image would score against this reference (its noise).
    pub noise_rel_mse: f64,
    /// For a configuration with an indirect part: its direct part alone against the same
    /// reference.
    pub direct_alone: Option<Metrics>,
    pub warnings: Vec<String>,
    pub provenance: Provenance,
}

impl Row {
    pub fn new(seed: u64, g: &Generated, config: &str, status: Status, provenance: &Provenance) -> Row {
        Row {
            seed,
            index: g.index,
            scene: g.name.clone(),
            theme: g.theme.name().into(),
            config: config.into(),
            status,
            reference: String::new(),
            frame_ms: f64::NAN,
            bake_ms: f64::NAN,
            metrics: None,
            noise_rel_mse: f64::NAN,
            direct_alone: None,
            warnings: Vec::new(),
            provenance: provenance.clone(),
        }
    }

    pub fn rel_mse(&self) -> Option<f64> {
        self.metrics.as_ref().map(|m| m.rel_mse)
    }

    pub fn mean_ratio(&self) -> Option<f64> {
        self.metrics.as_ref().map(|m| m.mean_ratio)
    }

    fn is_rooms(&self) -> bool {
        Theme::ALL.iter().any(|t| t.name() == self.theme && t.is_rooms())
    }
}

const COLUMNS: &str = "seed,index,scene,theme,config,status,reference,frame_ms,bake_ms,rel_mse,mean_ratio,rmse,flip,\
scaled_rel_rmse,ref_noise_rel_mse,direct_alone_rel_mse,direct_alone_mean_ratio,device,driver,commit,date,warnings,detail";

fn field(s: &str) -> String {
    s.replace([',', '\n', '\r'], ";")
}

fn num(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// The rows as CSV, one line each, with the columns of [`COLUMNS`].
pub fn csv(rows: &[Row]) -> String {
    let mut s = format!("{COLUMNS}\n");
    for r in rows {
        let m = r.metrics.as_ref();
        let d = r.direct_alone.as_ref();
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.seed,
            r.index,
            field(&r.scene),
            field(&r.theme),
            field(&r.config),
            r.status.name(),
            field(&r.reference),
            r.frame_ms,
            r.bake_ms,
            num(m.map(|m| m.rel_mse)),
            num(m.map(|m| m.mean_ratio)),
            num(m.map(|m| m.rmse)),
            num(m.map(|m| m.flip_mean)),
            num(m.map(|m| m.scaled_rel_rmse)),
            r.noise_rel_mse,
            num(d.map(|m| m.rel_mse)),
            num(d.map(|m| m.mean_ratio)),
            field(&r.provenance.device),
            field(&r.provenance.driver),
            field(&r.provenance.commit),
            field(&r.provenance.date),
            field(&r.warnings.join(" | ")),
            field(r.status.detail()),
        );
    }
    s
}

/// Reads back what [`csv`] wrote (the metrics it does not keep are NaN).
pub fn parse_csv(text: &str, file: &str) -> Result<Vec<Row>> {
    let mut lines = text.lines();
    if lines.next() != Some(COLUMNS) {
        return Err(Error::Usage(format!("{file}: not a suite table (its header differs)")));
    }
    let mut rows = Vec::new();
    for (n, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != COLUMNS.split(',').count() {
            return Err(Error::Usage(format!("{file}: line {}: {} fields", n + 2, f.len())));
        }
        let bad = |c: usize| Error::Usage(format!("{file}: line {}: column {c} is not a number", n + 2));
        let int = |c: usize| f[c].parse::<u64>().map_err(|_| bad(c));
        let opt = |c: usize| -> Result<Option<f64>> {
            if f[c].is_empty() {
                Ok(None)
            } else {
                f[c].parse::<f64>().map(Some).map_err(|_| bad(c))
            }
        };
        let metrics = |rel: Option<f64>, ratio: Option<f64>, rest: [Option<f64>; 3]| {
            rel.map(|rel_mse| Metrics {
                rmse: rest[0].unwrap_or(f64::NAN),
                rel_mse,
                mean_bias: f64::NAN,
                p99_abs_error: f64::NAN,
                max_abs_error: f64::NAN,
                flip_mean: rest[1].unwrap_or(f64::NAN),
                mean_ratio: ratio.unwrap_or(f64::NAN),
                scaled_rel_rmse: rest[2].unwrap_or(f64::NAN),
                pixels: 0,
            })
        };
        rows.push(Row {
            seed: int(0)?,
            index: int(1)?,
            scene: f[2].into(),
            theme: f[3].into(),
            config: f[4].into(),
            status: Status::parse(f[5], f[22].into()),
            reference: f[6].into(),
            frame_ms: opt(7)?.unwrap_or(f64::NAN),
            bake_ms: opt(8)?.unwrap_or(f64::NAN),
            metrics: metrics(opt(9)?, opt(10)?, [opt(11)?, opt(12)?, opt(13)?]),
            noise_rel_mse: opt(14)?.unwrap_or(f64::NAN),
            direct_alone: metrics(opt(15)?, opt(16)?, [None; 3]),
            warnings: f[21].split(" | ").filter(|w| !w.is_empty()).map(String::from).collect(),
            provenance: Provenance {
                device: f[17].into(),
                driver: f[18].into(),
                commit: f[19].into(),
                date: f[20].into(),
            },
        });
    }
    Ok(rows)
}

/// The nearest-rank quantile `q` of `values` (NaN when empty).
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let rank = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len());
    v[rank - 1]
}

/// One configuration over every scene it was given.
#[derive(Clone, Debug)]
pub struct MethodSummary {
    pub config: String,
    pub scenes: usize,
    pub ok: usize,
    pub refused: usize,
    /// Scene names with their failure.
    pub failures: Vec<(String, String)>,
    pub rel_mse_median: f64,
    pub rel_mse_p90: f64,
    pub worst: Option<(String, f64)>,
    pub mean_ratio_median: f64,
    pub mean_ratio_range: (f64, f64),
    pub frame_ms_median: f64,
    pub bake_ms_median: f64,
}

/// One of the targets, judged over the rows it applies to.
#[derive(Clone, Debug)]
pub struct Target {
    pub name: String,
    /// Scenes it applies to, and on how many it holds.
    pub applies: usize,
    pub holds: usize,
    /// The share of `applies` it must hold on (1 for "every").
    pub needed: f64,
    /// Scenes where it does not hold, with the measured values.
    pub misses: Vec<String>,
    /// Rows of the method it does not judge, and why (a direct method that warned it dropped
    /// light: the target is stated where the scene's lights are all drawn).
    pub set_aside: Vec<String>,
}

impl Target {
    pub fn met(&self) -> bool {
        self.applies > 0 && self.holds as f64 >= self.needed * self.applies as f64 - 1e-9
    }
}

pub struct Summary {
    pub rows: Vec<Row>,
    pub methods: Vec<MethodSummary>,
    pub targets: Vec<Target>,
}

/// Summarises every `suite*.csv` in `dir` (every shard run into it).
pub fn summarise_dir(dir: &Path) -> Result<Summary> {
    let mut rows = Vec::new();
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map_err(|e| Error::Usage(format!("{}: {e}", dir.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("suite") && n.ends_with(".csv"))
        })
        .collect();
    files.sort();
    for f in files {
        let text = std::fs::read_to_string(&f).map_err(|e| Error::Usage(format!("{}: {e}", f.display())))?;
        rows.extend(parse_csv(&text, &f.display().to_string())?);
    }
    rows.sort_by(|a, b| (a.seed, a.index, &a.config).cmp(&(b.seed, b.index, &b.config)));
    rows.dedup_by(|a, b| (a.seed, a.index, &a.config) == (b.seed, b.index, &b.config));
    Ok(summarise(rows))
}

pub fn summarise(rows: Vec<Row>) -> Summary {
    let mut by_config: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for r in &rows {
        by_config.entry(r.config.as_str()).or_default().push(r);
    }
    let methods = by_config.into_iter().map(|(c, rs)| method_summary(c, &rs)).collect();
    let targets = targets(&rows);
    Summary { rows, methods, targets }
}

fn method_summary(config: &str, rows: &[&Row]) -> MethodSummary {
    let rel: Vec<f64> = rows.iter().filter_map(|r| r.rel_mse()).collect();
    let ratio: Vec<f64> = rows.iter().filter_map(|r| r.mean_ratio()).collect();
    let worst = rows
        .iter()
        .filter_map(|r| Some((r.scene.clone(), r.rel_mse()?)))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let finite = |v: Vec<f64>| -> Vec<f64> { v.into_iter().filter(|x| x.is_finite()).collect() };
    MethodSummary {
        config: config.into(),
        scenes: rows.len(),
        ok: rows.iter().filter(|r| r.status == Status::Ok).count(),
        refused: rows.iter().filter(|r| matches!(r.status, Status::Refused(_))).count(),
        failures: rows
            .iter()
            .filter(|r| r.status.is_failure())
            .map(|r| (r.scene.clone(), format!("{}: {}", r.status.name(), r.status.detail())))
            .collect(),
        rel_mse_median: quantile(&rel, 0.5),
        rel_mse_p90: quantile(&rel, 0.9),
        worst,
        mean_ratio_median: quantile(&ratio, 0.5),
        mean_ratio_range: (quantile(&ratio, 0.0), quantile(&ratio, 1.0)),
        frame_ms_median: quantile(&finite(rows.iter().map(|r| r.frame_ms).collect()), 0.5),
        bake_ms_median: quantile(&finite(rows.iter().map(|r| r.bake_ms).collect()), 0.5),
    }
}

/// The direct methods the 1e-3 target names.
pub const DIRECT_METHODS: [&str; 5] = ["forward", "shadow_volumes", "clustered", "vls", "bsp_lights"];

/// A target over the rows `applies` selects: `holds` says whether it holds on one and, when
/// not, what was measured.
fn target(
    rows: &[Row],
    name: String,
    needed: f64,
    applies: impl Fn(&Row) -> bool,
    holds: impl Fn(&Row) -> std::result::Result<(), String>,
) -> Target {
    let mut t = Target {
        name,
        applies: 0,
        holds: 0,
        needed,
        misses: Vec::new(),
        set_aside: Vec::new(),
    };
    for r in rows.iter().filter(|r| applies(r)) {
        t.applies += 1;
        match holds(r) {
            Ok(()) => t.holds += 1,
            Err(why) => t.misses.push(format!("{} {}: {why}", r.scene, r.config)),
        }
    }
    t
}

fn measured(r: &Row) -> std::result::Result<&Metrics, String> {
    r.metrics
        .as_ref()
        .ok_or_else(|| format!("{}: {}", r.status.name(), r.status.detail()))
}

fn targets(rows: &[Row]) -> Vec<Target> {
    let mut out = vec![target(
        rows,
        "radiosity: relative MSE <= 0.01 and image mean within 3% on 90% of room scenes".into(),
        0.9,
        |r| r.config == "radiosity" && r.is_rooms() && !matches!(r.status, Status::Refused(_)),
        |r| {
            let m = measured(r)?;
            if m.rel_mse <= 0.01 && (m.mean_ratio - 1.0).abs() <= 0.03 {
                Ok(())
            } else {
                Err(format!("rel MSE {:.4}, mean ratio {:.3}", m.rel_mse, m.mean_ratio))
            }
        },
    )];
    out.push(target(
        rows,
        "lpv over shadow volumes: mean within 0.8-1.25 of the one-bounce reference and relative MSE <= 0.8x direct light alone on 90%".into(),
        0.9,
        |r| r.config == "lpv_over_shadow_volumes" && !matches!(r.status, Status::Refused(_)),
        |r| {
            let m = measured(r)?;
            let d = r.direct_alone.as_ref().ok_or("no direct-alone render")?;
            if (0.8..=1.25).contains(&m.mean_ratio) && m.rel_mse <= 0.8 * d.rel_mse {
                Ok(())
            } else {
                Err(format!(
                    "mean ratio {:.3} (direct alone {:.3}), rel MSE {:.4} = {:.2}x direct alone {:.4}",
                    m.mean_ratio,
                    d.mean_ratio,
                    m.rel_mse,
                    m.rel_mse / d.rel_mse,
                    d.rel_mse
                ))
            }
        },
    ));
    for method in DIRECT_METHODS {
        let mut t = target(
            rows,
            format!(
                "{method}: relative MSE <= 1e-3 against the direct reference where the scene's lights are supported"
            ),
            1.0,
            |r| r.config == method && r.status == Status::Ok && r.warnings.is_empty(),
            |r| {
                let m = measured(r)?;
                if m.rel_mse <= 1e-3 {
                    Ok(())
                } else {
                    Err(format!(
                        "rel MSE {:.2e} (reference noise {:.1e})",
                        m.rel_mse, r.noise_rel_mse
                    ))
                }
            },
        );
        t.set_aside = rows
            .iter()
            .filter(|r| r.config == method && r.status == Status::Ok && !r.warnings.is_empty())
            .map(|r| format!("{} {}: {}", r.scene, r.config, r.warnings.join("; ")))
            .collect();
        out.push(t);
    }
    out.push(target(
        rows,
        "every scene and method: no NaN or inf, no crash or error, no validation message".into(),
        1.0,
        |_| true,
        |r| {
            if r.status.is_failure() {
                Err(format!("{}: {}", r.status.name(), r.status.detail()))
            } else {
                Ok(())
            }
        },
    ));
    out
}

pub(crate) fn sci(v: f64) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{v:.2e}")
    }
}

pub(crate) fn fixed(v: f64, digits: usize) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{v:.digits$}")
    }
}

impl Summary {
    /// The per-method table, the targets, and every failure, as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::from("# Generated-scene suite\n\n");
        let scenes: std::collections::BTreeSet<(u64, u64)> = self.rows.iter().map(|r| (r.seed, r.index)).collect();
        if let Some(r) = self.rows.first() {
            let p = &r.provenance;
            let _ = writeln!(
                s,
                "{} scenes; device {}, driver {}, commit {}, {}. Relative MSE and mean ratio (Σ method / Σ reference) against the path-traced reference each configuration models; frame and bake times are medians over the scenes.\n",
                scenes.len(), p.device, p.driver, p.commit, p.date
            );
        }
        s.push_str("| configuration | scenes | ok | refused | failed | rel MSE median | p90 | worst (scene) | mean ratio median [min, max] | frame ms | bake ms |\n");
        s.push_str("|---|---|---|---|---|---|---|---|---|---|---|\n");
        for m in &self.methods {
            let worst = m
                .worst
                .as_ref()
                .map_or("-".into(), |(scene, v)| format!("{} ({scene})", sci(*v)));
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {worst} | {} [{}, {}] | {} | {} |",
                m.config,
                m.scenes,
                m.ok,
                m.refused,
                m.failures.len(),
                sci(m.rel_mse_median),
                sci(m.rel_mse_p90),
                fixed(m.mean_ratio_median, 3),
                fixed(m.mean_ratio_range.0, 3),
                fixed(m.mean_ratio_range.1, 3),
                fixed(m.frame_ms_median, 2),
                fixed(m.bake_ms_median, 0),
            );
        }
        s.push_str("\n## Targets\n\n");
        for t in &self.targets {
            let verdict = if t.applies == 0 {
                "no scene applies"
            } else if t.met() {
                "met"
            } else {
                "NOT met"
            };
            let _ = writeln!(s, "- {}: holds on {} of {}: {verdict}", t.name, t.holds, t.applies);
            for miss in t.misses.iter().take(10) {
                let _ = writeln!(s, "  - {miss}");
            }
            if t.misses.len() > 10 {
                let _ = writeln!(s, "  - and {} more", t.misses.len() - 10);
            }
            for aside in &t.set_aside {
                let _ = writeln!(s, "  - not judged, the method warned: {aside}");
            }
        }
        let refusals: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| matches!(r.status, Status::Refused(_)))
            .collect();
        if !refusals.is_empty() {
            s.push_str("\n## Refusals\n\n");
            for r in refusals {
                let _ = writeln!(s, "- {} {}: {}", r.scene, r.config, r.status.detail());
            }
        }
        s
    }
}

/// Copies into `dir/worst/` the `count` scenes with the largest relative MSE of each
/// configuration and every scene one failed on, named `<config>-<rank>-<scene>.toml` and
/// `<config>-failed-<scene>.toml`, from `dir/scenes/`.
pub fn save_worst(summary: &Summary, dir: &Path, count: usize) -> Result<()> {
    let worst = dir.join("worst");
    std::fs::create_dir_all(&worst).map_err(|e| Error::Usage(format!("{}: {e}", worst.display())))?;
    let copy = |scene: &str, name: String| -> Result<()> {
        let from = dir.join("scenes").join(format!("{scene}.toml"));
        if from.exists() {
            std::fs::copy(&from, worst.join(name)).map_err(|e| Error::Usage(format!("{}: {e}", from.display())))?;
        }
        Ok(())
    };
    for m in &summary.methods {
        let mut rows: Vec<&Row> = summary.rows.iter().filter(|r| r.config == m.config).collect();
        rows.sort_by(|a, b| b.rel_mse().unwrap_or(-1.0).total_cmp(&a.rel_mse().unwrap_or(-1.0)));
        for (rank, r) in rows.iter().filter(|r| r.rel_mse().is_some()).take(count).enumerate() {
            copy(&r.scene, format!("{}-{}-{}.toml", m.config, rank + 1, r.scene))?;
        }
        for r in rows.iter().filter(|r| r.status.is_failure()) {
            copy(&r.scene, format!("{}-failed-{}.toml", m.config, r.scene))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(index: u64, config: &str, theme: &str, status: Status, rel: Option<f64>, ratio: f64) -> Row {
        Row {
            seed: 1,
            index,
            scene: format!("s{index}"),
            theme: theme.into(),
            config: config.into(),
            status,
            reference: "direct, 64 spp".into(),
            frame_ms: 2.0,
            bake_ms: 10.0,
            metrics: rel.map(|rel_mse| Metrics {
                rmse: 0.1,
                rel_mse,
                mean_bias: f64::NAN,
                p99_abs_error: f64::NAN,
                max_abs_error: f64::NAN,
                flip_mean: 0.05,
                mean_ratio: ratio,
                scaled_rel_rmse: 0.2,
                pixels: 0,
            }),
            noise_rel_mse: 1e-5,
            direct_alone: None,
            warnings: vec!["a, b".into()],
            provenance: Provenance {
                device: "llvmpipe (LLVM 15, 256 bits)".into(),
                driver: "llvmpipe Mesa".into(),
                commit: "abc".into(),
                date: "2026-12-05".into(),
            },
        }
    }

    /// The CSV reads back the values the summary uses; quantiles, counts and the radiosity
    /// target over hand-made rows.
    #[test]
    fn csv_round_trips_and_targets_count_scenes() {
        let rows = vec![
            row(0, "radiosity", "lamps", Status::Ok, Some(0.004), 1.01),
            row(1, "radiosity", "sun", Status::Ok, Some(0.02), 0.99),
            row(2, "radiosity", "courtyard", Status::Ok, Some(0.5), 0.5),
            row(
                3,
                "radiosity",
                "lamps",
                Status::Refused("too big".into()),
                None,
                f64::NAN,
            ),
            row(
                4,
                "forward",
                "lamps",
                Status::NonFinite("pixel (1, 2)".into()),
                None,
                f64::NAN,
            ),
        ];
        let back = parse_csv(&csv(&rows), "t.csv").unwrap();
        assert_eq!(back.len(), rows.len());
        assert_eq!(back[0].rel_mse(), Some(0.004));
        assert_eq!(back[0].warnings, vec!["a; b".to_string()]);
        assert_eq!(back[4].status, Status::NonFinite("pixel (1; 2)".into()));
        let s = summarise(back);
        let radiosity = s.methods.iter().find(|m| m.config == "radiosity").unwrap();
        assert_eq!((radiosity.scenes, radiosity.ok, radiosity.refused), (4, 3, 1));
        assert_eq!(radiosity.rel_mse_median, 0.02);
        assert_eq!(radiosity.worst, Some(("s2".into(), 0.5)));
        // Room scenes only, refusals aside: lamps holds, sun misses its relative MSE.
        let t = &s.targets[0];
        assert_eq!((t.applies, t.holds, t.met()), (2, 1, false));
        let every = s.targets.last().unwrap();
        assert_eq!((every.applies, every.holds), (5, 4));
        assert!(
            s.markdown().contains("| radiosity | 4 | 3 | 1 | 0 | 2.00e-2 |"),
            "{}",
            s.markdown()
        );
    }

    /// A direct method's row that warned it dropped light is set aside by its target, named in
    /// the summary, and not counted; one without warnings is judged.
    #[test]
    fn direct_targets_set_aside_rows_that_dropped_light() {
        let mut clean = row(0, "vls", "lamps", Status::Ok, Some(5e-4), 1.0);
        clean.warnings.clear();
        let crowded = row(1, "vls", "crowd", Status::Ok, Some(2e-2), 0.83);
        let s = summarise(vec![clean, crowded]);
        let t = s.targets.iter().find(|t| t.name.starts_with("vls:")).unwrap();
        assert_eq!((t.applies, t.holds), (1, 1));
        assert_eq!(t.set_aside, vec!["s1 vls: a, b".to_string()]);
        assert!(
            s.markdown().contains("  - not judged, the method warned: s1 vls: a, b"),
            "{}",
            s.markdown()
        );
    }

    #[test]
    fn quantiles_are_nearest_rank() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(quantile(&v, 0.5), 5.0);
        assert_eq!(quantile(&v, 0.9), 9.0);
        assert_eq!(quantile(&v, 1.0), 10.0);
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
