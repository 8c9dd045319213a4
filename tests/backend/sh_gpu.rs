//! glsl/common/sh.glsl on the device against src/sh on the CPU: basis to 8 bands, z-rotation, ZH
//! rotation of caps and the clamped cosine, equirect and cube texel solid angles and directions.
//! The check kernel's output layout is documented in glsl/tests/sh_check.comp. Then the
//! environment projection pass (ShProjector) against the CPU projections: a band-limited sky, a
//! random image and a constant one, each equirectangular and as a cube map. Then the general
//! rotation (against ShRotation, identity, band energies, composition, the 4-band build), the
//! windows and the triple product over sh::product_terms (glsl/tests/sh_ops_check*.comp).

use crate::support as common;

use glam::Vec3;
use penumbra::backend::{vk, BufferDesc, ComputePipelineDesc, MemoryKind};
use penumbra::graph::{Access, RenderGraph, ResourceStates};
use penumbra::sh;
use penumbra::shaders::ShaderLibrary;

/// The real SH of bands 0–2 in the thesis convention (Condon–Shortley phase, m > 0 ↔ cos mφ,
/// m < 0 ↔ sin |m|φ; digest §1.1), written out as polynomials of the unit direction (SH frame),
/// index l(l+1) + m — independent of the library's recurrence.
fn basis_closed_form(d: Vec3) -> [f64; 9] {
    use std::f64::consts::PI;
    let (x, y, z) = (d.x as f64, d.y as f64, d.z as f64);
    let (c0, c1, c2, c20) = (
        (1.0 / (4.0 * PI)).sqrt(),
        (3.0 / (4.0 * PI)).sqrt(),
        (15.0 / (4.0 * PI)).sqrt(),
        (5.0 / (16.0 * PI)).sqrt(),
    );
    [
        c0,
        -c1 * y,
        c1 * z,
        -c1 * x,
        c2 * x * y,
        -c2 * y * z,
        c20 * (3.0 * z * z - 1.0),
        -c2 * x * z,
        0.5 * c2 * (x * x - y * y),
    ]
}

/// The ZH of a cap of half-angle `a` (the height-field thesis Appendix A.1 as the digest writes it, unit
/// radiance): √π(1 − c), (√(3π)/2)s², (√(5π)/2)c s², (√(7π)/8)s²(5c² − 1).
fn cap_closed_form(a: f64) -> [f64; 4] {
    use std::f64::consts::PI;
    let (c, s2) = (a.cos(), a.sin().powi(2));
    [
        PI.sqrt() * (1.0 - c),
        (3.0 * PI).sqrt() / 2.0 * s2,
        (5.0 * PI).sqrt() / 2.0 * c * s2,
        (7.0 * PI).sqrt() / 8.0 * s2 * (5.0 * c * c - 1.0),
    ]
}

