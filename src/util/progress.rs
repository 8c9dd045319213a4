//! A progress line for long work (bakes, the reference, the chart): rate, elapsed and remaining
//! time, on stderr only when stderr is a terminal and only once the work has taken more than a
//! second.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

pub struct Progress {
    name: String,
    start: Instant,
    last: Option<Instant>,
    shown: bool,
    terminal: bool,
    /// Shown after the counts (e.g. a solve's remaining energy).
    detail: String,
}

impl Progress {
    pub fn new(name: &str) -> Progress {
        Progress {
            name: name.to_string(),
            start: Instant::now(),
            last: None,
            shown: false,
            terminal: std::io::stderr().is_terminal(),
            detail: String::new(),
        }
    }

    /// Text shown at the end of the line from the next update on.
    pub fn set_detail(&mut self, detail: String) {
        self.detail = detail;
    }

    /// `done` of `total` units finished.
    pub fn update(&mut self, done: u64, total: u64) {
        let now = Instant::now();
        let elapsed = now - self.start;
        if !self.terminal
            || elapsed < Duration::from_secs(1)
            || self.last.is_some_and(|l| now - l < Duration::from_millis(200))
        {
            return;
        }
        self.last = Some(now);
        self.shown = true;
        let detail = if self.detail.is_empty() {
            String::new()
        } else {
            format!(", {}", self.detail)
        };
        crate::err!("\r{}{detail}\x1b[K", line(&self.name, done, total, elapsed));
        let _ = std::io::stderr().flush();
    }

    /// Ends the line if one was shown.
    pub fn finish(&mut self) {
        if self.shown {
            crate::errln!();
            self.shown = false;
        }
    }
}

/// `name: 40% (400/1000) 123.4/s, 3.2 s elapsed, 4.9 s left`.
pub fn line(name: &str, done: u64, total: u64, elapsed: Duration) -> String {
    let secs = elapsed.as_secs_f64().max(1e-9);
    let rate = done as f64 / secs;
    let pct = if total > 0 {
        100.0 * done as f64 / total as f64
    } else {
        0.0
    };
    let left = if done > 0 {
        (total.saturating_sub(done)) as f64 / rate
    } else {
        f64::NAN
    };
    format!("{name}: {pct:3.0}% ({done}/{total}) {rate:.1}/s, {secs:.1} s elapsed, {left:.1} s left")
}
