//! Printing that never panics. `println!` panics when standard output is a closed pipe
//! (`penumbra info | head -1`); these write through a handle instead. On standard output a
//! closed pipe is not an error: the command still does its work (files are written), and what
//! it would have printed simply has no reader. Any other write failure (a full disk behind a
//! redirection, or standard output closed from the start) is remembered and reported by `main`
//! as the command's error. Standard error
//! (progress, validation messages, the error line itself) is best effort.

use std::fmt;
use std::io::{ErrorKind, Write};
use std::sync::Mutex;

static STDOUT_FAILURE: Mutex<Option<String>> = Mutex::new(None);

/// Writes to standard output (see the module doc for failures).
pub fn out(args: fmt::Arguments<'_>) {
    if stdout_was_closed() {
        remember("standard output is closed: nothing printed could be read".to_string());
        return;
    }
    let mut o = std::io::stdout().lock();
    if let Err(e) = o.write_fmt(args).and_then(|_| o.flush()) {
        if e.kind() != ErrorKind::BrokenPipe {
            remember(format!("standard output: {e}"));
        }
    }
}

fn remember(failure: String) {
    if let Ok(mut f) = STDOUT_FAILURE.lock() {
        f.get_or_insert(failure);
    }
}

/// Whether the process started with standard output closed (`>&-`). The Rust runtime then opens
/// `/dev/null` read-write in its place, so writes succeed and would vanish without a word; a
/// shell's `>/dev/null` opens it write-only, which this tells apart (Linux: `/proc/self`).
fn stdout_was_closed() -> bool {
    static CLOSED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *CLOSED.get_or_init(|| {
        let null = std::fs::read_link("/proc/self/fd/1").is_ok_and(|p| p == std::path::Path::new("/dev/null"));
        let read_write = std::fs::read_to_string("/proc/self/fdinfo/1").is_ok_and(|info| {
            info.lines()
                .find_map(|l| l.strip_prefix("flags:"))
                .and_then(|f| u32::from_str_radix(f.trim(), 8).ok())
                .is_some_and(|flags| flags & 0o3 == 0o2)
        });
        null && read_write
    })
}

/// Writes to standard error, ignoring failures.
pub fn err(args: fmt::Arguments<'_>) {
    let _ = std::io::stderr().lock().write_fmt(args);
}

/// The first failure to write standard output other than a closed pipe.
pub fn stdout_failure() -> Option<String> {
    STDOUT_FAILURE.lock().ok().and_then(|f| f.clone())
}

/// `println!` to standard output without the panic on a closed pipe.
#[macro_export]
macro_rules! outln {
    () => { $crate::util::console::out(format_args!("\n")) };
    ($($t:tt)*) => { $crate::util::console::out(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` to standard output without the panic on a closed pipe.
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::util::console::out(format_args!($($t)*)) };
}

/// `eprintln!` without the panic on a closed standard error.
#[macro_export]
macro_rules! errln {
    () => { $crate::util::console::err(format_args!("\n")) };
    ($($t:tt)*) => { $crate::util::console::err(format_args!("{}\n", format_args!($($t)*))) };
}

/// `eprint!` without the panic on a closed standard error.
#[macro_export]
macro_rules! err {
    ($($t:tt)*) => { $crate::util::console::err(format_args!($($t)*)) };
}