/// Besides the CPU library, two independent values per texel: the GPU's basis of bands 0–2
/// against the closed-form polynomials above (measured 2.4e-7, 1e-5 allowed; cos and sin
/// swapped between m > 0 and m < 0 in the GLSL and the CPU alike, which the CPU comparison
/// cannot see, is off by 0.075 at the first texel, tried), and the GPU's rotated cap (half-angle 0.45) evaluated with
/// the GPU's basis at its own axis against Σ_l z_l √((2l+1)/4π) from the Appendix A.1 closed
/// form (the ZH rule leaves a cap's value on its axis unchanged; measured 6.2e-7 relative, 1e-5
/// allowed).
#[test]
fn glsl_sh_matches_the_cpu_library() {
    let mut gpu = common::test_gpu();
    let pipeline = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                name: "sh check".into(),
                shader: "tests/sh_check.comp".into(),
                specialization: vec![],
            },
            &ShaderLibrary::test_kernels(),
        )
        .unwrap();
    let size = 128 * 128 * 4;
    let out = gpu
        .create_buffer(&BufferDesc {
            name: "sh check".into(),
            size,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuToCpu,
        })
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    let c = vk::PipelineStageFlags2::COMPUTE_SHADER;
    graph
        .pass("sh check")
        .buffer(out, Access::StorageWrite { stages: c }, Some("result"))
        .record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[])?;
            ctx.rec.dispatch([128, 1, 1])
        });
    graph
        .pass("host")
        .buffer(out, Access::HostRead, None)
        .record(|_| Ok(()));
    common::run_once(&gpu, frame, graph);
    let got: Vec<f32> = bytemuck::cast_slice(&gpu.read_buffer(out).unwrap()).to_vec();

    let close = |a: f32, b: f64, tol: f64, what: &str| {
        assert!((a as f64 - b).abs() <= tol * b.abs().max(1.0), "{what}: GPU {a} vs {b}")
    };
    let (mut worst_basis, mut worst_cap) = (0.0f64, 0.0f64);
    for i in 0..128usize {
        let r = &got[i * 128..(i + 1) * 128];
        let (tx, ty) = (i % 16, (i / 16) % 8);
        let dir = sh::world_to_sh(sh::equirect_texel_dir_world(tx, ty, 16, 8));
        // Independent values first, then the CPU library.
        for (k, want) in basis_closed_form(dir).into_iter().enumerate() {
            worst_basis = worst_basis.max((r[k] as f64 - want).abs());
            close(
                r[k],
                want,
                1e-5,
                &format!("texel {i} basis {k} against the closed form"),
            );
        }
        let on_axis: f64 = (0..16).map(|k| r[96 + k] as f64 * r[k] as f64).sum();
        let zh = cap_closed_form(0.45);
        let want: f64 = (0..4)
            .map(|l| zh[l] * ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI)).sqrt())
            .sum();
        worst_cap = worst_cap.max((on_axis - want).abs() / want);
        close(
            on_axis as f32,
            want,
            1e-5,
            &format!("texel {i}: the cap on its axis against Appendix A.1"),
        );
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
        close(
            r[112],
            sh::equirect_texel_solid_angle(ty, 16, 8),
            1e-5,
            "equirect solid angle",
        );
        let omega = sh::cube_texel_solid_angle(i % 16, (i / 16) % 16, 16);
        assert!(
            (r[113] as f64 - omega).abs() <= 2e-6 * omega,
            "cube solid angle: GPU {} vs CPU {omega}",
            r[113]
        );
        let cd = sh::cube_texel_dir_world(i % 6, i % 16, (i / 16) % 16, 16);
        for (k, v) in [cd.x, cd.y, cd.z].into_iter().enumerate() {
            close(r[114 + k], v as f64, 1e-5, "cube texel direction");
        }
        let mut cc = sh::zh_rotate(&sh::clamped_cosine_zh(8).unwrap(), dir).unwrap();
        sh::rotate_z(&mut cc, 0.3).unwrap();
        close(r[117], sh::eval(&cc, Vec3::X).unwrap(), 1e-4, "rotated clamped cosine");
    }
    eprintln!("against closed forms: basis (bands 0-2) {worst_basis:.1e}, cap on its axis {worst_cap:.1e} relative");
    common::assert_clean(&gpu);
}

// ---- The environment projection pass (src/sh/gpu.rs, glsl/sh/) against src/sh/projection.rs.

/// Uploads `texels` (RGBA; a cube's six faces in layer order) as an equirect (`cube = false`,
/// `w`×`h`) or cube (`w`² faces) image, projects it on the device onto `bands` bands and reads
/// the coefficients back (SH frame).
fn gpu_project(
    gpu: &mut penumbra::backend::Gpu,
    cube: bool,
    w: u32,
    h: u32,
    texels: &[[f32; 4]],
    bands: u32,
) -> Vec<Vec3> {
    use penumbra::backend::ImageDesc;
    let desc = if cube {
        ImageDesc::new_cube("env", vk::Format::R32G32B32A32_SFLOAT, w)
    } else {
        ImageDesc::new_2d("env", vk::Format::R32G32B32A32_SFLOAT, w, h)
    };
    let image = gpu
        .create_image(&desc.usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST))
        .unwrap();
    gpu.upload_image(image, 0, bytemuck::cast_slice(texels)).unwrap();
    let mut states = ResourceStates::default();
    states
        .set_image(
            gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )
        .unwrap();
    let projector = sh::ShProjector::new(gpu, &ShaderLibrary::Embedded, "sh projection").unwrap();
    let out = gpu
        .create_buffer(&BufferDesc {
            name: "sh out".into(),
            size: 64 * 16,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuToCpu,
        })
        .unwrap();
    let env = sh::EnvImage::of(gpu, image).unwrap();
    assert_eq!(
        env.layout,
        if cube {
            sh::EnvLayout::Cube
        } else {
            sh::EnvLayout::Equirect
        }
    );
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    projector
        .add_passes(&mut graph, "sh projection", env, bands, out)
        .unwrap();
    graph
        .pass("host")
        .buffer(out, Access::HostRead, None)
        .record(|_| Ok(()));
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
    let got: Vec<[f32; 4]> = bytemuck::cast_slice(&gpu.read_buffer(out).unwrap()).to_vec();
    got[..(bands * bands) as usize]
        .iter()
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// World directions of every texel centre: equirect `w`×`h`, or six `w`² cube faces.
fn texel_dirs(cube: bool, w: usize, h: usize) -> Vec<Vec3> {
    if cube {
        (0..6 * w * w)
            .map(|i| sh::cube_texel_dir_world(i / (w * w), i % w, (i % (w * w)) / w, w).normalize())
            .collect()
    } else {
        (0..w * h)
            .map(|i| sh::equirect_texel_dir_world(i % w, i / w, w, h))
            .collect()
    }
}

