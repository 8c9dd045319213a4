//! Cube-map environments (`[environment] type = "cube"`) through every consumer, on the device
//! under validation: the forward method's sky pass and SH irradiance against the same sky as an
//! equirect map, the reference path tracer against closed forms (a constant cube, and half-face
//! lights that only the documented face orientation puts where the test expects them), and the
//! height-field methods' GPU projection against the same sky as an equirect map.
//!
//! The face images are written here from the convention in scenes/README.md (column = s, row = t,
//! `Environment::cube_dir`), so a renderer that read them another way would fail.

use crate::support as common;
use crate::support::heightfield as hf_common;
use crate::support::reference as reference_support;

use std::path::Path;

use glam::Vec3;
use penumbra::environment::EnvironmentMap;
use penumbra::reference::{Batching, LightPaths, ReferenceRenderer, Settings};
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::{Environment, Scene, CUBE_FACE_KEYS};
use penumbra::sh;
use penumbra::util::image_io::HdrImage;
use reference_support::{pixel_average, polygon_irradiance, Agreement};

/// Writes six `n`² EXR faces whose texel centres hold `f(direction)` and returns the
/// `[environment]` table naming them and the texels in layer order.
fn cube_sky(name: &str, n: u32, f: impl Fn(Vec3) -> [f32; 3]) -> (String, Vec<[f32; 4]>) {
    let mut table = "[environment]\ntype = \"cube\"\n".to_string();
    let mut all = Vec::new();
    for (face, key) in CUBE_FACE_KEYS.into_iter().enumerate() {
        let pixels: Vec<[f32; 4]> = (0..n * n)
            .map(|k| {
                let (s, t) = (
                    2.0 * ((k % n) as f32 + 0.5) / n as f32 - 1.0,
                    2.0 * ((k / n) as f32 + 0.5) / n as f32 - 1.0,
                );
                let c = f(Environment::cube_dir(face, s, t).normalize());
                [c[0], c[1], c[2], 1.0]
            })
            .collect();
        let path = common::temp_path(&format!("{name}-{key}.exr"));
        HdrImage {
            width: n,
            height: n,
            pixels: pixels.clone(),
        }
        .write_exr(&path)
        .expect("write face");
        table += &format!("{key} = {:?}\n", path.display().to_string());
        all.extend(pixels.iter().map(|p| [p[0], p[1], p[2], 0.0]));
    }
    (table, all)
}

/// Writes a `w`×`h` equirect EXR whose texel centres hold `f(direction)`; returns its table.
fn equirect_sky(name: &str, w: u32, h: u32, f: impl Fn(Vec3) -> [f32; 3]) -> String {
    let pixels = (0..w * h)
        .map(|i| {
            let c = f(
                sh::equirect_texel_dir_world((i % w) as usize, (i / w) as usize, w as usize, h as usize).normalize(),
            );
            [c[0], c[1], c[2], 1.0]
        })
        .collect();
    let path = common::temp_path(name);
    HdrImage {
        width: w,
        height: h,
        pixels,
    }
    .write_exr(&path)
    .expect("write sky");
    format!(
        "[environment]\ntype = \"image\"\npath = {:?}\n",
        path.display().to_string()
    )
}

fn parse(toml: &str) -> Scene {
    Scene::from_str(toml, "<test>", Path::new(".")).unwrap_or_else(|e| panic!("{e}\n{toml}"))
}

/// A sky linear in the direction, L = a + B·d, different in every channel and along every axis,
/// so a swapped or mirrored face shows. Its gradient on the sphere is at most |B_c| per channel.
const A: [f32; 3] = [1.0, 0.8, 0.6];
const B: [[f32; 3]; 3] = [[0.3, 0.5, -0.2], [-0.1, 0.0, 0.4], [0.0, 0.2, 0.25]];

fn linear_sky(d: Vec3) -> [f32; 3] {
    std::array::from_fn(|c| A[c] + Vec3::from(B[c]).dot(d))
}

