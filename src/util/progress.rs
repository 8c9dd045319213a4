//! A progress line for long work (bakes, the reference, the chart): rate, elapsed and remaining
//! time on stderr. On a terminal one line redrawn in place once the work has taken more than a
//! second; otherwise (a log, a pipe) nothing for the first ten seconds, then one line every five,
//! so a long bake is never silent. Either way, once two seconds of work give a rate, work that
//! will take over a minute in all says so once, with the estimate. Work that can time a small
//! sample of itself before it starts says so earlier ([`Progress::warn_before`]), and the rate's
//! warning then stays quiet.

use std::cell::RefCell;
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// One update of a progress line, as an observer sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct Update {
    pub name: String,
    pub done: u64,
    /// 0 when the work has just started and its size is not known yet.
    pub total: u64,
    /// Since this piece of work started.
    pub elapsed: Duration,
}

/// Receives the updates of every progress line made on a thread (the demo's panel follows a
/// bake running on another thread this way), besides what they write to stderr.
pub type Observer = Arc<dyn Fn(&Update) + Send + Sync>;

/// A request to stop long work, shared between the thread that asks and the thread (and its
/// workers) that does the work, which looks at it between batches.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Asks the work to stop; it does so at its next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

thread_local! {
    static OBSERVER: RefCell<Option<Observer>> = const { RefCell::new(None) };
    static CANCEL: RefCell<Option<Cancel>> = const { RefCell::new(None) };
}

/// Sets (or clears) the observer of the progress lines made on this thread from now on.
pub fn observe_this_thread(observer: Option<Observer>) {
    OBSERVER.with(|o| *o.borrow_mut() = observer);
}

/// Sets (or clears) the cancellation that the progress lines made on this thread from now on
/// report ([`Progress::cancelled`]): the demo's background bakes stop through it.
pub fn cancel_this_thread(cancel: Option<Cancel>) {
    CANCEL.with(|c| *c.borrow_mut() = cancel);
}

/// Whether the work on this thread was asked to stop.
pub fn this_thread_cancelled() -> bool {
    CANCEL.with(|c| c.borrow().as_ref().is_some_and(Cancel::is_cancelled))
}

pub struct Progress {
    name: String,
    start: Instant,
    /// Elapsed time at the last line shown.
    last: Option<Duration>,
    shown: bool,
    terminal: bool,
    warned: bool,
    /// Shown after the counts (e.g. a solve's remaining energy).
    detail: String,
    /// The observer of the thread this line was made on (updates may come from others).
    observer: Option<Observer>,
    /// The cancellation of the thread this line was made on.
    cancel: Option<Cancel>,
    /// Writes nothing and tells no observer (a calibration's run of the real work).
    quiet: bool,
    /// Elapsed time at the last update of 0 done, or at the end of the last stage before any
    /// update: the rate is taken from there, so that stages before the counted work (a solve's
    /// set-up) do not count as its time.
    counting_since: Duration,
    /// Whether an update has come: stages after it no longer move `counting_since`.
    counting: bool,
}

/// A terminal's line appears after this much work, and is redrawn at most this often.
const TERMINAL_AFTER: Duration = Duration::from_secs(1);
const TERMINAL_EVERY: Duration = Duration::from_millis(200);
/// Without a terminal, lines appear after this much work, one per period.
const LOG_AFTER: Duration = Duration::from_secs(10);
const LOG_EVERY: Duration = Duration::from_secs(5);
/// The estimate is made once this much work gives a rate, and warned about over the limit.
const ESTIMATE_AFTER: Duration = Duration::from_secs(2);
const ESTIMATE_LIMIT: Duration = Duration::from_secs(60);

/// A long piece of work's time, estimated before it starts from the work itself: its units
/// counted, a few of them timed.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub seconds: f64,
    /// How it was made (what was timed, the time per unit).
    pub method: String,
    /// The stage that dominates it, with its work.
    pub dominant: String,
    /// The settings that make it cheaper.
    pub remedy: String,
}

impl Progress {
    pub fn new(name: &str) -> Progress {
        Progress::to(name, std::io::stderr().is_terminal())
    }

