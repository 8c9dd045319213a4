//! `penumbra report` opened in a real browser: headless Chromium, driven through the Chrome
//! DevTools Protocol over its pipe (NUL-terminated JSON messages), loads a small report from
//! disk and the test checks what a reader would meet: every resource there and no console
//! error, one figure and one chart marker per configuration measured, a hover naming its
//! configuration, the one-click time budget picking the right one, and a screenshot.

use crate::support as common;

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

use serde_json::{json, Value};

/// The browser: $PENUMBRA_CHROMIUM, else the first of the usual names on the PATH.
fn chromium() -> PathBuf {
    if let Ok(p) = std::env::var("PENUMBRA_CHROMIUM") {
        return PathBuf::from(p);
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"] {
        for dir in std::env::split_paths(&path) {
            let candidate = dir.join(name);
            if candidate.is_file() {
                return candidate;
            }
        }
    }
    panic!("no Chromium found (looked for chromium, chromium-browser, google-chrome on the PATH, and $PENUMBRA_CHROMIUM); tools/setup.sh installs Debian's chromium package");
}

/// A headless browser driven over the DevTools protocol, attached to one page.
struct Browser {
    child: Child,
    input: ChildStdin,
    messages: Receiver<Value>,
    next_id: u64,
    /// The protocol's id of the attached page (its `sessionId`), once attached.
    page: Option<String>,
    /// Every event seen so far, in order.
    events: Vec<Value>,
}

impl Browser {
    /// Starts Chromium with DevTools on fds 3 (commands in) and 4 (replies out): a shell puts
    /// this process's pipes there, so no unsafe code is needed to arrange the descriptors.
    fn launch(profile: &Path) -> Browser {
        std::fs::create_dir_all(profile).expect("make the browser's profile dir");
        let mut child = Command::new("bash")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" 3<&0 4>&1 0</dev/null 1>/dev/null")
            .arg(chromium())
            .args([
                "--headless=new",
                "--remote-debugging-pipe",
                "--no-sandbox",
                "--disable-gpu",
                "--no-first-run",
                "--disable-extensions",
                "--hide-scrollbars",
                &format!("--user-data-dir={}", profile.display()),
            ])
            // Chromium's own scratch files (org.chromium.Chromium.*) go with the profile.
            .env("TMPDIR", profile)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start chromium");
        let input = child.stdin.take().unwrap();
        let output = child.stdout.take().unwrap();
        let (tx, messages) = channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(output);
            let mut buf = Vec::new();
            while reader.read_until(0, &mut buf).map(|n| n > 0).unwrap_or(false) {
                buf.pop();
                if let Ok(v) = serde_json::from_slice::<Value>(&buf) {
                    if tx.send(v).is_err() {
                        break;
                    }
                }
                buf.clear();
            }
        });
        Browser {
            child,
            input,
            messages,
            next_id: 1,
            page: None,
            events: Vec::new(),
        }
    }

    fn next(&mut self, what: &str) -> Value {
        self.messages
            .recv_timeout(Duration::from_secs(60))
            .unwrap_or_else(|_| panic!("Chromium sent nothing for 60 s while waiting for {what}"))
    }

    /// Sends a command (to the attached page once there is one) and returns its result.
    fn call(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let mut msg = json!({ "id": id, "method": method, "params": params });
        if let Some(s) = &self.page {
            msg["sessionId"] = json!(s);
        }
        self.input.write_all(msg.to_string().as_bytes()).unwrap();
        self.input.write_all(&[0]).unwrap();
        self.input.flush().unwrap();
        loop {
            let v = self.next(method);
            if v["id"] == json!(id) {
                assert!(v.get("error").is_none(), "{method}: {}", v["error"]);
                return v["result"].clone();
            }
            self.events.push(v);
        }
    }

    fn wait_for_event(&mut self, method: &str) {
        if self.events.iter().any(|e| e["method"] == method) {
            return;
        }
        loop {
            let v = self.next(method);
            let found = v["method"] == method;
            self.events.push(v);
            if found {
                return;
            }
        }
    }

    /// A JavaScript expression's value in the page.
    fn eval(&mut self, expression: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({ "expression": expression, "returnByValue": true, "awaitPromise": true }),
        );
        assert!(
            r.get("exceptionDetails").is_none(),
            "{expression}: {}",
            r["exceptionDetails"]
        );
        r["result"]["value"].clone()
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64) {
        let mut params = json!({ "type": kind, "x": x, "y": y });
        if kind != "mouseMoved" {
            params["button"] = json!("left");
            params["clickCount"] = json!(1);
        }
        self.call("Input.dispatchMouseEvent", params);
    }

    /// The centre of the element `selector` names, scrolled into view, in viewport pixels.
    fn centre(&mut self, selector: &str) -> (f64, f64) {
        let r = self.eval(&format!(
            "(() => {{ const e = document.querySelector({:?}); e.scrollIntoView({{block: 'center'}}); \
             const r = e.getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; }})()",
            selector
        ));
        (r[0].as_f64().unwrap(), r[1].as_f64().unwrap())
    }

    /// Console errors, uncaught exceptions, log errors and failed loads seen so far.
    fn problems(&self) -> Vec<String> {
        self.events
            .iter()
            .filter(|e| {
                let p = &e["params"];
                match e["method"].as_str().unwrap_or("") {
                    "Runtime.consoleAPICalled" => matches!(p["type"].as_str(), Some("error" | "warning" | "assert")),
                    "Runtime.exceptionThrown" | "Network.loadingFailed" => true,
                    "Log.entryAdded" => matches!(p["entry"]["level"].as_str(), Some("error" | "warning")),
                    _ => false,
                }
            })
            .map(|e| e.to_string())
            .collect()
    }
}

