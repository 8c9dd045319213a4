//! Devices made and dropped on some threads while others use theirs, as `cargo test` does with
//! the GPU tests of one binary. The validation layer of Debian 12 (1.3.239) looks every call's
//! device or instance up in a process-wide map that creating and destroying them change, with no
//! lock (its lookup is where this test crashed), and the Vulkan loader frees entries of its
//! process-wide device list without the lock its readers take (KhronosGroup/Vulkan-Loader#2018 upstream). So a
//! call on one thread could read an entry another thread was changing: the suite's occasional
//! SIGSEGV, at address 0 or inside the layer. The backend now orders those calls
//! (`vulkan_calls` and `device_set_change` in `src/backend/device.rs`); this test makes them meet
//! on purpose, in a binary of its own so that a crash names it. Measured by hand (debug build,
//! this 2-core machine): with the backend of before the lock all 8 of 8 runs crashed, with only
//! the exclusive side (no shared holds around other calls) 4 of 6, with the lock none of 12.
//!
//! Its own test binary: it races device creation against other threads' Vulkan calls, and the
//! race it guards needs no other tests' devices in the process.

mod support;
use support as common;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use penumbra::backend::{vk, BufferDesc, Gpu, MemoryKind};
use penumbra::graph::{Access, RenderGraph, ResourceStates};

/// A named host-visible buffer written, read back and destroyed: naming and resource creation
/// and destruction, many calls in a short time.
fn buffer_round_trip(gpu: &mut Gpu, name: &str, seed: usize) {
    let data: Vec<u8> = (0..256 + 16 * (seed % 64)).map(|i| (i * 7 + seed) as u8).collect();
    let desc = BufferDesc {
        name: name.into(),
        size: data.len() as u64,
        usage: vk::BufferUsageFlags::STORAGE_BUFFER,
        memory: MemoryKind::CpuToGpu,
    };
    let buffer = gpu.create_buffer(&desc).expect("a small buffer");
    gpu.upload_buffer(buffer, 0, &data).expect("write");
    assert_eq!(gpu.read_buffer(buffer).expect("read back"), data);
    gpu.destroy_buffer(buffer);
}

/// A buffer filled by a recorded and submitted frame and read back: recording and submission.
fn frame_round_trip(gpu: &mut Gpu, name: &str, seed: usize) {
    let words = 64 + 4 * (seed % 64);
    let value = 0x9e37_79b9u32.wrapping_mul(seed as u32 + 1);
    let desc = BufferDesc {
        name: name.into(),
        size: 4 * words as u64,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        memory: MemoryKind::GpuToCpu,
    };
    let buffer = gpu.create_buffer(&desc).expect("a small buffer");
    let frame = gpu.create_frame().expect("a frame");
    let mut graph = RenderGraph::new();
    graph
        .pass("fill")
        .buffer(buffer, Access::TransferWrite, None)
        .record(move |ctx| ctx.rec.fill_buffer(buffer, value));
    graph
        .pass("host")
        .buffer(buffer, Access::HostRead, None)
        .record(|_| Ok(()));
    let mut rec = gpu.begin_frame(frame).expect("begin");
    graph.execute(&mut rec, &mut ResourceStates::default()).expect("record");
    rec.finish().expect("finish");
    gpu.submit_and_wait(frame).expect("submit");
    let read: Vec<u32> = bytemuck::pod_collect_to_vec(&gpu.read_buffer(buffer).expect("read back"));
    assert_eq!(read, vec![value; words]);
    gpu.destroy_frame(frame).expect("destroy the frame");
    gpu.destroy_buffer(buffer);
}

#[test]
fn devices_made_and_dropped_while_other_threads_use_theirs() {
    const MAKERS: usize = 3;
    const DEVICES_PER_MAKER: usize = 500;
    // The last user records and submits frames; the others make and read buffers, many calls in
    // a short time (with frames among their rounds the race was hit in fewer runs).
    const USERS: usize = 3;
    let making = Arc::new(AtomicBool::new(true));
    let users: Vec<_> = (0..USERS)
        .map(|t| {
            let making = making.clone();
            std::thread::Builder::new()
                .name(format!("user-{t}"))
                .spawn(move || {
                    let mut gpu = Gpu::new(&common::test_gpu_desc()).expect("create a validated Vulkan device");
                    let mut rounds = 0;
                    while making.load(Ordering::Relaxed) || rounds < 10 {
                        let name = format!("user {t} round {rounds}");
                        if t == USERS - 1 {
                            frame_round_trip(&mut gpu, &name, rounds);
                        } else {
                            buffer_round_trip(&mut gpu, &name, rounds);
                        }
                        rounds += 1;
                    }
                    common::assert_clean(&gpu);
                    rounds
                })
                .expect("spawn")
        })
        .collect();
    let makers: Vec<_> = (0..MAKERS)
        .map(|t| {
            std::thread::Builder::new()
                .name(format!("maker-{t}"))
                .spawn(move || {
                    for k in 0..DEVICES_PER_MAKER {
                        let mut gpu = Gpu::new(&common::test_gpu_desc()).expect("create a validated Vulkan device");
                        buffer_round_trip(&mut gpu, &format!("maker {t} device {k}"), k);
                        common::assert_clean(&gpu);
                    }
                })
                .expect("spawn")
        })
        .collect();
    for t in makers {
        t.join().expect("a thread making devices failed");
    }
    making.store(false, Ordering::Relaxed);
    for t in users {
        let rounds = t.join().expect("a thread using its device failed");
        assert!(rounds >= 10, "a user thread ran {rounds} rounds");
    }
}