/// Forward: the sky pass shows the texel the pixel's ray falls in and the object is lit by the
/// map's 3-band SH irradiance. Cube (32² faces) and equirect (64×32) maps of the same linear sky
/// must agree: on the sky, to the lookup's discretisation — each map returns its texel centre's
/// value, at most the texel's half-diagonal from the ray, ≤ √2·π/64 ≈ 0.0694 rad for the equirect
/// and ≤ √2/32 ≈ 0.0442 rad for the cube (largest at a face's centre), so |Δ| ≤ |B_c|·0.114; on
/// the sphere, to the two quadratures of the SH projection (texel-centre values times exact
/// solid angles, second-order accurate: measured 5e-4 relative at most), allowed 1e-3 relative.
#[test]
fn forward_cube_and_equirect_skies_agree() {
    let (w, h) = (64u32, 48u32);
    let toml = |env: &str| {
        format!("[camera]\nposition = [1.6, 1.0, 2.6]\ntarget = [0, 0, 0]\nfov_y_deg = 60\n[[materials]]\nname = \"grey\"\nalbedo = [0.7, 0.5, 0.3]\n[[objects]]\nmesh = \"sphere\"\nmaterial = \"grey\"\n{env}")
    };
    let render = |toml: &str| {
        let scene = parse(toml);
        let mut r = Renderer::new(common::test_gpu(), scene.clone(), None, (w, h), 1).unwrap();
        let cam = r.scene.camera.clone();
        let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
        common::assert_clean(&r.gpu);
        (img, scene)
    };
    let (cube, scene) = render(&toml(&cube_sky("fwd-cube", 32, linear_sky).0));
    let (equirect, _) = render(&toml(&equirect_sky("fwd-equirect.exr", 64, 32, linear_sky)));
    let (mut sky_worst, mut sphere_worst, mut sky_pixels, mut sphere_pixels) = (0.0f32, 0.0f32, 0, 0);
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for j in 0..h {
        for i in 0..w {
            let (o, d) = scene.camera.pixel_center_ray(i, j, w, h);
            // Distance of the ray from the unit sphere's centre; away from the silhouette only.
            let miss = o.cross(d).length();
            let (a, b) = (cube.get(i, j), equirect.get(i, j));
            if miss > 1.05 {
                let want = linear_sky(d);
                for c in 0..3 {
                    let tol = Vec3::from(B[c]).length() * 0.114 + 1e-5;
                    sky_worst = sky_worst.max((a[c] - b[c]).abs() / tol);
                    // And each map is its own texel-centre value of the sky.
                    assert!(
                        (a[c] - want[c]).abs() <= Vec3::from(B[c]).length() * 0.0442 + 1e-5,
                        "cube sky ({i},{j}) ch {c}: {} vs {}",
                        a[c],
                        want[c]
                    );
                }
                lo = lo.min(a[0]);
                hi = hi.max(a[0]);
                sky_pixels += 1;
            } else if miss < 0.9 {
                for c in 0..3 {
                    sphere_worst = sphere_worst.max((a[c] - b[c]).abs() / (1e-3 * b[c].abs().max(1e-3)));
                }
                sphere_pixels += 1;
            }
        }
    }
    eprintln!("forward: {sky_pixels} sky pixels, worst |cube - equirect| {sky_worst:.3} of the bound; {sphere_pixels} sphere pixels, worst {sphere_worst:.3} of 1e-3 relative; sky red spans {lo:.3}..{hi:.3}");
    assert!(
        sky_pixels > 800 && sphere_pixels > 300,
        "{sky_pixels} sky, {sphere_pixels} sphere pixels"
    );
    assert!(sky_worst <= 1.0 && sphere_worst <= 1.0);
    // The sky seen varies by many times the tolerance: a wrong face would not pass.
    assert!(hi - lo > 5.0 * 0.616 * 0.114, "sky red spans only {lo}..{hi}");
}

fn settings(spp: u32, bounces: u32, paths: LightPaths) -> Settings {
    Settings {
        spp,
        bounces,
        paths,
        seed: 3,
        batching: Batching::Adaptive,
        ..Settings::default()
    }
}

fn reference(scene: &Scene, size: (u32, u32), s: Settings) -> penumbra::reference::ReferenceImage {
    let mut r = ReferenceRenderer::new(common::test_gpu(), scene, size).expect("reference renderer");
    let img = r.render(&s, &mut |_, _| {}).expect("render");
    common::assert_clean(&r.gpu);
    img
}

