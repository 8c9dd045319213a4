//! Translucent materials drawn by `forward`: each blended over what lies behind it, back to front,
//! as the reference's stochastic transparency gives a camera ray. Judged by composition: the frame
//! with two overlapping translucent panes equals, pixel by pixel, the frames of each pane drawn
//! opaque and of the wall alone, mixed by their opacities in depth order.

use crate::support as common;

use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

const SIZE: (u32, u32) = (48, 36);

/// A wall facing the camera, a far pane (0.5 m in front of it) and a near pane (1 m in front),
/// overlapping in the middle of the view; a point light in front of them all.
fn scene(far: Option<f32>, near: Option<f32>) -> Scene {
    let mut text = String::from(
        "methods = [\"forward\"]\n\
         [camera]\nposition = [0.2, 1.0, 4.0]\ntarget = [0.0, 1.0, 0.0]\nfov_y_deg = 50\n\
         [[materials]]\nname = \"wall\"\nalbedo = [0.6, 0.5, 0.4]\n\
         [[objects]]\nname = \"wall\"\nmesh = \"quad\"\ncorner = [-2, 0, 0]\nedge_u = [4, 0, 0]\nedge_v = [0, 2, 0]\nmaterial = \"wall\"\n\
         [[lights]]\ntype = \"point\"\nposition = [0.5, 2.5, 3.0]\nintensity = 5\n",
    );
    for (name, opacity, z, corner, albedo) in [
        ("far", far, 0.5, "[-1.0, 0.3", "[0.8, 0.2, 0.2]"),
        ("near", near, 1.0, "[-0.5, 0.6", "[0.2, 0.7, 0.3]"),
    ] {
        if let Some(a) = opacity {
            text += &format!(
                "[[materials]]\nname = \"{name}\"\nalbedo = {albedo}\nopacity = {a}\n\
                 [[objects]]\nname = \"{name}\"\nmesh = \"quad\"\ncorner = {corner}, {z}]\nedge_u = [1.5, 0, 0]\nedge_v = [0, 1.1, 0]\nmaterial = \"{name}\"\n"
            );
        }
    }
    Scene::from_str(&text, "panes.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

fn render(scene: Scene) -> HdrImage {
    let mut r = Renderer::new(common::test_gpu(), scene, None, SIZE, 1).unwrap_or_else(|e| panic!("{e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

#[test]
fn translucent_panes_blend_back_to_front_over_what_lies_behind() {
    let (a_far, a_near) = (0.6f32, 0.3f32);
    let wall = render(scene(None, None));
    let far = render(scene(Some(1.0), None));
    let near = render(scene(None, Some(1.0)));
    let both = render(scene(Some(a_far), Some(a_near)));
    let (mut on_both, mut on_one) = (0, 0);
    for (i, ((w, f), (n, got))) in wall
        .pixels
        .iter()
        .zip(&far.pixels)
        .zip(near.pixels.iter().zip(&both.pixels))
        .enumerate()
    {
        let differs = |x: &[f32; 4]| (0..3).any(|c| (x[c] - w[c]).abs() > 1e-3 * w[c].abs().max(1e-2));
        let (covered_far, covered_near) = (differs(f), differs(n));
        for c in 0..3 {
            let behind = if covered_far {
                a_far * f[c] + (1.0 - a_far) * w[c]
            } else {
                w[c]
            };
            let want = if covered_near {
                a_near * n[c] + (1.0 - a_near) * behind
            } else {
                behind
            };
            assert!(
                (got[c] - want).abs() <= 2e-3 * want.abs() + 1e-5,
                "pixel {i} channel {c}: {} against {want} (far {covered_far}, near {covered_near})",
                got[c]
            );
        }
        match (covered_far, covered_near) {
            (true, true) => on_both += 1,
            (true, false) | (false, true) => on_one += 1,
            _ => {}
        }
    }
    assert!(
        on_both > 50 && on_one > 50,
        "{on_both} pixels behind both panes, {on_one} behind one"
    );
}
