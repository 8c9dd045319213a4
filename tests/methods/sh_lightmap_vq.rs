//! The compressed SH light-map's look-ups on the device (glsl/sh_lightmap/vq.glsl through the check
//! kernel glsl/tests/shl_vq_check.comp), against the storage layout written on the CPU
//! (src/lighting/sh_lightmap/storage.rs) — the Ca3D-Engine thesis §5.6.2 and §5.8, digest §5.3: every one of
//! the 65,536 indices read back bit-exact (and a LINEAR sampler shown to break them), the
//! 256-row table fetched for every representative, and the 4-tap filter's profile.

use crate::support as common;

use penumbra::backend::{
    vk, BufferDesc, ComputePipelineDesc, Gpu, ImageDesc, ImageId, MemoryKind, SamplerDesc, SpecConstant,
    SubresourceRange,
};
use penumbra::graph::{Access, RenderGraph, ResourceStates};
use penumbra::lighting::sh_lightmap::storage;
use penumbra::shaders::ShaderLibrary;

fn image(
    gpu: &mut Gpu,
    states: &mut ResourceStates,
    name: &str,
    format: vk::Format,
    w: u32,
    h: u32,
    bytes: &[u8],
) -> ImageId {
    let image = gpu
        .create_image(
            &ImageDesc::new_2d(name, format, w, h)
                .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
        )
        .unwrap();
    gpu.upload_image(image, 0, bytes).unwrap();
    states
        .set_image(
            gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )
        .unwrap();
    image
}

/// Runs the check kernel in `mode` over `count` items with the index map `indices` (RGBA8 bytes,
/// `iw`×`ih`) and the RGBA8 table `table` (`tw`×`th`); returns the result words.
#[allow(clippy::too_many_arguments)]
fn check(
    mode: u32,
    count: u32,
    bands: u32,
    indices: &[u8],
    iw: u32,
    ih: u32,
    table: &[u8],
    tw: u32,
    th: u32,
    words_per_item: u64,
) -> Vec<u32> {
    let mut gpu = common::test_gpu();
    let mut states = ResourceStates::default();
    let index_uint = image(
        &mut gpu,
        &mut states,
        "indices",
        vk::Format::R8G8B8A8_UINT,
        iw,
        ih,
        indices,
    );
    let index_unorm = image(
        &mut gpu,
        &mut states,
        "indices (unorm)",
        vk::Format::R8G8B8A8_UNORM,
        iw,
        ih,
        indices,
    );
    let table = image(
        &mut gpu,
        &mut states,
        "table",
        vk::Format::R8G8B8A8_UNORM,
        tw,
        th,
        table,
    );
    let nearest = gpu.sampler(SamplerDesc::NEAREST_CLAMP).unwrap();
    let linear = gpu.sampler(SamplerDesc::LINEAR_CLAMP).unwrap();
    let spec = vec![
        SpecConstant { id: 0, bits: bands },
        SpecConstant { id: 1, bits: 1 },
        SpecConstant { id: 2, bits: mode },
        SpecConstant { id: 3, bits: count },
    ];
    let pipeline = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                name: "shl vq check".into(),
                shader: "tests/shl_vq_check.comp".into(),
                specialization: spec,
            },
            &ShaderLibrary::test_kernels(),
        )
        .unwrap();
    let out = gpu
        .create_buffer(&BufferDesc {
            name: "result".into(),
            size: 4 * words_per_item * count as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuToCpu,
        })
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    let c = vk::PipelineStageFlags2::COMPUTE_SHADER;
    graph
        .pass("shl vq check")
        .sample("indices", index_uint, SubresourceRange::mip(0), nearest, c)
        .sample("table", table, SubresourceRange::mip(0), nearest, c)
        .sample("indices_linear", index_unorm, SubresourceRange::mip(0), linear, c)
        .buffer(out, Access::StorageWrite { stages: c }, Some("result"))
        .record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[])?;
            ctx.rec.dispatch([count, 1, 1])
        });
    graph
        .pass("host")
        .buffer(out, Access::HostRead, None)
        .record(|_| Ok(()));
    common::run_once(&gpu, frame, graph);
    let got = bytemuck::cast_slice(&gpu.read_buffer(out).unwrap()).to_vec();
    common::assert_clean(&gpu);
    got
}