/// The furnace of a cube sky: an open Lambertian plane under a constant cube map reflects ρ·L
/// (all paths; a plane never sees itself), and the sky behind it is L. Noise only: checked in
/// units of the render's standard error.
#[test]
fn reference_plane_under_a_constant_cube_sky_reflects_rho_l() {
    let l = Vec3::new(1.5, 1.0, 0.5);
    let env = cube_sky("ref-constant", 4, |_| l.into()).0;
    let scene = parse(&format!(
        "[camera]\nposition = [0, 2, 0]\ntarget = [1.0, 1.6, -1.0]\nfov_y_deg = 100\n[[materials]]\nname = \"m\"\nalbedo = 0.6\n[[objects]]\nmesh = \"plane\"\nsize = 400\nmaterial = \"m\"\n{env}"
    ));
    let size = (24, 24);
    let img = reference(&scene, size, settings(16, 3, LightPaths::All));
    let (mut ground, mut sky) = (
        Agreement::new("plane under a constant cube sky"),
        Agreement::new("constant cube sky seen directly"),
    );
    for j in 0..size.1 {
        for i in 0..size.0 {
            let d = scene.camera.pixel_center_ray(i, j, size.0, size.1).1;
            if d.y < -0.05 {
                ground.check(&img, i, j, 0.6 * l, Vec3::ZERO);
            } else if d.y > 0.05 {
                sky.check(&img, i, j, l, Vec3::ZERO);
            }
        }
    }
    assert!(
        ground.pixels > 100 && sky.pixels > 100,
        "{} ground, {} sky pixels",
        ground.pixels,
        sky.pixels
    );
    ground.assert();
    sky.assert();
}

