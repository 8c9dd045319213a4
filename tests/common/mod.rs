//! Shared by the integration tests: every GPU test runs on lavapipe (or PENUMBRA_TEST_DEVICE)
//! with the Khronos validation layer and synchronization validation, and fails on any message.
#![allow(dead_code)]

use penumbra::backend::{Gpu, GpuDesc};

pub fn test_gpu_desc() -> GpuDesc {
    GpuDesc { validation: true, device_name: Some(std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into())), display: None }
}

pub fn test_gpu() -> Gpu {
    Gpu::new(&test_gpu_desc()).expect("create a validated Vulkan device (is lavapipe installed? run tools/setup.sh)")
}

/// Fails the test if the validation layer reported anything.
pub fn assert_clean(gpu: &Gpu) {
    let messages = gpu.validation_log().take();
    assert!(messages.is_empty(), "{} validation message(s):\n{}", messages.len(), messages.join("\n"));
}

pub fn temp_path(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("penumbra-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

/// Records `graph` into `frame` with fresh resource states, submits it and waits.
pub fn run_once(gpu: &Gpu, frame: penumbra::backend::Frame, graph: penumbra::graph::RenderGraph<'_>) {
    let mut states = penumbra::graph::ResourceStates::default();
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
}

/// Runs the `penumbra` binary as a user would: validation on, the test device chosen (`compare`
/// takes no device).
pub fn penumbra(args: &[&str]) -> std::process::Output {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
    cmd.args(args).env("PENUMBRA_VALIDATION", "1");
    if args.first() != Some(&"compare") {
        cmd.args(["--device", &device]);
    }
    cmd.output().expect("run penumbra")
}

/// The command's standard output, failing the test with its standard error if it failed.
pub fn ok(o: &std::process::Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}
