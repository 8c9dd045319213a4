//! Backend features the techniques rely on, each checked by a value that could be wrong:
//! 3D, cube and array images with mip chains; specialization constants; shader hot reload that
//! keeps the old pipeline when the new source does not compile; per-frame uploads past the
//! first 4 MiB block.

use crate::support as common;

use penumbra::backend::{
    vk, BufferDesc, BufferId, ComputePipelineDesc, Gpu, ImageDesc, ImageId, MemoryKind, PipelineId, SamplerDesc,
    SpecConstant, SubresourceRange,
};
use penumbra::graph::{Access, RenderGraph, ResourceStates};
use penumbra::shaders::ShaderLibrary;

fn readback_buffer(gpu: &mut Gpu, bytes: u64) -> BufferId {
    gpu.create_buffer(&BufferDesc {
        name: "readback".into(),
        size: bytes,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        memory: MemoryKind::GpuToCpu,
    })
    .unwrap()
}

/// Copies mip `mip`, layer `layer` of `image` back through the graph.
fn read_subresource(gpu: &mut Gpu, states: &mut ResourceStates, image: ImageId, mip: u32, layer: u32) -> Vec<u8> {
    let e = gpu.image_desc(image).unwrap().mip_extent(mip);
    let texel = penumbra::backend::format_texel_size(gpu.image_desc(image).unwrap().format).unwrap();
    let buf = readback_buffer(gpu, texel * (e.width * e.height * e.depth) as u64);
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    graph
        .pass("read")
        .transfer_read(image, SubresourceRange::mip_layer(mip, layer))
        .buffer(buf, Access::TransferWrite, None)
        .record(move |ctx| ctx.rec.copy_image_to_buffer(image, mip, layer, buf));
    graph
        .pass("host")
        .buffer(buf, Access::HostRead, None)
        .record(|_| Ok(()));
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    gpu.read_buffer(buf).unwrap()
}

#[test]
fn volume_cube_and_array_images_round_trip_every_subresource() {
    let mut gpu = common::test_gpu();
    let mut states = ResourceStates::default();
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
    let f = vk::Format::R32_SFLOAT;
    let kinds = [
        ImageDesc::new_3d("volume", f, 8, 4, 6).mips(2).usage(usage),
        ImageDesc::new_cube("cube", f, 8).all_mips().usage(usage),
        ImageDesc::new_2d("array", f, 4, 4).layers(3).all_mips().usage(usage),
    ];
    for desc in kinds {
        let img = gpu.create_image(&desc).unwrap();
        let e = desc.mip_extent(1);
        let texels = (e.width * e.height * e.depth * desc.layers) as usize;
        let data: Vec<f32> = (0..texels).map(|i| i as f32 * 0.5 + desc.layers as f32).collect();
        gpu.upload_image(img, 1, bytemuck::cast_slice(&data)).unwrap();
        states
            .set_image(
                &gpu,
                img,
                Access::SampledRead {
                    stages: vk::PipelineStageFlags2::ALL_COMMANDS,
                },
            )
            .unwrap();
        let per_layer = texels / desc.layers as usize;
        for layer in 0..desc.layers {
            let got = read_subresource(&mut gpu, &mut states, img, 1, layer);
            let want = &data[layer as usize * per_layer..(layer as usize + 1) * per_layer];
            assert_eq!(
                bytemuck::cast_slice::<u8, f32>(&got),
                want,
                "{} layer {layer}",
                desc.name
            );
        }
        assert!(desc.mip_levels >= 2, "{}: {} mips", desc.name, desc.mip_levels);
    }
    assert_eq!(ImageDesc::new_cube("c", f, 8).all_mips().mip_levels, 4);
    common::assert_clean(&gpu);
}

/// A zero-padded upload writes the bytes given and zeros after them, not whatever the staging
/// memory held: a full upload of 0xff bytes goes first, so that the padded one's staging buffer
/// reuses dirty memory (it fails with the padding left unwritten). More bytes than the image
/// holds are an error.
#[test]
fn a_zero_padded_upload_fills_the_rest_of_the_image_with_zeros() {
    let mut gpu = common::test_gpu();
    let mut states = ResourceStates::default();
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
    let desc = |name: &str| ImageDesc::new_2d(name, vk::Format::R32G32B32A32_UINT, 64, 4).usage(usage);
    let size = 64 * 4 * 16;
    // Both images first: the padded upload's staging buffer then takes the memory the dirty
    // one's staging buffer left.
    let dirty = gpu.create_image(&desc("dirty")).unwrap();
    let table = gpu.create_image(&desc("table")).unwrap();
    gpu.upload_image(dirty, 0, &vec![0xff; size]).unwrap();
    let data: Vec<u8> = (0..size / 3).map(|i| (i % 251) as u8 + 1).collect();
    gpu.upload_image_zero_padded(table, 0, &data).unwrap();
    states
        .set_image(
            &gpu,
            table,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )
        .unwrap();
    let got = read_subresource(&mut gpu, &mut states, table, 0, 0);
    assert_eq!(&got[..data.len()], &data[..]);
    assert!(got[data.len()..].iter().all(|&b| b == 0), "the padding is zero");
    let e = gpu
        .upload_image_zero_padded(table, 0, &vec![1; size + 16])
        .expect_err("more bytes than the image holds");
    assert!(e.to_string().contains("expected"), "{e}");
    common::assert_clean(&gpu);
}