/// Per-coefficient scale of the float rounding of the projection sum: Σ_t |L_t|·Ω_t·|y_k(ω_t)|
/// (channel max), in f64.
fn abs_scale(cube: bool, w: usize, h: usize, texels: &[[f32; 4]], bands: usize) -> Vec<f64> {
    let mut s = vec![0.0f64; bands * bands];
    let mut y = vec![0.0f64; bands * bands];
    for (i, d) in texel_dirs(cube, w, h).into_iter().enumerate() {
        let omega = if cube {
            sh::cube_texel_solid_angle(i % w, (i % (w * w)) / w, w)
        } else {
            sh::equirect_texel_solid_angle(i / w, w, h)
        };
        sh::eval_basis_f64(sh::world_to_sh(d).as_dvec3(), bands, &mut y).unwrap();
        let l = texels[i][..3].iter().fold(0.0f64, |m, v| m.max(v.abs() as f64));
        for k in 0..bands * bands {
            s[k] += l * omega * y[k].abs();
        }
    }
    s
}

// The random images' stream.
use crate::support::rng::XorShift as Rng;

/// (a) A band-limited environment L = Σ f_k y_k (4 bands, per channel f, 2f, −f) sampled at
/// the texel centres comes back as f. The only error is the texels' quadrature: the φ sum is
/// exact for band-limited content, the θ midpoint rule is second order, ~(π/32)²/24·l² ≈ 1e-3
/// of the largest coefficient at 32 rows; the cube's ~1e-4 at 32² faces. Checked against the
/// CPU's quadrature of the same texels too (which isolates the GPU's own error).
#[test]
fn gpu_projection_recovers_a_band_limited_environment() {
    let mut gpu = common::test_gpu();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let f: Vec<f32> = (0..16).map(|_| rng.next_f32() - 0.5).collect();
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
                assert!(
                    err <= tol * s.abs(),
                    "cube {cube}: coefficient {k} channel {ch}: GPU {g} vs {}",
                    s * f[k]
                );
            }
        }
        eprintln!("cube {cube} {w}x{h}: largest |GPU - f| {worst:.2e}");
    }
    common::assert_clean(&gpu);
}

/// Bands 0 and 1 of a texel quadrature written out here, independent of the SH library's
/// basis and solid angles: Ω of an equirect row from its edges' polar angles, (2π/w)(cos θ0 −
/// cos θ1); of a cube texel from the corner formula atan2(uv, √(u² + v² + 1)); the closed-form
/// y_00, y_1m (see `basis_closed_form`).
fn bands01_by_quadrature(cube: bool, w: usize, h: usize, texels: &[[f32; 4]]) -> [[f64; 3]; 4] {
    use std::f64::consts::{PI, TAU};
    let mut c = [[0.0f64; 3]; 4];
    for (i, d) in texel_dirs(cube, w, h).into_iter().enumerate() {
        let omega = if cube {
            let (x, y) = ((i % (w * w)) % w, (i % (w * w)) / w);
            let a = |u: f64, v: f64| (u * v).atan2((u * u + v * v + 1.0).sqrt());
            let e = |k: usize| 2.0 * k as f64 / w as f64 - 1.0;
            a(e(x), e(y)) - a(e(x), e(y + 1)) - a(e(x + 1), e(y)) + a(e(x + 1), e(y + 1))
        } else {
            let row = i / w;
            TAU / w as f64 * ((PI * row as f64 / h as f64).cos() - (PI * (row + 1) as f64 / h as f64).cos())
        };
        let y = basis_closed_form(sh::world_to_sh(d.normalize()));
        for k in 0..4 {
            for ch in 0..3 {
                c[k][ch] += texels[i][ch] as f64 * omega * y[k];
            }
        }
    }
    c
}

