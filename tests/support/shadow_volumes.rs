//! Helpers of the stencil-shadow-volume tests: rendering a scene text with the method, and
//! comparing a rendered lit/shadowed mask with a CPU ray-cast one.
#![allow(dead_code)]

use glam::Vec3;
use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::{Camera, Scene};
use penumbra::util::image_io::HdrImage;

use crate::support as common;

/// Parses `toml` (relative paths against `base`) and renders one frame with its first method.
pub fn render_in(toml: &str, base: &std::path::Path, size: (u32, u32)) -> (HdrImage, Scene) {
    let scene = Scene::from_str(toml, "<test>", base).unwrap_or_else(|e| panic!("test scene: {e}"));
    let img = render_scene(scene.clone(), size);
    (img, scene)
}

pub fn render(toml: &str, size: (u32, u32)) -> (HdrImage, Scene) {
    render_in(toml, std::path::Path::new("."), size)
}

pub fn render_scene(scene: Scene, size: (u32, u32)) -> HdrImage {
    render_with_notes(scene, size).0
}

/// One frame, and the method's notes on it (`LightingMethod::frame_notes`).
pub fn render_with_notes(scene: Scene, size: (u32, u32)) -> (HdrImage, Vec<String>) {
    let mut r = Renderer::new(common::test_gpu(), scene, None, size, 1).unwrap_or_else(|e| panic!("renderer: {e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    let notes = r.method_frame_notes().unwrap();
    common::assert_clean(&r.gpu);
    (img, notes)
}

/// `[[methods]]` text for the method with these extra `key = value` lines.
pub fn method(params: &[&str]) -> String {
    format!("[[methods]]\nname = \"shadow_volumes\"\n{}\n", params.join("\n"))
}

/// How a rendered lit mask compares with the CPU's.
#[derive(Debug, Default)]
pub struct MaskComparison {
    /// Pixels compared (the CPU gave a verdict at the centre).
    pub pixels: usize,
    pub gpu_shadow: usize,
    pub cpu_shadow: usize,
    /// Intersection over union of the shadowed sets.
    pub iou: f64,
    pub mismatches: usize,
    /// Mismatches where the CPU verdict is the same at the pixel's centre and all four corners:
    /// the rendering is wrong there, not just on the other side of an edge.
    pub interior_mismatches: usize,
}

/// Compares `gpu_lit(x, y)` with `cpu_lit(px, py)` (continuous pixel coordinates; `None` where
/// the pixel is not judged) over a `w × h` image.
pub fn compare_masks(
    w: u32,
    h: u32,
    gpu_lit: impl Fn(u32, u32) -> bool,
    cpu_lit: impl Fn(f32, f32) -> Option<bool>,
) -> MaskComparison {
    let mut c = MaskComparison::default();
    let (mut inter, mut union) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            let Some(cpu) = cpu_lit(x as f32 + 0.5, y as f32 + 0.5) else {
                continue;
            };
            let gpu = gpu_lit(x, y);
            c.pixels += 1;
            c.gpu_shadow += usize::from(!gpu);
            c.cpu_shadow += usize::from(!cpu);
            inter += usize::from(!gpu && !cpu);
            union += usize::from(!gpu || !cpu);
            if gpu != cpu {
                c.mismatches += 1;
                let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
                let uniform = corners
                    .iter()
                    .all(|&(dx, dy)| cpu_lit(x as f32 + dx, y as f32 + dy).is_none_or(|v| v == cpu));
                c.interior_mismatches += usize::from(uniform);
            }
        }
    }
    c.iou = if union == 0 { 1.0 } else { inter as f64 / union as f64 };
    c
}

/// Where the ray through continuous pixel `(px, py)` meets the plane `y = height`, if ahead.
pub fn hit_plane_y(cam: &Camera, px: f32, py: f32, size: (u32, u32), height: f32) -> Option<(Vec3, f32)> {
    let (o, d) = cam.ray(px, py, size.0, size.1);
    let t = (height - o.y) / d.y;
    (t > 0.0 && t.is_finite()).then_some((o + d * t, t))
}

/// Lit: any colour channel above `eps`.
pub fn lit(img: &HdrImage, x: u32, y: u32, eps: f32) -> bool {
    img.get(x, y)[..3].iter().any(|&c| c > eps)
}
