//! glsl/common/sh.glsl on the device against src/sh on the CPU: basis to 8 bands, z-rotation, ZH
//! rotation of caps and the clamped cosine, equirect and cube texel solid angles and directions.
//! The check kernel's output layout is documented in glsl/util/sh_check.comp.

mod common;

use glam::Vec3;
use penumbra::backend::{vk, BufferDesc, ComputePipelineDesc, MemoryKind};
use penumbra::graph::{Access, RenderGraph, ResourceStates};
use penumbra::sh;
use penumbra::shaders::ShaderLibrary;

#[test]
fn glsl_sh_matches_the_cpu_library() {
    let mut gpu = common::test_gpu();
    let pipeline = gpu
        .create_compute_pipeline(&ComputePipelineDesc { name: "sh check".into(), shader: "util/sh_check.comp".into(), specialization: vec![] }, &ShaderLibrary::Embedded)
        .unwrap();
    let size = 128 * 128 * 4;
    let out = gpu.create_buffer(&BufferDesc { name: "sh check".into(), size, usage: vk::BufferUsageFlags::STORAGE_BUFFER, memory: MemoryKind::GpuToCpu }).unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    let c = vk::PipelineStageFlags2::COMPUTE_SHADER;
    graph.pass("sh check").buffer(out, Access::StorageWrite { stages: c }, Some("result")).record(move |ctx| {
        ctx.rec.bind_pipeline(pipeline)?;
        ctx.bind(&[])?;
        ctx.rec.dispatch([128, 1, 1])
    });
    graph.pass("host").buffer(out, Access::HostRead, None).record(|_| Ok(()));
    let mut states = ResourceStates::default();
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    let got: Vec<f32> = bytemuck::cast_slice(&gpu.read_buffer(out).unwrap()).to_vec();

    let close = |a: f32, b: f64, tol: f64, what: &str| assert!((a as f64 - b).abs() <= tol * b.abs().max(1.0), "{what}: GPU {a} vs CPU {b}");
    for i in 0..128usize {
        let r = &got[i * 128..(i + 1) * 128];
        let (tx, ty) = (i % 16, (i / 16) % 8);
        let dir = sh::world_to_sh(sh::equirect_texel_dir_world(tx, ty, 16, 8));
        let mut y = vec![0.0f32; 64];
        sh::eval_basis(dir, 8, &mut y).unwrap();
        for k in 0..64 {
            close(r[k], y[k] as f64, 1e-5, &format!("texel {i} basis {k}"));
        }
        for k in 0..16 {
            close(r[64 + k], y[k] as f64, 1e-5, &format!("texel {i} sh_eval16 {k}"));
        }
        let mut rotated: Vec<f64> = y[..16].iter().map(|&v| v as f64).collect();
        sh::rotate_z(&mut rotated, 0.7).unwrap();
        for k in 0..16 {
            close(r[80 + k], rotated[k], 1e-5, &format!("texel {i} rotate_z {k}"));
        }
        let cap = sh::zh_rotate(&sh::cap_zh(0.45, 4).unwrap(), dir).unwrap();
        for k in 0..16 {
            close(r[96 + k], cap[k], 1e-5, &format!("texel {i} cap {k}"));
        }
        close(r[112], sh::equirect_texel_solid_angle(ty, 16, 8), 1e-5, "equirect solid angle");
        close(r[113], sh::cube_texel_solid_angle(i % 16, (i / 16) % 16, 16), 1e-4, "cube solid angle");
        let cd = sh::cube_texel_dir_world(i % 6, i % 16, (i / 16) % 16, 16);
        for (k, v) in [cd.x, cd.y, cd.z].into_iter().enumerate() {
            close(r[114 + k], v as f64, 1e-5, "cube texel direction");
        }
        let mut cc = sh::zh_rotate(&sh::clamped_cosine_zh(8).unwrap(), dir).unwrap();
        sh::rotate_z(&mut cc, 0.3).unwrap();
        close(r[117], sh::eval(&cc, Vec3::X).unwrap(), 1e-4, "rotated clamped cosine");
    }
    common::assert_clean(&gpu);
}
