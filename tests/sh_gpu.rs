//! glsl/common/sh.glsl on the device against src/sh on the CPU: basis to 8 bands, z-rotation, ZH
//! rotation of caps and the clamped cosine, equirect and cube texel solid angles and directions.
//! The check kernel's output layout is documented in glsl/util/sh_check.comp. Then the
//! environment projection pass (ShProjector) against the CPU projections: a band-limited sky, a
//! random image and a constant one, each equirectangular and as a cube map.

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
        let omega = sh::cube_texel_solid_angle(i % 16, (i / 16) % 16, 16);
        assert!((r[113] as f64 - omega).abs() <= 2e-6 * omega, "cube solid angle: GPU {} vs CPU {omega}", r[113]);
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

// ---- The environment projection pass (src/sh/gpu.rs, glsl/sh/) against src/sh/projection.rs.

/// Uploads `texels` (RGBA; a cube's six faces in layer order) as an equirect (`cube = false`,
/// `w`×`h`) or cube (`w`² faces) image, projects it on the device onto `bands` bands and reads
/// the coefficients back (SH frame).
fn gpu_project(gpu: &mut penumbra::backend::Gpu, cube: bool, w: u32, h: u32, texels: &[[f32; 4]], bands: u32) -> Vec<Vec3> {
    use penumbra::backend::ImageDesc;
    let desc = if cube { ImageDesc::new_cube("env", vk::Format::R32G32B32A32_SFLOAT, w) } else { ImageDesc::new_2d("env", vk::Format::R32G32B32A32_SFLOAT, w, h) };
    let image = gpu.create_image(&desc.usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST)).unwrap();
    gpu.upload_image(image, 0, bytemuck::cast_slice(texels)).unwrap();
    let mut states = ResourceStates::default();
    states.set_image(gpu, image, Access::SampledRead { stages: vk::PipelineStageFlags2::ALL_COMMANDS }).unwrap();
    let projector = sh::ShProjector::new(gpu, &ShaderLibrary::Embedded, "sh projection").unwrap();
    let out = gpu.create_buffer(&BufferDesc { name: "sh out".into(), size: 64 * 16, usage: vk::BufferUsageFlags::STORAGE_BUFFER, memory: MemoryKind::GpuToCpu }).unwrap();
    let env = sh::EnvImage::of(gpu, image).unwrap();
    assert_eq!(env.layout, if cube { sh::EnvLayout::Cube } else { sh::EnvLayout::Equirect });
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    projector.add_passes(&mut graph, "sh projection", env, bands, out).unwrap();
    graph.pass("host").buffer(out, Access::HostRead, None).record(|_| Ok(()));
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    let got: Vec<[f32; 4]> = bytemuck::cast_slice(&gpu.read_buffer(out).unwrap()).to_vec();
    got[..(bands * bands) as usize].iter().map(|c| Vec3::new(c[0], c[1], c[2])).collect()
}

/// World directions of every texel centre: equirect `w`×`h`, or six `w`² cube faces.
fn texel_dirs(cube: bool, w: usize, h: usize) -> Vec<Vec3> {
    if cube {
        (0..6 * w * w).map(|i| sh::cube_texel_dir_world(i / (w * w), i % w, (i % (w * w)) / w, w).normalize()).collect()
    } else {
        (0..w * h).map(|i| sh::equirect_texel_dir_world(i % w, i / w, w, h)).collect()
    }
}

/// Per-coefficient scale of the float rounding of the projection sum: Σ_t |L_t|·Ω_t·|y_k(ω_t)|
/// (channel max), in f64.
fn abs_scale(cube: bool, w: usize, h: usize, texels: &[[f32; 4]], bands: usize) -> Vec<f64> {
    let mut s = vec![0.0f64; bands * bands];
    let mut y = vec![0.0f64; bands * bands];
    for (i, d) in texel_dirs(cube, w, h).into_iter().enumerate() {
        let omega = if cube { sh::cube_texel_solid_angle(i % w, (i % (w * w)) / w, w) } else { sh::equirect_texel_solid_angle(i / w, w, h) };
        sh::eval_basis_f64(sh::world_to_sh(d).as_dvec3(), bands, &mut y).unwrap();
        let l = texels[i][..3].iter().fold(0.0f64, |m, v| m.max(v.abs() as f64));
        for k in 0..bands * bands {
            s[k] += l * omega * y[k].abs();
        }
    }
    s
}