    /// A progress line written as to a terminal (`terminal`) or to a log.
    pub fn to(name: &str, terminal: bool) -> Progress {
        let p = Progress::made(name, terminal, false);
        p.notify(0, 0);
        p
    }

    fn made(name: &str, terminal: bool, quiet: bool) -> Progress {
        Progress {
            name: name.to_string(),
            start: Instant::now(),
            last: None,
            shown: false,
            terminal,
            warned: false,
            detail: String::new(),
            observer: if quiet {
                None
            } else {
                OBSERVER.with(|o| o.borrow().clone())
            },
            cancel: CANCEL.with(|c| c.borrow().clone()),
            counting_since: Duration::ZERO,
            counting: false,
            quiet,
        }
    }

    /// A line that shows nothing, for work timed to estimate other work; it still reports the
    /// thread's cancellation.
    pub fn quiet(name: &str) -> Progress {
        Progress::made(name, false, true)
    }

    fn notify(&self, done: u64, total: u64) {
        if let Some(o) = &self.observer {
            o(&Update {
                name: self.name.clone(),
                done,
                total,
                elapsed: self.start.elapsed(),
            });
        }
    }

    /// Whether the work this line follows was asked to stop: long work looks between batches
    /// and ends early, and the bake it is part of fails as cancelled (nothing is cached).
    pub fn cancelled(&self) -> bool {
        self.cancel.as_ref().is_some_and(Cancel::is_cancelled)
    }

    /// The cancellation, for worker threads of the work to look at (`None`: it cannot be
    /// cancelled).
    pub fn cancellation(&self) -> Option<Cancel> {
        self.cancel.clone()
    }

    /// Text shown at the end of the line from the next update on.
    pub fn set_detail(&mut self, detail: String) {
        self.detail = detail;
    }

    /// `done` of `total` units finished.
    pub fn update(&mut self, done: u64, total: u64) {
        if self.quiet {
            return;
        }
        self.notify(done, total);
        let text = self.text_at(self.start.elapsed(), done, total);
        if !text.is_empty() {
            crate::err!("{text}");
            let _ = std::io::stderr().flush();
        }
    }

    /// What an update `elapsed` into the work writes to stderr (empty: nothing).
    pub fn text_at(&mut self, elapsed: Duration, done: u64, total: u64) -> String {
        let mut text = String::new();
        if done == 0 {
            self.counting_since = elapsed;
        }
        self.counting = true;
        let counting = elapsed.saturating_sub(self.counting_since);
        if !self.warned && counting >= ESTIMATE_AFTER && done > 0 && done < total {
            self.warned = true;
            let all = elapsed + counting.mul_f64((total - done) as f64 / done as f64);
            if all > ESTIMATE_LIMIT {
                let clear = if self.shown { "\r\x1b[K" } else { "" };
                text += &format!(
                    "{clear}warning: {}: about {} in all at the rate so far ({:.0}% after {:.1} s)\n",
                    self.name,
                    duration_words(all),
                    100.0 * done as f64 / total as f64,
                    elapsed.as_secs_f64()
                );
            }
        }
        let (after, every) = if self.terminal {
            (TERMINAL_AFTER, TERMINAL_EVERY)
        } else {
            (LOG_AFTER, LOG_EVERY)
        };
        if elapsed < after || self.last.is_some_and(|l| elapsed - l < every) {
            return text;
        }
        self.last = Some(elapsed);
        let detail = if self.detail.is_empty() {
            String::new()
        } else {
            format!(", {}", self.detail)
        };
        let body = line_counting(&self.name, done, total, elapsed, counting);
        if self.terminal {
            self.shown = true;
            text += &format!("\r{body}{detail}\x1b[K");
        } else {
            text += &format!("{body}{detail}\n");
        }
        text
    }

    /// Warns once, in one line, when `estimate` passes a minute: before the work starts, so the
    /// warning comes before the work would end. The rate's own warning then says nothing more.
    pub fn warn_before(&mut self, estimate: &Estimate) {
        if self.quiet {
            return;
        }
        let text = self.estimate_text(estimate);
        if !text.is_empty() {
            crate::err!("{text}");
            let _ = std::io::stderr().flush();
        }
    }

