//! The frame graph on a real device: per-subresource barriers for a mip pyramid (read mip N−1,
//! write mip N of one image) checked by synchronization validation and by the values computed,
//! and culling of passes whose outputs nothing uses.

use crate::support as common;

use penumbra::backend::{
    vk, Bind, BufferDesc, ComputePipelineDesc, ImageDesc, MemoryKind, SamplerDesc, SubresourceRange,
};
use penumbra::graph::{Access, RenderGraph, ResourceStates};
use penumbra::shaders::ShaderLibrary;

const SIZE: u32 = 16;
const MIPS: u32 = 5;

fn cpu_pyramid(base: &[f32]) -> Vec<Vec<f32>> {
    let mut levels = vec![base.to_vec()];
    for m in 1..MIPS {
        let (s, d) = (SIZE >> (m - 1), SIZE >> m);
        let prev = &levels[m as usize - 1];
        let mut next = vec![0.0; (d * d * 4) as usize];
        for y in 0..d {
            for x in 0..d {
                for c in 0..4 {
                    let at = |xx: u32, yy: u32| prev[((yy * s + xx) * 4 + c) as usize];
                    next[((y * d + x) * 4 + c) as usize] = 0.25
                        * (at(2 * x, 2 * y) + at(2 * x + 1, 2 * y) + at(2 * x, 2 * y + 1) + at(2 * x + 1, 2 * y + 1));
                }
            }
        }
        levels.push(next);
    }
    levels
}

#[test]
fn mip_pyramid_barriers_are_exact_and_values_correct() {
    let mut gpu = common::test_gpu();
    let shaders = ShaderLibrary::test_kernels();
    let pipeline = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                name: "downsample".into(),
                shader: "tests/downsample.comp".into(),
                specialization: vec![],
            },
            &shaders,
        )
        .unwrap();
    let usage = vk::ImageUsageFlags::SAMPLED
        | vk::ImageUsageFlags::STORAGE
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::TRANSFER_DST;
    let image = gpu
        .create_image(
            &ImageDesc::new_2d("pyramid", vk::Format::R32G32B32A32_SFLOAT, SIZE, SIZE)
                .mips(MIPS)
                .usage(usage),
        )
        .unwrap();
    let base: Vec<f32> = (0..SIZE * SIZE * 4).map(|i| ((i * 7919) % 101) as f32 * 0.5).collect();
    gpu.upload_image(image, 0, bytemuck::cast_slice(&base)).unwrap();
    let sampler = gpu.sampler(SamplerDesc::NEAREST_CLAMP).unwrap();
    let readbacks: Vec<_> = (1..MIPS)
        .map(|m| {
            let s = (SIZE >> m) as u64;
            gpu.create_buffer(&BufferDesc {
                name: format!("mip {m}"),
                size: s * s * 16,
                usage: vk::BufferUsageFlags::TRANSFER_DST,
                memory: MemoryKind::GpuToCpu,
            })
            .unwrap()
        })
        .collect();
    let mut states = ResourceStates::default();
    states
        .set_image(
            &gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )
        .unwrap();
    let frame = gpu.create_frame().unwrap();

    let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
    let mut graph = RenderGraph::new();
    for m in 1..MIPS {
        graph
            .pass(&format!("downsample {m}"))
            .sample("src", image, SubresourceRange::mip(m - 1), sampler, compute)
            .storage_write("dst", image, SubresourceRange::mip(m), compute)
            .record(move |ctx| {
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.bind(&[])?;
                ctx.rec.push_constants(&0u32.to_le_bytes())?;
                ctx.rec.dispatch([SIZE >> m, SIZE >> m, 1])
            });
    }
    for (i, &buf) in readbacks.iter().enumerate() {
        let m = i as u32 + 1;
        graph
            .pass(&format!("read mip {m}"))
            .transfer_read(image, SubresourceRange::mip(m))
            .buffer(buf, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.copy_image_to_buffer(image, m, 0, buf));
        graph
            .pass(&format!("host {m}"))
            .buffer(buf, Access::HostRead, None)
            .record(|_| Ok(()));
    }
    // A pass whose output nothing reads must not be recorded.
    let unused = gpu
        .create_image(&ImageDesc::new_2d("unused", vk::Format::R32G32B32A32_SFLOAT, 4, 4).usage(usage))
        .unwrap();
    graph
        .pass("unused output")
        .sample("src", image, SubresourceRange::mip(0), sampler, compute)
        .storage_write("dst", unused, SubresourceRange::mip(0), compute)
        .record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[])?;
            ctx.rec.dispatch([4, 4, 1])
        });

    let mut rec = gpu.begin_frame(frame).unwrap();
    let report = graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();

    assert_eq!(report.culled, vec!["unused output".to_string()]);
    assert_eq!(report.recorded.len(), 3 * (MIPS as usize - 1));
    // Per step: mip N−1 GENERAL→READ_ONLY (fresh mip N is UNDEFINED→GENERAL), except the first
    // step where mip 0 is already sampled: 1 + 2·3 for the pyramid, then 4 copies' transitions.
    assert_eq!(report.image_barriers, 1 + 2 * (MIPS as usize - 2) + (MIPS as usize - 1));
    let expected = cpu_pyramid(&base);
    for (i, &buf) in readbacks.iter().enumerate() {
        let got: Vec<f32> = bytemuck::cast_slice(&gpu.read_buffer(buf).unwrap()).to_vec();
        let want = &expected[i + 1];
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= 1e-4 * w.abs().max(1.0), "mip {}: {g} vs {w}", i + 1);
        }
    }
    // Every mip ends where the graph says it does.
    assert_eq!(
        states.image_layout(image, 0, 0),
        Some(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
    );
    for m in 1..MIPS {
        assert_eq!(
            states.image_layout(image, m, 0),
            Some(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
        );
    }
    let timings = gpu.frame_timings(frame).unwrap().expect("lavapipe has timestamps");
    assert_eq!(
        timings.len(),
        report.recorded.len(),
        "one timestamp scope per recorded pass"
    );
    assert!(timings.iter().all(|t| t.ms >= 0.0 && t.ms.is_finite()));
    common::assert_clean(&gpu);
}

#[test]
fn bindings_are_checked_against_reflection() {
    let mut gpu = common::test_gpu();
    let pipeline = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                name: "downsample".into(),
                shader: "tests/downsample.comp".into(),
                specialization: vec![],
            },
            &ShaderLibrary::test_kernels(),
        )
        .unwrap();
    let refl = gpu.pipeline_reflection(pipeline).unwrap();
    assert_eq!(refl.local_size, Some([8, 8, 1]));
    assert_eq!(refl.push_constant_size, 4);
    let names: Vec<(&str, vk::DescriptorType)> = refl.bindings.iter().map(|b| (b.name.as_str(), b.ty)).collect();
    assert_eq!(
        names,
        vec![
            ("src", vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            ("dst", vk::DescriptorType::STORAGE_IMAGE)
        ]
    );

    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::STORAGE;
    let img = gpu
        .create_image(&ImageDesc::new_2d("x", vk::Format::R32G32B32A32_SFLOAT, 4, 4).usage(usage))
        .unwrap();
    let buf = gpu
        .create_buffer(&BufferDesc {
            name: "b".into(),
            size: 64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuOnly,
        })
        .unwrap();
    let sampler = gpu.sampler(SamplerDesc::NEAREST_CLAMP).unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut rec = gpu.begin_frame(frame).unwrap();
    rec.bind_pipeline(pipeline).unwrap();
    let whole = SubresourceRange::mip(0);
    let err = |r: Result<(), penumbra::backend::BackendError>| r.unwrap_err().to_string();
    // Wrong type for a declared name.
    let e = err(rec.bind(&[
        ("src", Bind::StorageBuffer(buf)),
        (
            "dst",
            Bind::StorageImage {
                image: img,
                range: whole,
            },
        ),
    ]));
    assert!(e.contains("`src`") && e.contains("COMBINED_IMAGE_SAMPLER"), "{e}");
    // A name the shader does not declare.
    let e = err(rec.bind(&[(
        "source",
        Bind::Sampled {
            image: img,
            range: whole,
            sampler,
        },
    )]));
    assert!(
        e.contains("`source`") && e.contains("not declared") && e.contains("src, dst"),
        "{e}"
    );
    // A declared binding left out.
    let e = err(rec.bind(&[(
        "src",
        Bind::Sampled {
            image: img,
            range: whole,
            sampler,
        },
    )]));
    assert!(e.contains("`dst`") && e.contains("not bound"), "{e}");
    // Push constants of the wrong size.
    let e = err(rec.push_constants(&[0u8; 8]));
    assert!(e.contains("8 bytes given") && e.contains("declare 4"), "{e}");
    drop(rec);
    common::assert_clean(&gpu);
}