/// (b) A random image (values in [0, 1), 8 bands): the GPU matches `project_equirect` /
/// `project_cubemap` to 1e-5 of each coefficient's rounding scale Σ|L|Ω|y_k| (float summation
/// over a few thousand texels, against the CPU's f64; measured ~1e-7 on lavapipe). Bands 0–1
/// also against the quadrature written out above, independent of the library (same bound;
/// measured 9e-8).
#[test]
fn gpu_projection_of_a_random_image_matches_the_cpu() {
    let mut gpu = common::test_gpu();
    let mut rng = Rng(12345);
    for (cube, w, h, tol) in [
        (false, 64usize, 32usize, 1e-5f64),
        (false, 100, 37, 1e-5),
        (true, 32, 32, 1e-5),
    ] {
        let n = if cube { 6 * w * w } else { w * h };
        let texels: Vec<[f32; 4]> = (0..n)
            .map(|_| [rng.next_f32(), rng.next_f32(), rng.next_f32(), 0.0])
            .collect();
        let rgb: Vec<[f32; 3]> = texels.iter().map(|t| [t[0], t[1], t[2]]).collect();
        let cpu = if cube {
            sh::project_cubemap(&rgb, w, 8).unwrap()
        } else {
            sh::project_equirect(&rgb, w, h, 8).unwrap()
        };
        let got = gpu_project(&mut gpu, cube, w as u32, h as u32, &texels, 8);
        let scale = abs_scale(cube, w, h, &texels, 8);
        let mut worst = 0.0f64;
        for k in 0..64 {
            for ch in 0..3 {
                let rel = (got[k][ch] as f64 - cpu[k][ch] as f64).abs() / scale[k];
                worst = worst.max(rel);
                assert!(
                    rel <= tol,
                    "cube {cube} {w}x{h}: coefficient {k} channel {ch}: GPU {} vs CPU {} (scale {})",
                    got[k][ch],
                    cpu[k][ch],
                    scale[k]
                );
            }
        }
        let own = bands01_by_quadrature(cube, w, h, &texels);
        let mut worst_own = 0.0f64;
        for k in 0..4 {
            for ch in 0..3 {
                let rel = (got[k][ch] as f64 - own[k][ch]).abs() / scale[k];
                worst_own = worst_own.max(rel);
                assert!(
                    rel <= tol,
                    "cube {cube} {w}x{h}: coefficient {k} channel {ch}: GPU {} vs the test's quadrature {}",
                    got[k][ch],
                    own[k][ch]
                );
            }
        }
        eprintln!("cube {cube} {w}x{h}: largest |GPU - CPU| / scale {worst:.2e}; bands 0-1 against the test's own quadrature {worst_own:.2e}");
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
        let cpu = if cube {
            sh::project_cubemap(&rgb, w, 6).unwrap()
        } else {
            sh::project_equirect(&rgb, w, h, 6).unwrap()
        };
        let got = gpu_project(&mut gpu, cube, w as u32, h as u32, &texels, 6);
        let c00 = l * sh::CONSTANT_ONE_C00 as f32;
        assert!(
            (got[0] - c00).abs().max_element() <= 2e-6 * c00.max_element(),
            "cube {cube}: c00 {} vs {c00}",
            got[0]
        );
        let mut worst = 0.0f32;
        for k in 1..36 {
            worst = worst.max(got[k].abs().max_element() / c00.max_element());
            assert!(
                (got[k] - cpu[k]).abs().max_element() <= 1e-5 * c00.max_element(),
                "cube {cube}: coefficient {k}: GPU {} vs CPU {}",
                got[k],
                cpu[k]
            );
            assert!(
                got[k].abs().max_element() <= 2e-3 * c00.max_element(),
                "cube {cube}: coefficient {k}: {}",
                got[k]
            );
        }
        eprintln!(
            "cube {cube}: c00 {} (exact {c00}); largest other |c_k|/c00 {worst:.2e}",
            got[0]
        );
    }
    common::assert_clean(&gpu);
}

