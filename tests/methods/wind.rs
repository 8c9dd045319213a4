//! Scene-level motion on the GPU, shared by every method: Dickson et al. 2011's wind (digest §6.1) moves the
//! scene's vertex buffer before any method draws, as the formula says at known points and as the
//! CPU twin the reference traces; the LPV's RSM and its surfaces see the same moved leaf; frames
//! are deterministic; a turning sun is seen by `forward` and the LPV at the closed-form angle; and
//! methods that keep the rest pose say so.

use crate::support as common;

use glam::Vec3;
use penumbra::backend::{vk, BufferDesc, MemoryKind};
use penumbra::environment::EnvironmentMap;
use penumbra::gpu_scene::{SceneGpu, Vertex};
use penumbra::graph::{Access, RenderGraph, ResourceStates};
use penumbra::lighting::lpv::volume::Placement;
use penumbra::lighting::{registry, FrameClock};
use penumbra::renderer::wind::WindPass;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::shaders::ShaderLibrary;

fn scene(text: &str) -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    Scene::from_str(text, "wind test", &dir).unwrap_or_else(|e| panic!("{e}"))
}

/// The document's lift in f64, written out here: amplitude·unit·w·cos(rate·t + (x+z)/20 − y²/70
/// + z²/300) with x, y, z in units.
fn lift(p: Vec3, w: f64, t: f64, amplitude: f64, rate: f64, unit: f64) -> f64 {
    let [x, y, z] = p.to_array().map(|c| c as f64 / unit);
    amplitude * unit * w * (rate * t + (x + z) / 20.0 - y * y / 70.0 + z * z / 300.0).cos()
}

/// The scene's vertex buffer after the wind pass at renderer frame `frame`.
fn wind_vertices(scene: &Scene, frame: u64) -> (Vec<Vertex>, SceneGpu) {
    let mut gpu = common::test_gpu();
    let mut states = ResourceStates::default();
    let environment = EnvironmentMap::of_scene(scene).unwrap();
    let scene_gpu = SceneGpu::upload(&mut gpu, &mut states, scene, &environment).unwrap();
    let wind = WindPass::new(&mut gpu, &mut states, &ShaderLibrary::Embedded, scene, &scene_gpu)
        .unwrap()
        .expect("a windy object");
    let size = gpu.buffer_desc(scene_gpu.vertices).unwrap().size;
    let rb = gpu
        .create_buffer(&BufferDesc {
            name: "vertices readback".into(),
            size,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuToCpu,
        })
        .unwrap();
    let f = gpu.create_frame().unwrap();
    {
        let mut graph = RenderGraph::new();
        wind.add(&mut graph, &scene_gpu, FrameClock::at(frame).time_s);
        let vb = scene_gpu.vertices;
        graph
            .pass("readback")
            .buffer(vb, Access::TransferRead, None)
            .buffer(rb, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.copy_buffer(vb, rb, size));
        graph.pass("host").buffer(rb, Access::HostRead, None).record(|_| Ok(()));
        graph.output_buffer(rb);
        graph.run_and_wait(&gpu, f, &mut states, "wind test").unwrap();
    }
    let bytes = gpu.read_buffer(rb).unwrap();
    common::assert_clean(&gpu);
    (
        bytes
            .chunks_exact(std::mem::size_of::<Vertex>())
            .map(bytemuck::pod_read_unaligned)
            .collect(),
        scene_gpu,
    )
}