impl Browser {
    /// A browser showing `page` (a file), loaded, with its events recorded.
    fn open(page: &Path) -> Browser {
        let mut browser = Browser::launch(&common::temp_path("chromium-profile"));
        let target = browser.call("Target.createTarget", json!({ "url": "about:blank" }));
        let attached = browser.call(
            "Target.attachToTarget",
            json!({ "targetId": target["targetId"], "flatten": true }),
        );
        browser.page = Some(attached["sessionId"].as_str().unwrap().to_string());
        for domain in ["Runtime", "Log", "Page", "Network"] {
            browser.call(&format!("{domain}.enable"), json!({}));
        }
        browser.call(
            "Emulation.setDeviceMetricsOverride",
            json!({ "width": 1200, "height": 900, "deviceScaleFactor": 1, "mobile": false }),
        );
        browser.call("Page.navigate", json!({ "url": format!("file://{}", page.display()) }));
        browser.wait_for_event("Page.loadEventFired");
        browser
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Standard base64 (the screenshot's encoding).
fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let digits: Vec<u8> = text
        .bytes()
        .filter(|&c| c != b'=' && !c.is_ascii_whitespace())
        .map(value)
        .collect();
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &d)| n | (d as u32) << (18 - 6 * i));
        out.extend_from_slice(&n.to_be_bytes()[1..chunk.len()]);
    }
    out
}

/// (config, frame_ms, rel_mse) of each row of the chart table the report wrote.
fn chart_rows(csv: &Path) -> Vec<(String, f64, f64)> {
    let text = std::fs::read_to_string(csv).expect("the report writes each scene's chart.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (c, t, e) = (col("config"), col("frame_ms"), col("rel_mse"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[c].to_string(), f[t].parse().unwrap(), f[e].parse().unwrap())
        })
        .collect()
}