    /// What [`Progress::warn_before`] writes (empty: nothing).
    pub fn estimate_text(&mut self, e: &Estimate) -> String {
        if self.warned || e.seconds.is_nan() || e.seconds <= ESTIMATE_LIMIT.as_secs_f64() {
            return String::new();
        }
        self.warned = true;
        let clear = if self.shown { "\r\x1b[K" } else { "" };
        format!(
            "{clear}warning: {}: about {} in all, estimated before it starts ({}); {} dominates: {} cut it\n",
            self.name,
            duration_words(Duration::from_secs_f64(e.seconds.min(1e9))),
            e.method,
            e.dominant,
            e.remedy
        )
    }

    /// Runs `what`, a stage of this work that reports no progress of its own: once the work has
    /// passed ten seconds, a line every five names the stage and the time so far (terminal or
    /// not), so a long stage is never silent.
    pub fn stage<T>(&mut self, what: &str, work: impl FnOnce() -> T) -> T {
        if self.quiet {
            return work();
        }
        let (stop, stopped) = std::sync::mpsc::channel::<()>();
        let (name, start) = (self.name.as_str(), self.start);
        let out = std::thread::scope(|scope| {
            scope.spawn(move || {
                let mut next = LOG_AFTER;
                loop {
                    let wait = next.saturating_sub(start.elapsed());
                    if stopped.recv_timeout(wait) != Err(std::sync::mpsc::RecvTimeoutError::Timeout) {
                        return;
                    }
                    let elapsed = start.elapsed();
                    if elapsed >= next {
                        crate::errln!("{name}: {what}, {:.1} s elapsed", elapsed.as_secs_f64());
                        next = elapsed + LOG_EVERY;
                    }
                }
            });
            let out = work();
            drop(stop);
            out
        });
        // Set-up before the count: the count's rate is timed from here even when its first
        // update comes after some of it is done.
        if !self.counting {
            self.counting_since = self.start.elapsed();
        }
        out
    }

    /// Ends the line if one was shown.
    pub fn finish(&mut self) {
        if self.shown {
            crate::errln!();
            self.shown = false;
        }
    }
}