/// The GPU's wind on a bush of the leaf texture (alpha = weight): stems (alpha 0) stay put,
/// tips (alpha 1) rise by the formula's closed form, and every vertex equals the CPU twin that
/// the reference path tracer traces.
#[test]
fn wind_moves_vertices_by_the_formula_as_the_reference_does() {
    let s = scene(
        "[camera]\nposition = [2.4, 1.7, 2.7]\ntarget = [0, 1, 0]\n\
         [[materials]]\nname = \"leaf\"\nalbedo = [0.45, 0.6, 0.25]\nalbedo_map = \"textures/leaf_albedo.png\"\n\
         [[objects]]\nmesh = \"plane\"\nsize = 4\n\
         [[objects]]\nname = \"bush\"\nmesh = \"bush\"\nleaves = 40\nmaterial = \"leaf\"\nwind = { unit = 0.1, rate = 3 }\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n",
    );
    let frame = 37;
    let t = FrameClock::at(frame).time_s;
    let (got, scene_gpu) = wind_vertices(&s, frame);
    let (item, rest) = (&scene_gpu.draws[1], &scene_gpu.meshes[1]);
    let first = item.vertex_offset as usize;
    let (mut stems, mut tips) = (0, 0);
    for (i, p) in rest.positions.iter().enumerate() {
        let v = &got[first + i];
        let uv = rest.uvs[i];
        if uv.y == 1.0 {
            // The stem's row of the map has alpha 0.
            assert_eq!(Vec3::from(v.position), *p, "stem vertex {i} moved");
            stems += 1;
        } else if uv.y == 0.0 {
            let want = lift(*p, 1.0, t as f64, 0.3, 3.0, 0.1);
            let dy = v.position[1] as f64 - p.y as f64;
            assert!(
                (dy - want).abs() < 2e-6 && v.position[0] == p.x && v.position[2] == p.z,
                "tip vertex {i}: lift {dy} vs {want}"
            );
            tips += 1;
        }
    }
    assert!(stems >= 40 && tips >= 40, "{stems} stems, {tips} tips");
    // The ground has no wind: untouched.
    let ground = &scene_gpu.meshes[0];
    assert!(ground
        .positions
        .iter()
        .enumerate()
        .all(|(i, p)| Vec3::from(got[i].position) == *p));
    // The reference's geometry: the CPU twin at the same time.
    let twin = s.wind_mesh(&s.objects[1], rest.clone(), t).unwrap();
    let mut worst = (0.0f32, 0.0f32);
    for (i, (p, n)) in twin.positions.iter().zip(&twin.normals).enumerate() {
        let v = &got[first + i];
        worst.0 = worst.0.max(Vec3::from(v.position).distance(*p));
        worst.1 = worst.1.max(Vec3::from(v.normal).distance(*n));
    }
    assert!(
        worst.0 < 1e-6 && worst.1 < 1e-5,
        "GPU vs CPU twin: position {:.2e} m, normal {:.2e}",
        worst.0,
        worst.1
    );
    assert!(
        twin.positions
            .iter()
            .zip(&rest.positions)
            .any(|(a, b)| (a.y - b.y).abs() > 1e-3),
        "the wind moved nothing"
    );
}

/// A 1 m² leaf at 0.37 m whose wind lifts it uniformly by 0.1·cos(90 t) m (a huge `unit` makes
/// the phase's lattice terms vanish), under an overhead sun, in a 2 m volume centred at 0.5 m.
fn lifted_leaf(view: &str) -> Scene {
    scene(&format!(
        "methods = [{{ name = \"lpv\", grid = 8, rsm = 64, iterations = 0, snap = false, centre = [0, 0.5, 0], size = 2, view = \"{view}\" }}]\n\
         [camera]\nposition = [0, 2, 3]\ntarget = [0, 0.37, 0]\n\
         [[materials]]\nname = \"leaf\"\nalbedo = 0.5\ntransmittance = 0.3\n\
         [[objects]]\nmesh = \"quad\"\nmaterial = \"leaf\"\ncorner = [-0.5, 0.37, 0.5]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, -1]\nwind = {{ amplitude = 1e-5, unit = 1e4, rate = 90 }}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 2\n"
    ))
}