// ---- General rotation, windows and the triple product of glsl/common/sh.glsl against src/sh/
// (check kernels glsl/tests/sh_ops_check*.comp; layout in sh_ops_check.glsl).

const OPS_CASES: usize = 64;
const OPS_STRIDE: usize = 512;

/// One check case: the rotations (R1, R2 in the SH frame, Rw in the world frame), a window width
/// and two random 8-band vectors.
struct OpsCase {
    r1: glam::Mat3,
    r2: glam::Mat3,
    rw: glam::Mat3,
    width: f32,
    a: Vec<f32>,
    b: Vec<f32>,
}

/// Random rotations (normalised quaternions) and coefficients in [-1, 1); the last two cases'
/// widths are 0 and NaN (refused on the CPU; all-zero windows on the GPU).
fn ops_cases() -> Vec<OpsCase> {
    let mut rng = Rng(0x5eed_0f5b_0007);
    let mut s = move || 2.0 * rng.next_f32() - 1.0;
    (0..OPS_CASES)
        .map(|i| {
            let mut rot = || glam::Mat3::from_quat(glam::Quat::from_xyzw(s(), s(), s(), s()).normalize());
            let (r1, r2, rw) = (rot(), rot(), rot());
            let width = match i {
                62 => 0.0,
                63 => f32::NAN,
                _ => 0.5 + 0.25 * i as f32, // 0.5 .. 15.75: below, at and above 8 bands
            };
            let a = (0..64).map(|_| s()).collect();
            let b = (0..64).map(|_| s()).collect();
            OpsCase {
                r1,
                r2,
                rw,
                width,
                a,
                b,
            }
        })
        .collect()
}

/// Runs `shader` on `cases` with the 8-band product term list; returns each case's 512 outputs.
fn run_ops_check(shader: &str, cases: &[OpsCase]) -> Vec<Vec<f32>> {
    let mut gpu = common::test_gpu();
    let pipeline = gpu
        .create_compute_pipeline(
            &ComputePipelineDesc {
                name: "sh ops check".into(),
                shader: shader.into(),
                specialization: vec![],
            },
            &ShaderLibrary::test_kernels(),
        )
        .unwrap();
    let mut input = Vec::<f32>::with_capacity(OPS_CASES * 48 * 4);
    for c in cases {
        for m in [c.r1, c.r2, c.rw] {
            for col in [m.x_axis, m.y_axis, m.z_axis] {
                input.extend([col.x, col.y, col.z, 0.0]);
            }
        }
        input.extend([c.width, 0.0, 0.0, 0.0]);
        input.extend(&c.a);
        input.extend(&c.b);
        input.resize(input.len() + 6 * 4, 0.0); // 42 vec4s used of the case's 48
    }
    let terms = sh::product_terms(8).unwrap();
    let cases_buf = gpu
        .create_buffer_init(
            "sh ops cases",
            vk::BufferUsageFlags::STORAGE_BUFFER,
            bytemuck::cast_slice(&input),
        )
        .unwrap();
    let terms_buf = gpu
        .create_buffer_init(
            "sh ops terms",
            vk::BufferUsageFlags::STORAGE_BUFFER,
            bytemuck::cast_slice(&terms),
        )
        .unwrap();
    let out = gpu
        .create_buffer(&BufferDesc {
            name: "sh ops result".into(),
            size: (OPS_CASES * OPS_STRIDE * 4) as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuToCpu,
        })
        .unwrap();
    let frame = gpu.create_frame().unwrap();
    let mut graph = RenderGraph::new();
    let c = vk::PipelineStageFlags2::COMPUTE_SHADER;
    let count = [terms.len() as i32];
    graph
        .pass("sh ops check")
        .buffer(cases_buf, Access::StorageRead { stages: c }, Some("cases"))
        .buffer(terms_buf, Access::StorageRead { stages: c }, Some("terms"))
        .buffer(out, Access::StorageWrite { stages: c }, Some("result"))
        .record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[])?;
            ctx.rec.push_constants(bytemuck::cast_slice(&count))?;
            ctx.rec.dispatch([OPS_CASES as u32, 1, 1])
        });
    graph
        .pass("host")
        .buffer(out, Access::HostRead, None)
        .record(|_| Ok(()));
    common::run_once(&gpu, frame, graph);
    let got: Vec<f32> = bytemuck::cast_slice(&gpu.read_buffer(out).unwrap()).to_vec();
    common::assert_clean(&gpu);
    got.chunks_exact(OPS_STRIDE).map(<[f32]>::to_vec).collect()
}