/// A small deterministic generator (xorshift) for the random images.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// (a) A band-limited environment L = Σ f_k y_k (4 bands, per channel f, 2f, −f) sampled at
/// the texel centres comes back as f. The only error is the texels' quadrature: the φ sum is
/// exact for band-limited content, the θ midpoint rule is second order, ~(π/32)²/24·l² ≈ 1e-3
/// of the largest coefficient at 32 rows; the cube's ~1e-4 at 32² faces. Checked against the
/// CPU's quadrature of the same texels too (which isolates the GPU's own error).
#[test]
fn gpu_projection_recovers_a_band_limited_environment() {
    let mut gpu = common::test_gpu();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let f: Vec<f32> = (0..16).map(|_| rng.next() - 0.5).collect();
    for (cube, w, h, tol) in [(false, 64usize, 32usize, 1e-3f32), (true, 32, 32, 1e-3)] {
        let texels: Vec<[f32; 4]> = texel_dirs(cube, w, h)
            .into_iter()
            .map(|d| {
                let mut y = [0.0f32; 16];
                sh::eval_basis(sh::world_to_sh(d), 4, &mut y).unwrap();
                let v: f32 = f.iter().zip(&y).map(|(a, b)| a * b).sum();
                [v, 2.0 * v, -v, 0.0]
            })
            .collect();
        let got = gpu_project(&mut gpu, cube, w as u32, h as u32, &texels, 4);
        let mut worst = 0.0f32;
        for (k, c) in got.iter().enumerate() {
            for (ch, (g, s)) in [(c.x, 1.0), (c.y, 2.0), (c.z, -1.0)].into_iter().enumerate() {
                let err = (g - s * f[k]).abs();
                worst = worst.max(err / s.abs());
                assert!(err <= tol * s.abs(), "cube {cube}: coefficient {k} channel {ch}: GPU {g} vs {}", s * f[k]);
            }
        }
        eprintln!("cube {cube} {w}x{h}: largest |GPU - f| {worst:.2e}");
    }
    common::assert_clean(&gpu);
}

/// (b) A random image (values in [0, 1), 8 bands): the GPU matches `project_equirect` /
/// `project_cubemap` to 1e-5 of each coefficient's rounding scale Σ|L|Ω|y_k| (float summation
/// over a few thousand texels, against the CPU's f64; measured ~1e-7 on lavapipe).
#[test]
fn gpu_projection_of_a_random_image_matches_the_cpu() {
    let mut gpu = common::test_gpu();
    let mut rng = Rng(12345);
    for (cube, w, h, tol) in [(false, 64usize, 32usize, 1e-5f64), (false, 100, 37, 1e-5), (true, 32, 32, 1e-5)] {
        let n = if cube { 6 * w * w } else { w * h };
        let texels: Vec<[f32; 4]> = (0..n).map(|_| [rng.next(), rng.next(), rng.next(), 0.0]).collect();
        let rgb: Vec<[f32; 3]> = texels.iter().map(|t| [t[0], t[1], t[2]]).collect();
        let cpu = if cube { sh::project_cubemap(&rgb, w, 8).unwrap() } else { sh::project_equirect(&rgb, w, h, 8).unwrap() };
        let got = gpu_project(&mut gpu, cube, w as u32, h as u32, &texels, 8);
        let scale = abs_scale(cube, w, h, &texels, 8);
        let mut worst = 0.0f64;
        for k in 0..64 {
            for ch in 0..3 {
                let rel = (got[k][ch] as f64 - cpu[k][ch] as f64).abs() / scale[k];
                worst = worst.max(rel);
                assert!(rel <= tol, "cube {cube} {w}x{h}: coefficient {k} channel {ch}: GPU {} vs CPU {} (scale {})", got[k][ch], cpu[k][ch], scale[k]);
            }
        }
        eprintln!("cube {cube} {w}x{h}: largest |GPU - CPU| / scale {worst:.2e}");
    }
    common::assert_clean(&gpu);
}

/// (c) A constant image L: c00 = 2√π·L to float rounding (the texel solid angles sum to 4π
/// exactly), and every other coefficient is the quadrature's residue of ∫y_k = 0 — the same as
/// the CPU's (1e-5 of c00). That residue is zero for m ≠ 0 (uniform φ) and, for the zonal terms,
/// the θ midpoint rule's O(Δθ²) error: measured 1.2e-3·c00 at 32 rows (l = 4), bounded here by
/// 2e-3; the cube's (only l = 4 survives its symmetry) is smaller.
#[test]
fn gpu_projection_of_a_constant_image_is_band_zero() {
    let mut gpu = common::test_gpu();
    let l = Vec3::new(0.5, 1.0, 2.0);
    for (cube, w, h) in [(false, 64usize, 32usize), (true, 32, 32)] {
        let n = if cube { 6 * w * w } else { w * h };
        let texels = vec![[l.x, l.y, l.z, 0.0]; n];
        let rgb = vec![[l.x, l.y, l.z]; n];
        let cpu = if cube { sh::project_cubemap(&rgb, w, 6).unwrap() } else { sh::project_equirect(&rgb, w, h, 6).unwrap() };
        let got = gpu_project(&mut gpu, cube, w as u32, h as u32, &texels, 6);
        let c00 = l * sh::CONSTANT_ONE_C00 as f32;
        assert!((got[0] - c00).abs().max_element() <= 2e-6 * c00.max_element(), "cube {cube}: c00 {} vs {c00}", got[0]);
        let mut worst = 0.0f32;
        for k in 1..36 {
            worst = worst.max(got[k].abs().max_element() / c00.max_element());
            assert!((got[k] - cpu[k]).abs().max_element() <= 1e-5 * c00.max_element(), "cube {cube}: coefficient {k}: GPU {} vs CPU {}", got[k], cpu[k]);
            assert!(got[k].abs().max_element() <= 2e-3 * c00.max_element(), "cube {cube}: coefficient {k}: {}", got[k]);
        }
        eprintln!("cube {cube}: c00 {} (exact {c00}); largest other |c_k|/c00 {worst:.2e}", got[0]);
    }
    common::assert_clean(&gpu);
}