#[test]
fn unsupported_capability_is_an_error_not_a_panic() {
    let mut gpu = common::test_gpu();
    let too_big = gpu.caps().max_image_dimension_2d + 1;
    let e = gpu
        .create_image(
            &ImageDesc::new_2d("huge", vk::Format::R8G8B8A8_UNORM, too_big, 1).usage(vk::ImageUsageFlags::SAMPLED),
        )
        .unwrap_err();
    assert!(matches!(e, penumbra::backend::BackendError::Unsupported(_)), "{e}");
    let e = penumbra::backend::Gpu::new(&penumbra::backend::GpuDesc {
        device_name: Some("no such device 42".into()),
        ..common::test_gpu_desc()
    })
    .err()
    .expect("an unknown device name is an error");
    assert!(
        e.to_string().contains("no such device 42") && e.to_string().contains("available"),
        "{e}"
    );
    common::assert_clean(&gpu);
}

/// The harness itself: a missing barrier must reach the log, or a clean run proves nothing.
#[test]
fn synchronization_validation_is_live() {
    use penumbra::backend::ImageTransition;
    let mut gpu = common::test_gpu();
    let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED;
    let img = gpu
        .create_image(&ImageDesc::new_2d("hazard", vk::Format::R8G8B8A8_UNORM, 4, 4).usage(usage))
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut rec = gpu.begin_frame(frame).unwrap();
    let range = SubresourceRange::mip(0);
    rec.barriers(
        &[ImageTransition {
            image: img,
            range,
            src_stages: vk::PipelineStageFlags2::NONE,
            src_access: vk::AccessFlags2::NONE,
            dst_stages: vk::PipelineStageFlags2::CLEAR,
            dst_access: vk::AccessFlags2::TRANSFER_WRITE,
            old_layout: vk::ImageLayout::UNDEFINED,
            new_layout: vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        }],
        &[],
    )
    .unwrap();
    rec.clear_color_image(img, range, [1.0; 4]).unwrap();
    // Second write with no barrier in between: a write-after-write hazard.
    rec.clear_color_image(img, range, [0.0; 4]).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    let messages = gpu.validation_log().take();
    assert!(
        messages.iter().any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")),
        "{messages:?}"
    );
}