/// Largest |gpu - cpu| over a slice pair.
fn worst(gpu: &[f32], cpu: &[f64]) -> f64 {
    assert_eq!(gpu.len(), cpu.len());
    gpu.iter()
        .zip(cpu)
        .map(|(g, c)| (*g as f64 - c).abs())
        .fold(0.0, f64::max)
}

fn f64s(v: &[f32]) -> Vec<f64> {
    v.iter().map(|x| *x as f64).collect()
}

/// Float rounding in the recurrence grows with the band; coefficients are O(1) here, and the
/// f32 recurrence measured (lavapipe) under the bound by the margin printed below.
const ROTATION_TOL: f64 = 1e-5;

/// The band-1 part of an SH vector as the vector a with f(d) = a·d: y_1,−1 = −√(3/4π) y,
/// y_1,0 = √(3/4π) z, y_1,1 = −√(3/4π) x (see `basis_closed_form`).
fn band1_lobe(c: &[f32]) -> glam::DVec3 {
    glam::DVec3::new(-c[3] as f64, -c[1] as f64, c[2] as f64) * (3.0 / (4.0 * std::f64::consts::PI)).sqrt()
}

/// sh_rotate against ShRotation (f64) for 64 random rotations and vectors, 8 bands; a 4-band
/// call leaves the higher bands alone; a world-frame rotation through sh_rotation_from_world
/// equals ShRotation::from_world. Independent of the CPU recurrence: band 0 is unchanged and
/// band 1 is a linear function a·d, which rotating by R turns into (R a)·d — checked for R1 (SH
/// frame) and Rw (world frame, conjugated by the y-up ↔ z-up swap written out here); measured
/// 2.0e-7, ROTATION_TOL allowed. The band-1 block transposed in the GLSL and the CPU alike
/// (rotating by Rᵀ), which the CPU comparison cannot see, is off by 0.96 (tried).
#[test]
fn glsl_general_rotation_matches_the_cpu() {
    let cases = ops_cases();
    let got = run_ops_check("tests/sh_ops_check.comp", &cases);
    let (mut w8, mut w4, mut ww, mut wl) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (i, (c, g)) in cases.iter().zip(&got).enumerate() {
        let a = f64s(&c.a);
        let cpu = sh::ShRotation::new(c.r1, 8).unwrap().rotate(&a).unwrap();
        w8 = w8.max(worst(&g[0..64], &cpu));
        let cpu4 = sh::ShRotation::new(c.r1, 4).unwrap().rotate(&a[..16]).unwrap();
        w4 = w4.max(worst(&g[192..208], &cpu4));
        assert_eq!(
            &g[208..256],
            &c.a[16..],
            "case {i}: a 4-band rotation changed bands 4..7"
        );
        let cpuw = sh::ShRotation::from_world(c.rw, 8).unwrap().rotate(&a).unwrap();
        ww = ww.max(worst(&g[256..320], &cpuw));
        // Independent: band 0 kept, band 1 rotated as a vector.
        let swap = glam::DMat3::from_cols(glam::DVec3::X, glam::DVec3::Z, -glam::DVec3::Y); // world (x, y, z) → SH (x, −z, y)
        for (out, r) in [
            (0usize, c.r1.as_dmat3()),
            (256, swap * c.rw.as_dmat3() * swap.transpose()),
        ] {
            let want = r * band1_lobe(&c.a);
            let got = band1_lobe(&g[out..out + 4]);
            wl = wl
                .max((got - want).abs().max_element())
                .max((g[out] - c.a[0]).abs() as f64);
        }
    }
    eprintln!("sh_rotate vs ShRotation, largest |GPU - CPU|: 8 bands {w8:.2e}, 4 bands {w4:.2e}, world frame {ww:.2e}");
    assert!(
        w8 <= ROTATION_TOL && w4 <= ROTATION_TOL && ww <= ROTATION_TOL,
        "8 bands {w8:e}, 4 bands {w4:e}, world {ww:e}"
    );
    eprintln!("band 0 and 1 against the rotated vector: largest difference {wl:.2e}");
    assert!(wl <= ROTATION_TOL, "band 1 is not the rotated vector: {wl:e}");
}