/// Runs tests/downsample.comp on a 2×2 image of constant `value` and returns the 1×1 result.
fn downsample_once(gpu: &mut Gpu, pipeline: PipelineId, value: f32) -> f32 {
    let usage = vk::ImageUsageFlags::SAMPLED
        | vk::ImageUsageFlags::STORAGE
        | vk::ImageUsageFlags::TRANSFER_SRC
        | vk::ImageUsageFlags::TRANSFER_DST;
    let img = gpu
        .create_image(
            &ImageDesc::new_2d("img", vk::Format::R32G32B32A32_SFLOAT, 2, 2)
                .mips(2)
                .usage(usage),
        )
        .unwrap();
    gpu.upload_image(img, 0, bytemuck::cast_slice(&[value; 16])).unwrap();
    let sampler = gpu.sampler(SamplerDesc::NEAREST_CLAMP).unwrap();
    let mut states = ResourceStates::default();
    states
        .set_image(
            gpu,
            img,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let c = vk::PipelineStageFlags2::COMPUTE_SHADER;
    let mut graph = RenderGraph::new();
    graph
        .pass("downsample")
        .sample("src", img, SubresourceRange::mip(0), sampler, c)
        .storage_write("dst", img, SubresourceRange::mip(1), c)
        .record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[])?;
            ctx.rec.push_constants(&0u32.to_le_bytes())?;
            ctx.rec.dispatch([1, 1, 1])
        });
    graph.output_image(img);
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    let bytes = read_subresource(gpu, &mut states, img, 1, 0);
    bytemuck::cast_slice::<u8, f32>(&bytes)[0]
}

#[test]
fn specialization_constants_reach_the_shader() {
    let mut gpu = common::test_gpu();
    let lib = ShaderLibrary::test_kernels();
    let desc = |scale: f32| ComputePipelineDesc {
        name: format!("downsample x{scale}"),
        shader: "tests/downsample.comp".into(),
        specialization: vec![SpecConstant {
            id: 0,
            bits: scale.to_bits(),
        }],
    };
    let plain = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                specialization: vec![],
                ..desc(1.0)
            },
            &lib,
        )
        .unwrap();
    let tripled = gpu.create_compute_pipeline(&desc(3.0), &lib).unwrap();
    assert_eq!(downsample_once(&mut gpu, plain, 2.5), 2.5);
    assert_eq!(downsample_once(&mut gpu, tripled, 2.5), 7.5);
    common::assert_clean(&gpu);
}

#[test]
fn hot_reload_swaps_pipelines_and_keeps_the_old_one_on_errors() {
    // A private copy of glsl/ to edit, as a user would edit the checkout's.
    let root = common::temp_path("glsl-reload");
    let rel = "tests/downsample.comp";
    let dst = root.join(rel);
    std::fs::create_dir_all(dst.parent().unwrap()).unwrap();
    std::fs::copy(ShaderLibrary::source_dir().join(rel), &dst).unwrap();
    let lib = ShaderLibrary::Directory(root.clone());
    let mut gpu = common::test_gpu();
    let p = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                name: "downsample".into(),
                shader: "tests/downsample.comp".into(),
                specialization: vec![],
            },
            &lib,
        )
        .unwrap();
    assert_eq!(downsample_once(&mut gpu, p, 1.0), 1.0);

    let file = root.join("tests/downsample.comp");
    let source = std::fs::read_to_string(&file).unwrap();
    std::fs::write(&file, source.replace("r * SCALE", "r * SCALE * 4.0")).unwrap();
    gpu.reload_pipeline(p, &lib).unwrap();
    assert_eq!(
        downsample_once(&mut gpu, p, 1.0),
        4.0,
        "the edited shader runs after reload"
    );

    std::fs::write(&file, source.replace("r * SCALE", "r * undefined_scale")).unwrap();
    let err = gpu.reload_pipeline(p, &lib).unwrap_err().to_string();
    assert!(
        err.contains("undefined_scale") && err.contains("downsample.comp"),
        "{err}"
    );
    assert_eq!(
        downsample_once(&mut gpu, p, 1.0),
        4.0,
        "the previous pipeline keeps running"
    );
    common::assert_clean(&gpu);
}

