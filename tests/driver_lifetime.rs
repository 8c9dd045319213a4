//! The Vulkan loader and driver stay loaded after the last device is dropped, so that a process
//! that creates one device after another (`penumbra chart`: one per configuration) does not
//! unload and reload the driver each time. NVIDIA's 580 driver failed a chart that way ("Unable
//! to find a Vulkan driver" after some dozens of devices, on an H200); lavapipe reloads without
//! complaint, so what is checked here is the mechanism: the shared libraries that came with the
//! first device are still mapped after it is gone, and a second device comes up.
//!
//! Its own test binary: in one shared with other tests, their devices would keep the driver
//! loaded whatever this process does.

mod support;
use support as common;

use std::collections::BTreeSet;

use penumbra::backend::{Gpu, GpuDesc};

/// The shared libraries mapped into this process.
fn mapped_libraries() -> BTreeSet<String> {
    let maps = std::fs::read_to_string("/proc/self/maps").expect("read /proc/self/maps");
    maps.lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.contains(".so"))
        .map(str::to_owned)
        .collect()
}

#[test]
fn the_driver_stays_loaded_between_devices() {
    // No validation layer: its library belongs to the validating instance and goes with it.
    let desc = GpuDesc {
        validation: false,
        ..common::test_gpu_desc()
    };
    let before = mapped_libraries();
    let gpu = Gpu::new(&desc).expect("create a Vulkan device");
    let name = gpu.caps().name.clone();
    let came: BTreeSet<String> = mapped_libraries().difference(&before).cloned().collect();
    assert!(
        came.iter().any(|l| l.contains("vulkan")),
        "creating a device loaded no Vulkan library: {came:?}"
    );
    drop(gpu);
    let after = mapped_libraries();
    let gone: Vec<&String> = came.iter().filter(|l| !after.contains(*l)).collect();
    assert!(gone.is_empty(), "dropping the last device ({name}) unloaded {gone:?}");
    let again = Gpu::new(&desc).expect("create a second Vulkan device");
    assert_eq!(again.caps().name, name);
}