/// Rotation by the identity returns the vector; every rotation keeps each band's energy
/// sum_m c_lm^2 (the blocks are orthogonal).
#[test]
fn glsl_rotation_identity_and_band_energies() {
    let cases = ops_cases();
    let got = run_ops_check("tests/sh_ops_check.comp", &cases);
    let (mut wid, mut wen) = (0.0f64, 0.0f64);
    for (c, g) in cases.iter().zip(&got) {
        wid = wid.max(worst(&g[128..192], &f64s(&c.a)));
        for l in 0..8 {
            let band = l * l..(l + 1) * (l + 1);
            let e0: f64 = c.a[band.clone()].iter().map(|v| (*v as f64).powi(2)).sum();
            for out in [0usize, 64, 256] {
                let e: f64 = g[out..][band.clone()].iter().map(|v| (*v as f64).powi(2)).sum();
                wen = wen.max((e - e0).abs() / e0);
            }
        }
    }
    eprintln!("identity: largest |GPU - a| {wid:.2e}; band energy: largest relative change {wen:.2e}");
    assert!(wid <= 1e-6, "identity rotation moved a coefficient by {wid:e}");
    assert!(wen <= 1e-5, "a rotation changed a band's energy by {wen:e} (relative)");
}

/// Rotating by R1 then R2 on the GPU equals rotating once by R2 R1 on the CPU.
#[test]
fn glsl_rotation_composes() {
    let cases = ops_cases();
    let got = run_ops_check("tests/sh_ops_check.comp", &cases);
    let mut w = 0.0f64;
    for (c, g) in cases.iter().zip(&got) {
        let cpu = sh::ShRotation::new(c.r2 * c.r1, 8)
            .unwrap()
            .rotate(&f64s(&c.a))
            .unwrap();
        w = w.max(worst(&g[64..128], &cpu));
    }
    eprintln!("sh_rotate(R2, sh_rotate(R1, a)) vs ShRotation(R2 R1): largest difference {w:.2e}");
    assert!(w <= 2.0 * ROTATION_TOL, "composition off by {w:e}");
}

/// With SH_ROTATE_MAX_BANDS 4 the first 4 bands rotate as before and an 8-band request zeroes
/// bands 4..7 (documented: never silently unrotated).
#[test]
fn glsl_rotation_with_4_band_scratch() {
    let cases = ops_cases();
    let got = run_ops_check("tests/sh_ops_check4.comp", &cases);
    let mut w = 0.0f64;
    for (i, (c, g)) in cases.iter().zip(&got).enumerate() {
        let cpu = sh::ShRotation::new(c.r1, 4).unwrap().rotate(&f64s(&c.a[..16])).unwrap();
        w = w.max(worst(&g[0..16], &cpu)).max(worst(&g[192..208], &cpu));
        assert!(g[16..64].iter().all(|v| *v == 0.0), "case {i}: bands 4..7 not zeroed");
    }
    eprintln!("4-band scratch: largest |GPU - CPU| {w:.2e}");
    assert!(w <= ROTATION_TOL, "{w:e}");
}