/// `Gpu::scoped` frees what its closure created — buffers, pipelines and frames (with their
/// upload buffers) — when it succeeds and when it fails half-way (the bakes' compute passes rely
/// on it for every exit path).
#[test]
fn a_scoped_computation_leaves_nothing_behind_on_success_or_error() {
    use penumbra::backend::{vk, BackendError, ComputePipelineDesc};
    let mut gpu = common::test_gpu();
    let before = gpu.live_objects();
    let frames = gpu.live_frames();
    let made = |gpu: &mut penumbra::backend::Gpu| -> Result<(), BackendError> {
        gpu.create_buffer_init("scoped", vk::BufferUsageFlags::STORAGE_BUFFER, &[0u8; 64])?;
        gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: "scoped".into(),
                shader: "tests/sh_check.comp".into(),
                specialization: vec![],
            },
            &penumbra::shaders::ShaderLibrary::test_kernels(),
        )?;
        gpu.create_frame()?;
        Ok(())
    };
    gpu.scoped(|gpu| made(gpu)).unwrap();
    assert_eq!(
        (gpu.live_objects(), gpu.live_frames()),
        (before, frames),
        "after a scoped success"
    );
    let failed: Result<(), BackendError> = gpu.scoped(|gpu| {
        made(gpu)?;
        Err(BackendError::Invalid("failed half-way".into()))
    });
    assert!(failed.is_err());
    assert_eq!(
        (gpu.live_objects(), gpu.live_frames()),
        (before, frames),
        "after a scoped failure"
    );
    // Inside, the objects were alive.
    gpu.scoped(|gpu| -> Result<(), BackendError> {
        made(gpu)?;
        // The buffer (a frame's upload blocks belong to the frame, not to the buffer arena).
        assert!(
            gpu.live_objects().0 > before.0 && gpu.live_objects().2 == before.2 + 1 && gpu.live_frames() == frames + 1
        );
        Ok(())
    })
    .unwrap();
    common::assert_clean(&gpu);
}

/// The check kernel of glsl/tests/upload_check.comp.
fn upload_check_pipeline(gpu: &mut Gpu) -> PipelineId {
    gpu.create_compute_pipeline(
        &ComputePipelineDesc {
            name: "upload check".into(),
            shader: "tests/upload_check.comp".into(),
            specialization: vec![],
        },
        &ShaderLibrary::test_kernels(),
    )
    .unwrap()
}

/// Records `graph` into `frame`, submits it, waits, and reads `result` back as words.
fn run_and_read(
    gpu: &Gpu,
    frame: penumbra::backend::Frame,
    states: &mut ResourceStates,
    graph: RenderGraph<'_>,
    result: BufferId,
) -> Vec<u32> {
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    bytemuck::cast_slice(&gpu.read_buffer(result).unwrap()).to_vec()
}

/// One frame uploads far more than the first 4 MiB block (thousands of lights' constants do:
/// the stencil method at 4,096 lights): later blocks are added as needed, every dispatch reads
/// exactly what was uploaded for it, and the same frame slot reused with other data (and the
/// blocks it kept) reads the new data.
#[test]
fn uploads_past_the_first_block_reach_the_shader() {
    use penumbra::backend::Bind;
    let mut gpu = common::test_gpu();
    let pipeline = upload_check_pipeline(&mut gpu);
    // 1.5 MiB each, then one of 9 MiB that no block grown by doubling alone would hold yet.
    let sizes: Vec<usize> = (0..7).map(|_| 3 << 19).chain([9 << 20]).collect();
    let total: usize = sizes.iter().sum();
    assert!(
        total > 3 * (4 << 20),
        "the test must pass the first block several times over"
    );
    let slots = sizes.len() as u32;
    let result = gpu
        .create_storage_output("upload check result", slots as u64 * 64 * 4, MemoryKind::GpuToCpu)
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut states = ResourceStates::default();
    for round in 0..2u32 {
        let blocks: Vec<Vec<u32>> = sizes
            .iter()
            .enumerate()
            .map(|(slot, &bytes)| {
                (0..bytes as u32 / 4)
                    .map(|j| (round << 31) | ((slot as u32) << 24) | j)
                    .collect()
            })
            .collect();
        let strides: Vec<u32> = sizes.iter().map(|&b| (b / 4 / 64) as u32).collect();
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let mut graph = RenderGraph::new();
        for (slot, words) in blocks.iter().enumerate() {
            let push = [slot as u32, strides[slot]];
            graph
                .pass(&format!("read block {slot}"))
                .buffer(result, Access::StorageWrite { stages: compute }, Some("result"))
                .record(move |ctx| {
                    ctx.rec.bind_pipeline(pipeline)?;
                    ctx.bind(&[("data", Bind::StorageData(bytemuck::cast_slice(words)))])?;
                    ctx.rec.push_constants(bytemuck::cast_slice(&push))?;
                    ctx.rec.dispatch([1, 1, 1])
                });
        }
        graph
            .pass("host")
            .buffer(result, Access::HostRead, None)
            .record(|_| Ok(()));
        let got = run_and_read(&gpu, frame, &mut states, graph, result);
        for (slot, words) in blocks.iter().enumerate() {
            for i in 0..64 {
                assert_eq!(
                    got[slot * 64 + i],
                    words[i * strides[slot] as usize],
                    "round {round}, block {slot}, word {i}"
                );
            }
        }
        let held = gpu.frame_footprint(frame).unwrap();
        assert!(
            held.upload_blocks >= 3 && held.upload_bytes >= total as u64,
            "round {round}: {held:?}"
        );
    }
    common::assert_clean(&gpu);
}