#[test]
fn a_small_report_opens_in_chromium_clean_and_its_chart_names_what_is_hovered() {
    let dir = common::temp_path("report");
    let cache = common::temp_path("report-cache");
    let start = std::time::Instant::now();
    let out = common::penumbra(&[
        "report",
        "scenes/cornell_radiosity.toml",
        "--size",
        "48x27",
        "--reference-spp",
        "16",
        "--reference-noise",
        "0",
        "--frames",
        "3",
        "--cache-dir",
        cache.to_str().unwrap(),
        "--suite",
        SUITE_TABLE,
        "-o",
        dir.to_str().unwrap(),
    ]);
    common::ok(&out);
    eprintln!("report written in {:.1} s", start.elapsed().as_secs_f64());
    let rows = chart_rows(&dir.join("cornell_radiosity/chart.csv"));
    assert!(
        rows.len() >= 3,
        "the scene's sweep has several configurations: {rows:?}"
    );

    let mut browser = Browser::open(&dir.join("index.html"));
    // The index links the scene's page; follow the link as a reader would.
    let (x, y) = browser.centre("a[href='cornell_radiosity.html']");
    browser.events.clear();
    browser.mouse("mousePressed", x, y);
    browser.mouse("mouseReleased", x, y);
    browser.wait_for_event("Page.loadEventFired");
    assert_eq!(
        browser.eval("location.pathname.split('/').pop()"),
        json!("cornell_radiosity.html")
    );

    // Every image loaded; one figure of three pictures and one chart marker per configuration.
    let broken = browser.eval("[...document.images].filter(i => !i.complete || i.naturalWidth === 0).map(i => i.src)");
    assert_eq!(broken, json!([]), "images that did not load");
    let n = rows.len() as u64;
    assert_eq!(browser.eval("document.querySelectorAll('.config').length"), json!(n));
    assert_eq!(
        browser.eval("document.querySelectorAll('.config img').length"),
        json!(3 * n)
    );
    assert_eq!(
        browser.eval("document.querySelectorAll('#chart .point').length"),
        json!(n)
    );
    assert_eq!(
        browser.eval("document.querySelectorAll('#configs tbody tr').length"),
        json!(n)
    );

    // A real hover over the last marker shows its configuration's name.
    let last = rows.len() - 1;
    let (x, y) = browser.centre(&format!(
        "#chart .point[data-row='{last}'] :is(circle:not(.ring), polygon)"
    ));
    browser.mouse("mouseMoved", x, y);
    let tip = browser.eval("document.querySelector('#chart-tip').getAttribute('visibility') + '|' + document.querySelector('#chart-tip text').textContent");
    let tip = tip.as_str().unwrap();
    let hover = browser.call("Page.captureScreenshot", json!({ "format": "png" }));
    let hover_path = common::temp_path("report-hover.png");
    std::fs::write(&hover_path, base64_decode(hover["data"].as_str().unwrap())).unwrap();
    eprintln!("hover screenshot: {}", hover_path.display());
    assert!(tip.starts_with("visible|"), "{tip}");
    assert!(
        tip.contains(&rows[last].0.replace(';', ",")),
        "hovering marker {last} names `{}`: {tip}",
        rows[last].0
    );

    // One click on the 10 ms budget names the most accurate configuration within it.
    let best = rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.1 <= 10.0)
        .min_by(|a, b| a.1 .2.total_cmp(&b.1 .2));
    let (x, y) = browser.centre("button.budget[data-budget='10']");
    browser.mouse("mousePressed", x, y);
    browser.mouse("mouseReleased", x, y);
    let result = browser.eval("document.getElementById('best-result').textContent");
    let result = result.as_str().unwrap();
    match best {
        Some((i, r)) => {
            assert!(
                result.contains(&format!("#{} {}", i + 1, r.0.replace(';', ","))),
                "{result}"
            );
            assert_eq!(
                browser.eval("[...document.querySelectorAll('#chart .point.selected')].map(p => p.dataset.row)"),
                json!([i.to_string()])
            );
        }
        None => assert!(result.starts_with("No configuration"), "{result}"),
    }

    let shot = browser.call(
        "Page.captureScreenshot",
        json!({ "format": "png", "captureBeyondViewport": true }),
    );
    let png = base64_decode(shot["data"].as_str().unwrap());
    let image = image::load_from_memory(&png)
        .expect("the screenshot is a PNG")
        .to_rgb8();
    let path = common::temp_path("report-screenshot.png");
    image.save(&path).unwrap();
    let colours: std::collections::HashSet<[u8; 3]> = image.pixels().map(|p| p.0).collect();
    assert!(
        image.width() >= 1000 && image.height() > 900 && colours.len() > 500,
        "the screenshot ({}x{}, {} colours, {}) shows a page with pictures",
        image.width(),
        image.height(),
        colours.len(),
        path.display()
    );
    eprintln!("screenshot: {}", path.display());
    let problems = browser.problems();
    assert!(
        problems.is_empty(),
        "console errors or failed loads:\n{}",
        problems.join("\n")
    );

    // The checks above see a missing resource: with one map gone, the reload reports it.
    std::fs::remove_file(dir.join("cornell_radiosity/config01-flip.png")).unwrap();
    browser.events.clear();
    browser.call("Page.reload", json!({}));
    browser.wait_for_event("Page.loadEventFired");
    let broken = browser.eval("[...document.images].filter(i => !i.complete || i.naturalWidth === 0).length");
    assert_eq!(broken, json!(1), "the removed map is seen as not loaded");
    assert!(
        !browser.problems().is_empty(),
        "the removed map is reported as a failed load"
    );
    suite_page_opens_with_its_summary(&mut browser, &dir);
}