/// `75 s`, `12.5 min`, `3.2 h`.
fn duration_words(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// `name: 40% (400/1000) 123.4/s, 3.2 s elapsed, 4.9 s left`.
pub fn line(name: &str, done: u64, total: u64, elapsed: Duration) -> String {
    line_counting(name, done, total, elapsed, elapsed)
}

/// [`line`] with the rate and the time left from the last `counting` of the `elapsed` time.
fn line_counting(name: &str, done: u64, total: u64, elapsed: Duration, counting: Duration) -> String {
    let secs = elapsed.as_secs_f64().max(1e-9);
    let rate = done as f64 / counting.as_secs_f64().max(1e-9);
    let pct = if total > 0 {
        100.0 * done as f64 / total as f64
    } else {
        0.0
    };
    if done == 0 {
        // No rate yet: nothing to say of the time left.
        return format!(
            "{name}: {pct:3.0}% (0/{}), {secs:.1} s elapsed",
            count_words(total as f64, 0)
        );
    }
    let left = (total.saturating_sub(done)) as f64 / rate;
    let left = if left >= 120.0 {
        duration_words(Duration::from_secs_f64(left.min(1e9)))
    } else {
        format!("{left:.1} s")
    };
    format!(
        "{name}: {pct:3.0}% ({}/{}) {}/s, {secs:.1} s elapsed, {left} left",
        count_words(done as f64, 0),
        count_words(total as f64, 0),
        count_words(rate, 1)
    )
}

/// A count as read at a glance: as it is under 100,000 (with `decimals`), else to three figures
/// in thousands, millions or billions (a shadow pass's 85,115,968 pairs: "85.1 M").
fn count_words(n: f64, decimals: usize) -> String {
    let three = |x: f64, unit: &str| match x {
        x if x < 10.0 => format!("{x:.2} {unit}"),
        x if x < 100.0 => format!("{x:.1} {unit}"),
        x => format!("{x:.0} {unit}"),
    };
    match n {
        n if n < 1e5 => format!("{n:.decimals$}"),
        n if n < 1e6 => three(n / 1e3, "k"),
        n if n < 1e9 => three(n / 1e6, "M"),
        n => three(n / 1e9, "G"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: fn(f64) -> Duration = Duration::from_secs_f64;

    /// Large counts and long times are written as read: a shadow pass's pairs in millions, the
    /// time left in minutes or hours; small ones as they are.
    #[test]
    fn large_counts_and_long_times_read_at_a_glance() {
        assert_eq!(
            line_counting("bsp", 5_651_797, 85_115_968, S(10.0), S(8.0)),
            "bsp:   7% (5.65 M/85.1 M) 706 k/s, 10.0 s elapsed, 112.5 s left"
        );
        assert_eq!(
            line_counting("bsp", 1_000_000, 85_115_968, S(10.0), S(10.0)),
            "bsp:   1% (1.00 M/85.1 M) 100 k/s, 10.0 s elapsed, 14.0 min left"
        );
        assert_eq!(
            line_counting("rays", 6_000_000_000, 9_000_000_000, S(100.0), S(100.0)),
            "rays:  67% (6.00 G/9.00 G) 60.0 M/s, 100.0 s elapsed, 50.0 s left"
        );
        assert_eq!(
            line("bake", 400, 1000, S(3.2)),
            "bake:  40% (400/1000) 125.0/s, 3.2 s elapsed, 4.8 s left"
        );
        assert_eq!(count_words(99_999.0, 0), "99999");
        assert_eq!(count_words(123_456.0, 0), "123 k");
    }

    /// Without a terminal: silent for ten seconds, then a whole line every five seconds.
    #[test]
    fn a_log_gets_a_line_every_five_seconds_after_ten() {
        let mut p = Progress::to("bake", false);
        let shown: Vec<f64> = (0..=60)
            .map(|t| t as f64 * 0.5)
            .filter(|&t| !p.text_at(S(t), 1, 1).is_empty())
            .collect();
        assert_eq!(shown, vec![10.0, 15.0, 20.0, 25.0, 30.0]);
        let mut p = Progress::to("bake", false);
        let text = p.text_at(S(12.0), 1, 1);
        assert!(
            text.starts_with("bake: 100% (1/1)") && text.ends_with('\n') && !text.contains('\r'),
            "{text:?}"
        );
    }

    /// On a terminal: the redrawn line after a second, at most five times a second.
    #[test]
    fn a_terminal_gets_a_redrawn_line_after_one_second() {
        let mut p = Progress::to("bake", true);
        assert!(p.text_at(S(0.9), 1, 1).is_empty());
        assert!(p.text_at(S(1.0), 1, 1).starts_with("\rbake:"));
        assert!(p.text_at(S(1.1), 1, 1).is_empty());
        assert!(p.text_at(S(1.3), 1, 1).starts_with("\rbake:"));
    }

    /// Work that will take over a minute says so once, with the estimate from the rate so far;
    /// work that will not says nothing.
    #[test]
    fn long_work_is_warned_about_once_with_its_estimate() {
        let mut p = Progress::to("radiosity", false);
        assert!(p.text_at(S(1.0), 1, 100).is_empty(), "no estimate before two seconds");
        let text = p.text_at(S(2.0), 2, 100);
        assert_eq!(
            text,
            "warning: radiosity: about 100 s in all at the rate so far (2% after 2.0 s)\n"
        );
        assert!(p.text_at(S(3.0), 3, 100).is_empty(), "warned once");
        let mut quick = Progress::to("radiosity", false);
        assert!(quick.text_at(S(2.0), 50, 100).is_empty(), "4 s in all");
        assert!(quick.text_at(S(2.5), 51, 100).is_empty());
    }

    /// Work that starts counting after stages of its own (a solve after its set-up) is timed
    /// from its last update of 0 done, not from the start: 4 s of set-up and then a unit a
    /// second is not 300 s for 100 units.
    #[test]
    fn the_rate_counts_from_the_last_update_of_none_done() {
        let mut p = Progress::to("radiosity", false);
        assert!(p.text_at(S(4.0), 0, 100).is_empty());
        assert!(
            p.text_at(S(5.0), 1, 100).is_empty(),
            "no estimate before two seconds of it"
        );
        assert_eq!(
            p.text_at(S(6.0), 2, 100),
            "warning: radiosity: about 104 s in all at the rate so far (2% after 6.0 s)\n"
        );
        assert_eq!(
            p.text_at(S(10.0), 6, 100),
            "radiosity:   6% (6/100) 1.0/s, 10.0 s elapsed, 94.0 s left\n"
        );
    }

    /// A count whose first update comes after some work (no update of 0 done) is timed from the
    /// end of the stages before it: the light-map's visibility after 25 s of set-up read "about
    /// 29.8 min in all" at 1% done, for a bake that took 45 s. Stages after the count has begun
    /// leave its rate alone.
    #[test]
    fn the_rate_counts_from_the_end_of_the_stages_before_the_count() {
        let mut p = Progress::to("bake", false);
        p.stage("set-up", || std::thread::sleep(Duration::from_millis(500)));
        let since = p.counting_since;
        assert!(since >= Duration::from_millis(500), "{since:?}");
        // 10 of 270 in the 2 s after the set-up: about 55 s in all. Timed from the start, the
        // rate would say 68 s, over the minute.
        assert!(p.text_at(since + Duration::from_secs(2), 10, 270).is_empty());
        p.stage("borders", || ());
        assert_eq!(p.counting_since, since, "a stage after the count began");
        // At 0 done there is no rate: the line says no time left (it read "NaN s left").
        assert_eq!(
            line_counting("bake", 0, 270, S(12.0), S(0.0)),
            "bake:   0% (0/270), 12.0 s elapsed"
        );
    }

    /// An estimate made before the work says so once over a minute, and the rate's warning
    /// then stays quiet; one under a minute leaves the rate's warning to speak.
    #[test]
    fn an_estimate_before_the_work_warns_once_over_a_minute() {
        let e = |seconds: f64| Estimate {
            seconds,
            method: "4 units timed: 1 s each".into(),
            dominant: "shooting (100 units)".into(),
            remedy: "fewer units".into(),
        };
        let mut p = Progress::to("radiosity", false);
        assert_eq!(
            p.estimate_text(&e(100.0)),
            "warning: radiosity: about 100 s in all, estimated before it starts (4 units timed: 1 s each); shooting (100 units) dominates: fewer units cut it\n"
        );
        assert!(p.estimate_text(&e(100.0)).is_empty(), "warned once");
        assert!(p.text_at(S(2.0), 2, 100).is_empty(), "the rate's warning stays quiet");
        let mut quick = Progress::to("radiosity", false);
        assert!(quick.estimate_text(&e(59.0)).is_empty());
        assert!(quick
            .text_at(S(2.0), 2, 100)
            .starts_with("warning: radiosity: about 100 s"));
    }

    /// A thread's observer sees the lines made on that thread (their start and every update),
    /// and no other thread's.
    #[test]
    fn an_observer_follows_the_lines_made_on_its_thread() {
        let seen = Arc::new(std::sync::Mutex::new(Vec::new()));
        let sink = seen.clone();
        observe_this_thread(Some(Arc::new(move |u: &Update| {
            sink.lock().unwrap().push((u.name.clone(), u.done, u.total))
        })));
        let mut p = Progress::to("bake", false);
        std::thread::spawn(|| Progress::to("elsewhere", false).update(1, 2))
            .join()
            .unwrap();
        p.update(3, 4);
        observe_this_thread(None);
        Progress::to("after", false).update(1, 1);
        assert_eq!(
            *seen.lock().unwrap(),
            [("bake".to_string(), 0, 0), ("bake".to_string(), 3, 4)]
        );
    }

    /// A line made on a thread with a cancellation reports it once cancelled; lines made
    /// elsewhere, or after it is cleared, never do.
    #[test]
    fn a_line_reports_its_threads_cancellation() {
        let cancel = Cancel::new();
        cancel_this_thread(Some(cancel.clone()));
        let p = Progress::to("bake", false);
        let worker = p.cancellation().expect("made under a cancellation");
        let elsewhere = std::thread::spawn(|| Progress::to("elsewhere", false)).join().unwrap();
        assert!(!p.cancelled() && !this_thread_cancelled());
        cancel.cancel();
        assert!(p.cancelled() && worker.is_cancelled() && this_thread_cancelled());
        assert!(!elsewhere.cancelled());
        cancel_this_thread(None);
        assert!(!Progress::to("after", false).cancelled() && !this_thread_cancelled());
    }
}