#[test]
fn all_65536_indices_round_trip_bit_exact_and_linear_sampling_breaks_them() {
    // Texel (x, y) of a 256 × 256 map holds index y·256 + x, scrambled so that neighbours differ.
    let want: Vec<u16> = (0..65_536u32)
        .map(|i| (i.wrapping_mul(40_503) & 0xffff) as u16)
        .collect();
    let bytes = storage::pack_indices_rgba8(&want);
    assert_eq!(
        (bytes[0], bytes[1]),
        ((want[0] & 255) as u8, (want[0] >> 8) as u8),
        "R is the low byte, G the high"
    );
    let table = vec![128u8; 4 * 256];
    let got = check(0, 65_536, 2, &bytes, 256, 256, &table, 1, 256, 2);
    let wrong = (0..65_536).filter(|&i| got[2 * i] != want[i] as u32).count();
    assert_eq!(wrong, 0, "{wrong} indices read back wrong through integer fetches");
    let blended = (0..65_536).filter(|&i| got[2 * i + 1] != want[i] as u32).count();
    assert!(
        blended > 60_000,
        "a LINEAR sampler at the seed's texel-edge coordinates should mix indices: only {blended} of 65,536 wrong"
    );
}

#[test]
fn the_table_is_64_by_256_for_4096_representatives_and_fetches_every_coefficient() {
    let (reps, bands) = (4096usize, 4usize);
    assert_eq!(storage::table_size(reps, bands).unwrap(), (64, 256));
    let mut x = 0x1234_5678u32;
    let codebook: Vec<f32> = (0..reps * bands * bands)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x as f32 / u32::MAX as f32) * 4.0 - 2.0
        })
        .collect();
    let (tw, th, bytes) = storage::pack_table_rgba8(&codebook, bands).unwrap();
    let groups = 4u32;
    let got = check(
        1,
        reps as u32 * groups,
        bands as u32,
        &[0, 0, 0, 255],
        1,
        1,
        &bytes,
        tw,
        th,
        4,
    );
    let mut worst = 0.0f32;
    for (i, &c) in codebook.iter().enumerate() {
        let g = f32::from_bits(got[i]);
        worst = worst.max((g - c).abs());
        // The GPU decodes the byte the CPU encoded: within float rounding of the CPU's decode.
        let cpu = storage::decode_range(storage::encode_range(c));
        assert!((g - cpu).abs() < 1e-5, "coefficient {i}: GPU {g}, CPU decode {cpu}");
    }
    assert!(
        worst <= 2.0 / 255.0 + 1e-6,
        "worst {worst} beyond half a step of the range encoding"
    );
}

#[test]
fn the_4_tap_filter_is_piecewise_constant_and_exact_on_constant_regions() {
    // Texels 0..4 of row 0 hold representative 0 (value v0), texels 4..8 representative 1 (v1).
    let (v0, v1) = (-0.5f32, 1.25f32);
    let indices: Vec<u16> = (0..8).map(|x| u16::from(x >= 4)).collect();
    let mut codebook = vec![0.0f32; 2 * 4];
    codebook[0] = v0;
    codebook[4] = v1;
    let (tw, th, table) = storage::pack_table_rgba8(&codebook, 2).unwrap();
    let n = 256u32;
    let got = check(2, n, 2, &storage::pack_indices_rgba8(&indices), 8, 1, &table, tw, th, 1);
    // The device's own decodes, read where all four taps agree (far from the step); they match
    // the CPU's within float rounding.
    let (d0, d1) = (f32::from_bits(got[0]), f32::from_bits(got[got.len() - 1]));
    assert!(
        (d0 - storage::decode_range(storage::encode_range(v0))).abs() < 1e-6
            && (d1 - storage::decode_range(storage::encode_range(v1))).abs() < 1e-6
    );
    for (i, word) in got.iter().enumerate() {
        let x = 2.0 + 4.0 * (i as f32 + 0.5) / n as f32;
        // Relative to texel 3's centre (3.5): v0 below 1/4, the mean to 3/4, v1 beyond.
        let f = x - 3.5;
        let want = if f < 0.25 {
            d0
        } else if f < 0.75 {
            0.25 * (d0 + d1 + d0 + d1)
        } else {
            d1
        };
        let g = f32::from_bits(*word);
        if !(0.2..0.3).contains(&f) && !(0.7..0.8).contains(&f) {
            // Away from the switch points (float rounding of the tap positions): the exact value,
            // bit for bit on the constant regions (one look-up there).
            assert_eq!(g.to_bits(), want.to_bits(), "x = {x}: {g} want {want}");
        }
    }
}