/// Face orientation: red only on the half of the +X face with s < 0, green only on the half of
/// the +Y face with t < 0. By the documented convention the red half lies toward +z
/// (x ≥ |y|, 0 ≤ z) and the green half toward −z, so a Lambertian plane facing +z is lit red
/// alone, with ρ/π times the red region's projected solid angle (Lambert's polygon formula: the
/// region is a spherical polygon wholly above the horizon), and one facing −z green alone. Any
/// other reading of s, t or the face order moves light across these planes.
#[test]
fn reference_half_face_skies_light_the_planes_that_face_them() {
    let sky = |d: Vec3| {
        let (face, s, t) = Environment::cube_face(d);
        [
            if face == 0 && s < 0.0 { 1.0 } else { 0.0 },
            if face == 2 && t < 0.0 { 1.0 } else { 0.0 },
            0.0,
        ]
    };
    let env = cube_sky("ref-halves", 8, sky).0;
    let red = [
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
    ];
    let green = [
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let rho = 0.8;
    for (normal, rot, cam_z) in [(Vec3::Z, 90, 3.0), (Vec3::NEG_Z, -90, -3.0)] {
        let scene = parse(&format!(
            "[camera]\nposition = [0, 0, {cam_z}]\ntarget = [0, 0, 0]\nfov_y_deg = 60\n[[materials]]\nname = \"m\"\nalbedo = {rho}\n[[objects]]\nmesh = \"plane\"\nsize = 400\nrotate_deg = [{rot}, 0, 0]\nmaterial = \"m\"\n{env}"
        ));
        let e = |poly: &[Vec3]| {
            if poly.iter().all(|v| v.dot(normal) >= 0.0) {
                polygon_irradiance(Vec3::ZERO, normal, poly)
            } else {
                0.0
            }
        };
        let want = Vec3::new(e(&red), e(&green), 0.0) * rho / std::f32::consts::PI;
        assert!(want.max_element() > 0.05 && want.min_element() == 0.0, "{want}");
        let size = (8, 8);
        let img = reference(&scene, size, settings(64, 0, LightPaths::Direct));
        let mut lit = Agreement::new("plane under a half-face cube sky");
        for j in 0..size.1 {
            for i in 0..size.0 {
                lit.check(&img, i, j, want, Vec3::ZERO);
            }
        }
        eprintln!(
            "plane facing {normal}: want {want}, pixel (3,3) {:?}",
            img.mean.get(3, 3)
        );
        lit.assert();
    }
}

/// The path tracer's lookup of a cube map seen directly is the CPU's nearest texel, for a sky
/// whose every texel differs (any mis-indexing shows).
#[test]
fn reference_cube_sky_seen_directly_is_its_texels() {
    let n = 8u32;
    let sky = |d: Vec3| {
        let (face, s, t) = Environment::cube_face(d);
        let (x, y) = (((s + 1.0) * 0.5 * n as f32) as u32, ((t + 1.0) * 0.5 * n as f32) as u32);
        [1.0 + face as f32, 0.1 * x as f32, 0.1 * y as f32]
    };
    let (env, texels) = cube_sky("ref-direct", n, sky);
    let map = EnvironmentMap::from_cube(n, texels);
    let scene = parse(&format!(
        "[camera]\nposition = [0, 0, 0]\ntarget = [0.7, 0.6, -1]\nfov_y_deg = 110\n{env}"
    ));
    let size = (32, 32);
    let img = reference(&scene, size, settings(4, 1, LightPaths::All));
    let mut direct = Agreement::new("cube sky seen directly");
    let mut faces = std::collections::BTreeSet::new();
    for j in 0..size.1 {
        for i in 0..size.0 {
            let mut texel = None;
            let want = pixel_average(i, j, 4, |x, y| {
                let d = scene.camera.ray(x, y, size.0, size.1).1;
                let (face, s, t) = Environment::cube_face(d);
                let key = (
                    face,
                    ((s + 1.0) * 0.5 * n as f32) as u32,
                    ((t + 1.0) * 0.5 * n as f32) as u32,
                );
                (*texel.get_or_insert(key) == key).then(|| map.radiance(d))
            });
            if let Some(want) = want {
                faces.insert(want.x as u32);
                direct.check(&img, i, j, want, Vec3::ZERO);
            }
        }
    }
    assert!(
        direct.pixels > 300 && faces.len() == 3,
        "{} pixels on faces {faces:?}",
        direct.pixels
    );
    direct.assert();
}

/// Height fields: the environment SH comes from the GPU projection pass, which takes a cube image
/// (six layers) as such. A smooth sky as a 32² cube and as a 64×32 equirect map must shade a
/// field of cones alike: the shading is T·c with |T|₂ ≤ ‖max(cos, 0)/π‖₂ = √(2π/3)/π, so it can
/// differ by at most that times |c_cube − c_equirect|₂, computed here on the CPU from the same
/// texels (the GPU projection equals the CPU's to ~1e-7 relative, tests/backend/sh_gpu.rs), plus rounding.
#[test]
fn heightfield_cube_and_equirect_skies_shade_alike() {
    let f = |d: Vec3| {
        [
            0.6 + 0.3 * d.x + 0.4 * d.y + 0.2 * d.y * d.y,
            0.5 - 0.2 * d.z + 0.3 * d.x * d.y,
            0.4 + 0.1 * d.y,
        ]
    };
    let bands = 4;
    let (cube_env, cube_texels) = cube_sky("hf-cube", 32, f);
    let equirect_env = equirect_sky("hf-equirect.exr", 64, 32, f);
    let rgb = |t: &[[f32; 4]]| t.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let c_cube = sh::project_cubemap(&rgb(&cube_texels), 32, bands).unwrap();
    let eq_texels: Vec<[f32; 3]> = (0..64 * 32)
        .map(|i| f(sh::equirect_texel_dir_world(i % 64, i / 64, 64, 32).normalize()))
        .collect();
    let c_eq = sh::project_equirect(&eq_texels, 64, 32, bands).unwrap();
    let dc: Vec3 = c_cube
        .iter()
        .zip(&c_eq)
        .map(|(a, b)| (*a - *b) * (*a - *b))
        .sum::<Vec3>()
        .powf(0.5);
    let t_norm = (2.0 * std::f32::consts::PI / 3.0).sqrt() / std::f32::consts::PI;
    let cones =
        "size = 8\nresolution = 64\ngenerator = \"cones\"\ncount = 5\nradius = 1.2\nring_radius = 2\nheight = 1.5";
    let method = format!("{{ name = \"heightfield_pyramid\", bands = {bands} }}");
    let shade = |env: &str| {
        let mut h = hf_common::harness(&hf_common::scene(cones, &method, env));
        let img = h.shading(0.0).unwrap();
        hf_common::clean(&h);
        img
    };
    let (cube, equirect) = (shade(&cube_env), shade(&equirect_env));
    let mut worst = 0.0f32;
    let (mut lo, mut hi) = (f32::MAX, f32::MIN);
    for (a, b) in cube.iter().zip(&equirect) {
        for c in 0..3 {
            let tol = t_norm * dc[c] + 1e-5 * b[c].abs().max(1.0);
            worst = worst.max((a[c] - b[c]).abs() / tol);
        }
        lo = lo.min(a[0]);
        hi = hi.max(a[0]);
    }
    eprintln!("height field: |c_cube - c_equirect| = {dc}, worst |cube - equirect| {worst:.3} of the bound; red shading {lo:.3}..{hi:.3}");
    assert!(worst <= 1.0, "{worst}");
    assert!(hi - lo > 0.1, "shading barely varies: {lo}..{hi}");
}

/// scenes/terrain_sky_cube.toml (the sky of tools/make_sky.py on six 32² faces) shades the
/// mountains as scenes/terrain_sky.toml (the same sky, 128×64 equirect) does, within the same SH
/// bound as above computed from the two scenes' own texels (which include each file's RGBE
/// rounding); pyramid method, 4 bands, at 64².
#[test]
fn terrain_sky_cube_scene_matches_terrain_sky() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let (cube, equirect) = (
        Scene::from_file(dir.join("terrain_sky_cube.toml")).unwrap(),
        Scene::from_file(dir.join("terrain_sky.toml")).unwrap(),
    );
    let Some(Environment::Cube { faces, scale }) = &cube.environment else {
        panic!("{:?}", cube.environment)
    };
    let Some(Environment::Image { path, .. }) = &equirect.environment else {
        panic!("{:?}", equirect.environment)
    };
    let faces = penumbra::scene::CubeFaces::load(faces, *scale).unwrap();
    let rgb = |t: &[[f32; 4]]| t.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    let c_cube = sh::project_cubemap(&rgb(&faces.texels), faces.size as usize, 4).unwrap();
    let eq = EnvironmentMap::load(path, 1.0, "terrain_sky.toml").unwrap();
    let c_eq = sh::project_equirect(&rgb(&eq.texels), eq.width as usize, eq.height as usize, 4).unwrap();
    let dc: Vec3 = c_cube
        .iter()
        .zip(&c_eq)
        .map(|(a, b)| (*a - *b) * (*a - *b))
        .sum::<Vec3>()
        .powf(0.5);
    let t_norm = (2.0 * std::f32::consts::PI / 3.0).sqrt() / std::f32::consts::PI;
    let shade = |s: &Scene| {
        let mut decl = s.methods[0].clone();
        decl.params.push(("resolution".into(), toml::Value::Integer(64), 0));
        decl.params.push(("bands".into(), toml::Value::Integer(4), 0));
        let mut h = penumbra::lighting::heightfield::standalone::Standalone::new(common::test_gpu(), s, &decl).unwrap();
        let img = h.shading(0.0).unwrap();
        hf_common::clean(&h);
        img
    };
    let (a, b) = (shade(&cube), shade(&equirect));
    let mut worst = 0.0f32;
    for (p, q) in a.iter().zip(&b) {
        for c in 0..3 {
            worst = worst.max((p[c] - q[c]).abs() / (t_norm * dc[c] + 1e-5 * q[c].abs().max(1.0)));
        }
    }
    let c00 = c_eq[0];
    eprintln!(
        "terrain sky: |c_cube - c_equirect| = {dc} (c_00 {c00}), worst |cube - equirect| {worst:.3} of the bound"
    );
    assert!(worst <= 1.0, "{worst}");
    // The bound is tight enough to mean something: a few per cent of the sky's mean.
    assert!((dc / c00).max_element() < 0.05, "{dc} vs {c00}");
}