/// A committed table of the generated-scene suite (12 scenes, leading `#` provenance lines).
const SUITE_TABLE: &str = "docs/results/lavapipe/suite_seed1_n12_32x24.csv";

/// The suite's page, reached from the index: its provenance, one summary row per configuration,
/// the targets, one row per table row, sortable, with no console error.
fn suite_page_opens_with_its_summary(browser: &mut Browser, dir: &Path) {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(SUITE_TABLE)).unwrap();
    let data: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let configs: std::collections::BTreeSet<&str> = data.iter().map(|f| f[4]).collect();
    browser.events.clear();
    browser.call(
        "Page.navigate",
        json!({ "url": format!("file://{}", dir.join("index.html").display()) }),
    );
    browser.wait_for_event("Page.loadEventFired");
    let (x, y) = browser.centre("a[href='generated_suite.html']");
    browser.events.clear();
    browser.mouse("mousePressed", x, y);
    browser.mouse("mouseReleased", x, y);
    browser.wait_for_event("Page.loadEventFired");
    assert_eq!(
        browser.eval("document.querySelectorAll('#suite-methods tbody tr').length"),
        json!(configs.len())
    );
    assert_eq!(
        browser.eval("document.querySelectorAll('#suite-rows tbody tr').length"),
        json!(data.len())
    );
    let meta = browser.eval("document.querySelector('p.meta + p.meta').textContent");
    assert!(meta.as_str().unwrap().contains("device: llvmpipe"), "{meta}");
    let targets = browser.eval("[...document.querySelectorAll('#suite-targets > li > b')].map(b => b.textContent)");
    assert!(
        targets.as_array().unwrap().iter().any(|t| t == "NOT met"),
        "the table's unmet targets are shown: {targets}"
    );
    // The summary's first column holds each configuration once, as the table names them.
    let names = browser
        .eval("[...document.querySelectorAll('#suite-methods tbody tr td:first-child')].map(t => t.textContent)");
    let names: std::collections::BTreeSet<String> = names
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_owned())
        .collect();
    assert_eq!(names, configs.iter().map(|c| c.to_string()).collect());
    // Sorting by relative MSE (a header click) puts the smallest first.
    let (x, y) = browser.centre("#suite-rows thead th:nth-child(5)");
    browser.mouse("mousePressed", x, y);
    browser.mouse("mouseReleased", x, y);
    let first =
        browser.eval("parseFloat(document.querySelector('#suite-rows tbody tr td:nth-child(5)').dataset.value)");
    let smallest = data
        .iter()
        .filter_map(|f| f[9].parse::<f64>().ok())
        .fold(f64::INFINITY, f64::min);
    assert!(
        (first.as_f64().unwrap() - smallest).abs() <= 1e-12 * smallest.abs().max(1.0),
        "{first} vs {smallest}"
    );
    let problems = browser.problems();
    assert!(problems.is_empty(), "suite page:\n{}", problems.join("\n"));
}

/// A report made beforehand (`PENUMBRA_REPORT_PAGE`: a scene's page) opens clean: every image
/// loads, no console error or failed load, one marker per row of its chart.csv.
#[test]
#[ignore = "needs PENUMBRA_REPORT_PAGE, a report made with penumbra report"]
fn a_given_report_page_opens_clean() {
    let page = PathBuf::from(std::env::var("PENUMBRA_REPORT_PAGE").expect("set PENUMBRA_REPORT_PAGE"));
    let page = page.canonicalize().expect("the page exists");
    let stem = page.file_stem().unwrap().to_string_lossy().to_string();
    let rows = chart_rows(&page.with_file_name(&stem).join("chart.csv"));
    let mut browser = Browser::open(&page);
    let broken = browser.eval("[...document.images].filter(i => !i.complete || i.naturalWidth === 0).map(i => i.src)");
    assert_eq!(broken, json!([]), "images that did not load");
    assert_eq!(
        browser.eval("document.querySelectorAll('#chart .point').length"),
        json!(rows.len())
    );
    let problems = browser.problems();
    assert!(
        problems.is_empty(),
        "console errors or failed loads:\n{}",
        problems.join("\n")
    );
    eprintln!(
        "{}: {} configurations, every image loaded, no console error",
        page.display(),
        rows.len()
    );
}