/// The centre pixel of frames 0 … `frames` − 1.
fn centres(s: Scene, method: &str, size: u32, frames: u64) -> Vec<[f32; 4]> {
    let mut r = Renderer::new(common::test_gpu(), s, Some(method), (size, size), 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let out = (0..frames)
        .map(|_| {
            let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
            img.pixels[(img.height / 2 * img.width + img.width / 2) as usize]
        })
        .collect();
    common::assert_clean(&r.gpu);
    out
}

/// The LPV's RSM (drawn from the sun) and its surface look-up (drawn from the camera) both see
/// the leaf at the height the wind gives it at frames 0 and 1, 0.1·cos(90·t) m above its rest
/// pose: the same moved geometry in both.
#[test]
fn the_rsm_and_the_surfaces_see_the_same_moved_leaf() {
    let volume = Placement::fit(Vec3::new(-1.0, -0.5, -1.0), Vec3::new(1.0, 1.5, 1.0), 8);
    let side = volume.cell * 8.0;
    let height = |frame: u64| 0.37 + lift(Vec3::ZERO, 1.0, FrameClock::at(frame).time_s as f64, 1e-5, 90.0, 1e4);
    for view in ["rsm_position", "position"] {
        let got = centres(lifted_leaf(view), "lpv", 33, 2);
        for (frame, px) in got.iter().enumerate() {
            let y = volume.origin.y + px[1] * side;
            let want = height(frame as u64);
            assert!(
                (y as f64 - want).abs() < 2e-4,
                "{view}, frame {frame}: the leaf at {y} m, the wind puts it at {want} m"
            );
        }
        assert!(
            (got[0][1] - got[1][1]).abs() * side > 0.09,
            "{view}: the leaf did not move"
        );
    }
}

/// Two renderers give bit-identical frames 0 … 3 of a windy leaf's indirect light, and the
/// light changes from frame to frame.
#[test]
fn windy_frames_are_deterministic() {
    let s = lifted_leaf("indirect").to_owned();
    let run = || {
        let mut r =
            Renderer::new(common::test_gpu(), s.clone(), Some("lpv"), (16, 16), 1).unwrap_or_else(|e| panic!("{e}"));
        let cam = r.scene.camera.clone();
        let frames: Vec<Vec<[f32; 4]>> = (0..4)
            .map(|_| r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap().pixels)
            .collect();
        common::assert_clean(&r.gpu);
        frames
    };
    let (a, b) = (run(), run());
    assert!(a == b, "two runs differ");
    assert!(a[0] != a[1] && a[1] != a[2], "the wind changed nothing");
}

/// `[light_motion]` turns the sun 30° about z by frame 1 (1800°/s at 60 frames a second), for
/// every method: `forward`'s and `shadow_volumes`' lit plane falls to cos 30° of frame 0's
/// radiance, and the LPV's RSM,
/// looking along the turned sun through the volume's centre h above the plane, meets the plane
/// h · tan 30° off centre (0.42 m).
#[test]
fn a_turning_sun_is_seen_by_every_method_at_the_closed_form_angle() {
    let text = |method: &str| {
        format!(
            "methods = [\"forward\", {{ name = \"shadow_volumes\", mode = \"physical\" }}, {{ name = \"lpv\", grid = 8, rsm = 256, iterations = 0, snap = false, centre = [0, 0.5, 0], size = 2, view = \"rsm_position\" }}]\n{method}\n\
             [camera]\nposition = [0, 3, 0.01]\ntarget = [0, -0.4, 0]\n\
             [[materials]]\nname = \"grey\"\nalbedo = 0.5\n\
             [[objects]]\nmesh = \"quad\"\nmaterial = \"grey\"\ncorner = [-2, -0.4, 2]\nedge_u = [4, 0, 0]\nedge_v = [0, 0, -4]\n\
             [[lights]]\ntype = \"directional\"\nname = \"sun\"\ndirection = [0, -1, 0]\nirradiance = 2\n\
             [light_motion]\nlight = \"sun\"\naxis = [0, 0, 1]\ndeg_per_s = 1800\n"
        )
    };
    let forward = centres(scene(&text("")), "forward", 9, 2);
    let ratio = forward[1][0] / forward[0][0];
    assert!(
        (forward[0][0] - 0.5 * 2.0 / std::f32::consts::PI).abs() < 1e-4,
        "frame 0: {:?}",
        forward[0]
    );
    assert!(
        (ratio - 30f32.to_radians().cos()).abs() < 1e-4,
        "forward: frame 1 / frame 0 = {ratio}"
    );
    // Shadow volumes light the plane with the frame's sun, and say nothing of keeping a pose.
    // The centre pixel lies on the quad's diagonal, an inner edge with no side faces.
    let sv = centres(scene(&text("")), "shadow_volumes", 9, 2);
    assert!(
        (sv[1][0] / sv[0][0] - ratio).abs() < 1e-4 && (sv[0][0] - forward[0][0]).abs() < 1e-4,
        "shadow_volumes: frames {sv:?} against forward's {forward:?}"
    );
    let turning = scene(&text(""));
    let config = registry::configuration(&turning, Some("shadow_volumes")).unwrap();
    assert!(registry::motion_notes(&config, &turning).is_empty());
    let lpv = centres(scene(&text("")), "lpv", 33, 2);
    let volume = Placement::fit(Vec3::new(-1.0, -0.5, -1.0), Vec3::new(1.0, 1.5, 1.0), 8);
    let side = volume.cell * 8.0;
    let at = |px: [f32; 4]| volume.origin + Vec3::new(px[0], px[1], px[2]) * side;
    let (p0, p1) = (at(lpv[0]), at(lpv[1]));
    let centre = volume.centre();
    let want = (centre.y + 0.4) * 30f32.to_radians().tan();
    assert!(want > 0.4, "{want}");
    assert!(
        (p0.x - centre.x).abs() < 2e-3 && (p0.y + 0.4).abs() < 1e-3,
        "frame 0: the RSM's centre meets the plane at {p0}"
    );
    assert!(
        (p1.x - centre.x - want).abs() < 2e-3 && (p1.y + 0.4).abs() < 1e-3,
        "frame 1: {p1}, {want} m off centre expected"
    );
}

/// Methods that bake say they keep the rest pose of a moving scene; those that follow it say
/// nothing; a still scene gets no note.
#[test]
fn methods_that_keep_the_rest_pose_say_so() {
    let text = "methods = [\"forward\", \"lpv\", \"radiosity\", \"prt\"]\n[camera]\nposition = [0, 2, 3]\ntarget = [0, 0, 0]\n\
                [[objects]]\nname = \"leaf\"\nmesh = \"quad\"\ncorner = [-0.5, 0.37, 0.5]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, -1]\nWIND\n\
                [[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = 1\n";
    let windy = scene(&text.replace("WIND", "wind = { unit = 0.1 }"));
    let still = scene(&text.replace("WIND", ""));
    for (method, noted) in [("forward", false), ("lpv", false), ("radiosity", true), ("prt", true)] {
        let notes = registry::motion_notes(&registry::configuration(&windy, Some(method)).unwrap(), &windy);
        assert_eq!(notes.len(), noted as usize, "{method}: {notes:?}");
        if noted {
            assert!(
                notes[0].contains(method)
                    && notes[0].contains("rest pose")
                    && notes[0].contains("wind (objects[0] \"leaf\")"),
                "{}",
                notes[0]
            );
        }
        assert!(registry::motion_notes(&registry::configuration(&still, Some(method)).unwrap(), &still).is_empty());
    }
}

/// The path tracer's scene at frame 1 (`penumbra reference --frame 1`) holds the leaf where the
/// wind puts it and the sun where `[light_motion]` turned it, as the renderer's frame 1 does.
#[test]
fn the_reference_traces_the_frames_geometry_and_sun() {
    use penumbra::reference::TracedScene;
    let s = scene(
        "[camera]\nposition = [0, 2, 3]\ntarget = [0, 0.37, 0]\n\
         [[objects]]\nmesh = \"quad\"\ncorner = [-0.5, 0.37, 0.5]\nedge_u = [1, 0, 0]\nedge_v = [0, 0, -1]\nwind = { amplitude = 1e-5, unit = 1e4, rate = 90 }\n\
         [[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 2\n\
         [light_motion]\naxis = [0, 0, 1]\ndeg_per_s = 1800\n",
    );
    for frame in [0u64, 1] {
        let t = FrameClock::at(frame).time_s;
        let traced = TracedScene::build_at(&s, t).unwrap();
        let want = 0.37 + lift(Vec3::ZERO, 1.0, t as f64, 1e-5, 90.0, 1e4);
        assert!(!traced.corners.is_empty());
        for c in traced.corners.iter().flatten() {
            assert!(
                (c.y as f64 - want).abs() < 1e-5,
                "frame {frame}: a corner at {} m, the wind puts the leaf at {want} m",
                c.y
            );
        }
        let turned = (30.0 * frame as f32).to_radians();
        let d = Vec3::from_slice(&traced.lights[0].direction[..3]);
        assert!(
            d.distance(Vec3::new(turned.sin(), -turned.cos(), 0.0)) < 1e-5,
            "frame {frame}: sun {d}"
        );
    }
}