/// One frame binding more descriptor sets than a descriptor pool holds (2,048; a pass per
/// light for thousands of lights does) takes them from further pools instead of asking one
/// pool for more than it has, which a driver may refuse: every dispatch reads its own data.
#[test]
fn a_frame_binding_more_sets_than_a_pool_holds_takes_more_pools() {
    use penumbra::backend::{Bind, BufferTransition};
    let mut gpu = common::test_gpu();
    let pipeline = upload_check_pipeline(&mut gpu);
    const BINDS: u32 = 5000;
    let result = gpu
        .create_storage_output("bind check result", BINDS as u64 * 64 * 4, MemoryKind::GpuToCpu)
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut states = ResourceStates::default();
    let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
    let mut graph = RenderGraph::new();
    graph
        .pass("many binds")
        .buffer(result, Access::StorageWrite { stages: compute }, Some("result"))
        .record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            for slot in 0..BINDS {
                // 64 words, each the slot's number and its own index.
                let words: Vec<u32> = (0..64).map(|i| slot * 1000 + i).collect();
                ctx.bind(&[("data", Bind::StorageData(bytemuck::cast_slice(&words)))])?;
                ctx.rec.push_constants(bytemuck::cast_slice(&[slot, 1]))?;
                ctx.rec.dispatch([1, 1, 1])?;
                // The dispatches write disjoint words, but a whole-buffer binding is what
                // synchronization validation sees.
                let w = vk::AccessFlags2::SHADER_STORAGE_WRITE;
                ctx.rec.barriers(
                    &[],
                    &[BufferTransition {
                        buffer: result,
                        src_stages: compute,
                        src_access: w,
                        dst_stages: compute,
                        dst_access: w,
                    }],
                )?;
            }
            Ok(())
        });
    graph
        .pass("host")
        .buffer(result, Access::HostRead, None)
        .record(|_| Ok(()));
    let got = run_and_read(&gpu, frame, &mut states, graph, result);
    for slot in 0..BINDS {
        for i in 0..64 {
            assert_eq!(got[(slot * 64 + i) as usize], slot * 1000 + i, "bind {slot}, word {i}");
        }
    }
    let held = gpu.frame_footprint(frame).unwrap();
    assert!(
        held.descriptor_pools >= 3,
        "{BINDS} sets of two storage buffers fit in {} pool(s)",
        held.descriptor_pools
    );
    common::assert_clean(&gpu);
}

/// `read_buffer_prefix` returns exactly the bytes asked for from the start of the buffer, and
/// refuses to read past its end (an error, not a panic).
#[test]
fn a_buffer_prefix_reads_back_what_was_written() {
    let mut gpu = common::test_gpu();
    let buf = gpu.create_storage_output("prefix", 64, MemoryKind::GpuToCpu).unwrap();
    let bytes: Vec<u8> = (0..64u8).map(|b| b.wrapping_mul(37)).collect();
    gpu.upload_buffer(buf, 0, &bytes).unwrap();
    assert_eq!(gpu.read_buffer_prefix(buf, 12).unwrap(), bytes[..12]);
    assert_eq!(gpu.read_buffer_prefix(buf, 64).unwrap(), bytes);
    assert!(gpu.read_buffer_prefix(buf, 65).is_err());
    common::assert_clean(&gpu);
}