/// sh_hanning / sh_lanczos equal sh::hanning / sh::lanczos for widths 0.5..15.75 (below, at and
/// above the band count), sh_apply_window scales each band; width 0 and NaN give all zeros.
/// Independent of the CPU: at width 4 (case 14) the windows are the literal values of their
/// definitions (Sloan, "Stupid SH tricks"): Hanning (1 + cos(πl/4))/2 = 1, 0.853553, 0.5,
/// 0.146447, then 0; Lanczos sin(πl/4)/(πl/4) = 1, 0.900316, 0.636620, 0.300105, then 0
/// (measured 4e-8, 1e-6 allowed; a Hanning one band wider in the GLSL and the CPU alike, which
/// the CPU comparison cannot see, is off by 0.2, tried).
#[test]
fn glsl_windows_match_the_cpu() {
    let cases = ops_cases();
    let got = run_ops_check("tests/sh_ops_check.comp", &cases);
    let mut w = 0.0f64;
    for (i, (c, g)) in cases.iter().zip(&got).enumerate() {
        if c.width.is_nan() || c.width <= 0.0 {
            assert!(
                g[384..464].iter().all(|v| *v == 0.0),
                "case {i}: width {} must give zero windows",
                c.width
            );
            continue;
        }
        let h = sh::hanning(8, c.width as f64).unwrap();
        let l = sh::lanczos(8, c.width as f64).unwrap();
        w = w.max(worst(&g[384..392], &h)).max(worst(&g[392..400], &l));
        let mut a = f64s(&c.a);
        sh::apply_window(&mut a, &l).unwrap();
        w = w.max(worst(&g[400..464], &a));
    }
    eprintln!("windows: largest |GPU - CPU| {w:.2e}");
    assert!(w <= 1e-6, "{w:e}");
    assert_eq!(cases[14].width, 4.0);
    let hanning4 = [1.0, 0.853553390593, 0.5, 0.146446609407, 0.0, 0.0, 0.0, 0.0];
    let lanczos4 = [
        1.0,
        0.900316316157,
        std::f64::consts::FRAC_2_PI,
        0.300105438719,
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let literal = worst(&got[14][384..392], &hanning4).max(worst(&got[14][392..400], &lanczos4));
    eprintln!("width 4 against the literal windows: {literal:.1e}");
    assert!(
        literal <= 1e-6,
        "width-4 windows: {:?} {:?}",
        &got[14][384..392],
        &got[14][392..400]
    );
}

/// sh_product over sh::product_terms(8) equals sh::product (f64) to 1e-5 of each output's
/// rounding scale sum |Gamma_ijk a_i b_j|. Independent of the term list: the product's c_00 is
/// ∫ f g y_00 = y_00 Σ_k a_k b_k by orthonormality alone (both inputs have all 8 bands, and c_00
/// needs no truncation), to 1e-5 of y_00 Σ|a_k b_k| (measured 6.5e-8; a tensor without band 7's
/// terms, which the CPU shares, fails it, tried).
#[test]
fn glsl_triple_product_matches_the_cpu() {
    let cases = ops_cases();
    let got = run_ops_check("tests/sh_ops_check.comp", &cases);
    let terms = sh::product_terms(8).unwrap();
    let mut w = 0.0f64;
    for (i, (c, g)) in cases.iter().zip(&got).enumerate() {
        let (a, b) = (f64s(&c.a), f64s(&c.b));
        let cpu = sh::product(&a, &b, 8).unwrap();
        let mut scale = [0.0f64; 64];
        for [packed, bits] in &terms {
            let (ti, tj, tk) = (
                (packed & 0xff) as usize,
                ((packed >> 8) & 0xff) as usize,
                (packed >> 16) as usize,
            );
            scale[tk] += (f32::from_bits(*bits) as f64 * a[ti] * b[tj]).abs();
        }
        for k in 0..64 {
            let rel = (g[320 + k] as f64 - cpu[k]).abs() / scale[k].abs().max(1e-30);
            w = w.max(rel);
            assert!(
                rel <= 1e-5,
                "case {i} coefficient {k}: GPU {} vs CPU {} (scale {})",
                g[320 + k],
                cpu[k],
                scale[k]
            );
        }
    }
    eprintln!("sh_product vs sh::product: largest |GPU - CPU| / scale {w:.2e}");
    let mut w00 = 0.0f64;
    for (i, (c, g)) in cases.iter().zip(&got).enumerate() {
        let dot: f64 = c.a.iter().zip(&c.b).map(|(x, y)| *x as f64 * *y as f64).sum();
        let y00 = 0.5 / std::f64::consts::PI.sqrt();
        let scale: f64 =
            c.a.iter()
                .zip(&c.b)
                .map(|(x, y)| (*x as f64 * *y as f64).abs())
                .sum::<f64>()
                * y00;
        let rel = (g[320] as f64 - y00 * dot).abs() / scale;
        w00 = w00.max(rel);
        assert!(rel <= 1e-5, "case {i}: c_00 {} vs y_00·a·b {}", g[320], y00 * dot);
    }
    eprintln!("c_00 against y_00 Σ a_k b_k: largest difference / scale {w00:.2e}");
}
