//! A crash report for the test binaries. A test process killed by a signal (a fault inside the
//! Vulkan driver, the validation layer or penumbra) otherwise leaves only "signal: 11" in cargo's
//! output, with nothing to say which thread or library died. This handler prints the thread's
//! name, the faulting address, the library and symbol the program counter is in, and a raw
//! backtrace, then hands the signal back to whatever handled it before (Rust's stack-overflow
//! check, or the default action), so the process still dies by the same signal.
//!
//! Only async-signal-safe work happens in the handler: formatting into a stack buffer, `write`,
//! `dladdr` and glibc's `backtrace_symbols_fd` (loaded ahead of time by `install`).

use std::ffi::{c_int, c_void, CStr};
use std::fmt::Write as _;
use std::sync::{Once, OnceLock};

const SIGNALS: [c_int; 5] = [libc::SIGSEGV, libc::SIGBUS, libc::SIGILL, libc::SIGFPE, libc::SIGABRT];

/// The actions installed before ours, restored before the signal goes on.
static PREVIOUS: OnceLock<Vec<(c_int, libc::sigaction)>> = OnceLock::new();

extern "C" {
    fn backtrace(buffer: *mut *mut c_void, size: c_int) -> c_int;
    fn backtrace_symbols_fd(buffer: *const *mut c_void, size: c_int, fd: c_int);
}

/// Installs the report once per process.
pub fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| unsafe {
        // The first call loads the unwinder, which allocates: do it here, not in the handler.
        let mut frames = [std::ptr::null_mut(); 4];
        backtrace(frames.as_mut_ptr(), frames.len() as c_int);
        let mut previous = Vec::new();
        for sig in SIGNALS {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as *const () as usize;
            action.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK;
            libc::sigemptyset(&mut action.sa_mask);
            let mut old: libc::sigaction = std::mem::zeroed();
            if libc::sigaction(sig, &action, &mut old) == 0 {
                previous.push((sig, old));
            }
        }
        let _ = PREVIOUS.set(previous);
    });
}

/// A fixed buffer that `write!` can fill without allocating.
struct Line {
    bytes: [u8; 1024],
    len: usize,
}

impl std::fmt::Write for Line {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let n = s.len().min(self.bytes.len() - self.len);
        self.bytes[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

unsafe fn c_str<'a>(p: *const libc::c_char) -> &'a str {
    if p.is_null() {
        "?"
    } else {
        CStr::from_ptr(p).to_str().unwrap_or("?")
    }
}

#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
unsafe fn program_counter(context: *mut c_void) -> usize {
    (*(context as *const libc::ucontext_t)).uc_mcontext.gregs[libc::REG_RIP as usize] as usize
}

#[cfg(not(all(target_os = "linux", target_arch = "x86_64")))]
unsafe fn program_counter(_context: *mut c_void) -> usize {
    0
}

extern "C" fn on_signal(sig: c_int, info: *mut libc::siginfo_t, context: *mut c_void) {
    unsafe {
        let mut line = Line {
            bytes: [0; 1024],
            len: 0,
        };
        let mut name = [0 as libc::c_char; 64];
        libc::pthread_getname_np(libc::pthread_self(), name.as_mut_ptr(), name.len());
        let pc = program_counter(context);
        let _ = write!(
            line,
            "\ncrash report: signal {sig} on thread '{}', fault address {:p}, pc {pc:#x}",
            c_str(name.as_ptr()),
            (*info).si_addr()
        );
        let mut place: libc::Dl_info = std::mem::zeroed();
        if pc != 0 && libc::dladdr(pc as *const c_void, &mut place) != 0 {
            let _ = write!(
                line,
                " in {} (+{:#x}), symbol {}",
                c_str(place.dli_fname),
                pc - place.dli_fbase as usize,
                c_str(place.dli_sname)
            );
        }
        let _ = writeln!(line);
        libc::write(2, line.bytes.as_ptr() as *const c_void, line.len);
        let mut frames = [std::ptr::null_mut(); 64];
        let n = backtrace(frames.as_mut_ptr(), frames.len() as c_int);
        backtrace_symbols_fd(frames.as_ptr(), n, 2);
        // Hand the signal on: a fault re-executes its instruction under the previous action when
        // this handler returns; a signal sent by raise/kill (si_code <= 0) must be sent again.
        if let Some((_, old)) = PREVIOUS.get().and_then(|p| p.iter().find(|(s, _)| *s == sig)) {
            libc::sigaction(sig, old, std::ptr::null_mut());
        }
        if (*info).si_code <= 0 {
            libc::raise(sig);
        }
    }
}
