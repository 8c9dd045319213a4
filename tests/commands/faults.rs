//! Faults a user can meet at any time, reported as one line and never a panic: an allocation
//! beyond the device's memory, and a lost device (injected with `PENUMBRA_INJECT_FAULT`, as no
//! test machine can lose its device on demand). Nothing is left half-written.

use crate::support as common;

use penumbra::backend::{vk, BufferDesc, MemoryKind};

#[test]
fn an_allocation_beyond_the_heap_is_an_error_not_a_panic() {
    let mut gpu = common::test_gpu();
    let heap = gpu.caps().name.clone();
    // Far beyond any heap lavapipe or a real GPU has (a petabyte).
    let e = gpu
        .create_buffer(&BufferDesc {
            name: "too big".into(),
            size: 1 << 50,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuOnly,
        })
        .expect_err("a petabyte buffer must be refused")
        .to_string();
    assert_eq!(e.lines().count(), 1, "{heap}: {e}");
    assert!(
        e.contains("too big") || e.contains("out of") || e.contains("vkCreateBuffer"),
        "{e}"
    );
    // The device is still usable afterwards.
    gpu.create_buffer(&BufferDesc {
        name: "small".into(),
        size: 256,
        usage: vk::BufferUsageFlags::STORAGE_BUFFER,
        memory: MemoryKind::GpuOnly,
    })
    .unwrap();
    common::assert_clean(&gpu);
}

#[test]
fn a_lost_device_is_one_line_and_leaves_no_output() {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    for (fault, says) in [
        ("device-lost", "the GPU device was lost during vkQueueSubmit2"),
        ("out-of-memory", "vkQueueSubmit2: out of GPU memory"),
    ] {
        let (png, exr) = (
            common::temp_path(&format!("{fault}.png")),
            common::temp_path(&format!("{fault}.exr")),
        );
        let _ = (std::fs::remove_file(&png), std::fs::remove_file(&exr));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args([
                "capture",
                "--size",
                "16x16",
                "--device",
                &device,
                "-o",
                png.to_str().unwrap(),
                "--exr",
                exr.to_str().unwrap(),
            ])
            .env("PENUMBRA_INJECT_FAULT", fault)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{fault}: {e}");
        assert_eq!(e.lines().count(), 1, "{fault}: {e}");
        assert!(e.starts_with(&format!("error: {says}")), "{fault}: {e}");
        assert!(!png.exists() && !exr.exists(), "{fault}: an output was written");
    }
}

/// A test process killed by a signal says which thread died and where, and still dies by the
/// same signal (so cargo reports the crash, not a pass).
#[test]
fn a_crash_is_reported_with_its_thread_and_place_and_still_kills() {
    use std::os::unix::process::ExitStatusExt;
    if std::env::var_os("PENUMBRA_TEST_CRASH_NOW").is_some() {
        common::crash_report::install();
        let crasher = std::thread::Builder::new().name("crasher".into());
        // An unmapped, aligned, non-null address: a real fault, not a precondition panic.
        let _ = crasher
            .spawn(|| unsafe { (8usize as *const u32).read_volatile() })
            .unwrap()
            .join();
        unreachable!("the read should have faulted");
    }
    let exe = std::env::current_exe().unwrap();
    let out = std::process::Command::new(&exe)
        .args([
            "--exact",
            "faults::a_crash_is_reported_with_its_thread_and_place_and_still_kills",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("PENUMBRA_TEST_CRASH_NOW", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.signal(), Some(libc::SIGSEGV), "{:?}\n{stderr}", out.status);
    assert!(
        stderr.contains("crash report: signal 11 on thread 'crasher', fault address 0x8"),
        "{stderr}"
    );
    let name = exe.file_name().unwrap().to_string_lossy();
    assert!(
        stderr.lines().any(|l| l.contains("crash report") && l.contains(&*name)),
        "the faulting library is named: {stderr}"
    );
}
