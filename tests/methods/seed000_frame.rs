//! The Ca3D-Engine thesis's frame on `scenes/bsp_rooms.toml` (the `seed000` combination): the radiosity
//! light-map as the ambient base, per-pixel Phong with stencil shadow volumes as the direct term.
//! The composed image is the sum of its parts, the light-map puts bounced light where the direct
//! lights leave shadow, and the entities get none of it.

use crate::support as common;

use penumbra::renderer::{FrameOutput, Renderer};
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

/// bsp_rooms.toml with a coarser light-map (a quicker bake; the composition is the same) and the
/// shadow volumes' constant ambient set to `ambient`.
fn scene(ambient: f32) -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(dir.join("bsp_rooms.toml")).unwrap();
    let text = text
        .replace("patch_size = 0.5", "patch_size = 1.0")
        .replace("lightmap = [0.035, 0.035, 0.045]", &format!("lightmap = [{ambient:?}]"));
    Scene::from_str(&text, "bsp_rooms.toml", &dir).unwrap_or_else(|e| panic!("{e}"))
}

fn render(scene: Scene, name: &str) -> HdrImage {
    let mut r =
        Renderer::new(common::test_gpu(), scene, Some(name), (64, 36), 1).unwrap_or_else(|e| panic!("{name}: {e}"));
    let cam = r.scene.camera.clone();
    let img = r.render(&cam, FrameOutput::Readback).unwrap().image.unwrap();
    common::assert_clean(&r.gpu);
    img
}

fn luminance(p: &[f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

#[test]
fn the_seed000_frame_is_the_light_map_under_the_direct_light() {
    let composed = render(scene(0.0), "seed000");
    let base = render(scene(0.0), "radiosity");
    // shadow_volumes alone with no ambient: its direct light only.
    let direct = render(scene(0.0), "shadow_volumes");
    let mut worst = 0.0f32;
    for ((c, b), d) in composed.pixels.iter().zip(&base.pixels).zip(&direct.pixels) {
        for k in 0..3 {
            worst = worst.max((c[k] - (b[k] + d[k])).abs() / (b[k] + d[k]).max(1e-3));
        }
    }
    assert!(
        worst < 1e-3,
        "composed ≠ light-map + direct light: worst relative difference {worst}"
    );
    // The light-map carries light: in the pixels the direct lights leave in shadow (their direct
    // term under 1% of the image's mean), the composed frame is lit by bounced light alone.
    let mean = |img: &HdrImage| img.pixels.iter().map(luminance).sum::<f32>() / img.pixels.len() as f32;
    let shadowed: Vec<usize> = (0..direct.pixels.len())
        .filter(|&i| luminance(&direct.pixels[i]) < 0.01 * mean(&direct))
        .collect();
    assert!(shadowed.len() > 50, "the view has shadowed pixels ({})", shadowed.len());
    let lit = shadowed
        .iter()
        .filter(|&&i| luminance(&composed.pixels[i]) > 0.02 * mean(&composed))
        .count();
    assert!(
        lit as f64 > 0.8 * shadowed.len() as f64,
        "bounced light reaches {lit} of {} shadowed pixels",
        shadowed.len()
    );
    // The constant ambient it replaces is gone: the composed frame does not depend on it.
    let with_ambient = render(scene(0.5), "seed000");
    assert_eq!(with_ambient.pixels, composed.pixels);
}

/// `seed000_faithful`: the faithful CaLight light-map (8-bit display values, reflectivity 0.3)
/// as the base under the same direct light: the frame is the sum of its parts, and the map
/// differs from the corrected one (tone-reproduced, not radiometric).
#[test]
fn the_faithful_seed000_frame_is_calights_light_map_under_the_direct_light() {
    let composed = render(scene(0.0), "seed000_faithful");
    let base = render(scene(0.0), "radiosity_faithful");
    let direct = render(scene(0.0), "shadow_volumes");
    let mut worst = 0.0f32;
    for ((c, b), d) in composed.pixels.iter().zip(&base.pixels).zip(&direct.pixels) {
        for k in 0..3 {
            worst = worst.max((c[k] - (b[k] + d[k])).abs() / (b[k] + d[k]).max(1e-3));
        }
    }
    assert!(
        worst < 1e-3,
        "composed ≠ light-map + direct light: worst relative difference {worst}"
    );
    let mean = |img: &HdrImage| img.pixels.iter().map(luminance).sum::<f32>() / img.pixels.len() as f32;
    let corrected = render(scene(0.0), "radiosity");
    eprintln!(
        "mean luminance: faithful light-map {:.4}, corrected light-map {:.4}, direct {:.4}",
        mean(&base),
        mean(&corrected),
        mean(&direct)
    );
    assert!(
        mean(&base) > 0.01 * mean(&direct),
        "the faithful light-map carries light"
    );
    assert_ne!(base.pixels, corrected.pixels);
}

/// CaLight's point lights (digest §1.2 step D): in faithful mode every patch in the light's PVS
/// facing it receives I·cos θ/d² with no shadow ray; a patch outside the PVS receives nothing.
/// The corrected mode's shadow rays light fewer patches (the level's pillars and door frames).
#[test]
fn faithful_point_lights_reach_every_patch_in_their_pvs() {
    use glam::DVec3;
    use penumbra::lighting::lightmap::{patches::Patches, solve::Mode, solve::Occluders};
    use penumbra::lighting::radiosity::bake;
    use penumbra::scene::{world_mesh, Light, MeshSource};
    let mut scene = scene(0.0);
    // One light: the warm one of room 0.
    scene.lights.retain(|l| l.name() == "room 0 warm");
    let Light::Point {
        position, intensity, ..
    } = scene.lights[0]
    else {
        panic!("a point light")
    };
    let geometry = penumbra::lighting::lightmap::geometry::scene_geometry(&scene, "radiosity").unwrap();
    let occluders = Occluders::new(&geometry.triangles);
    let (level, translate) = scene
        .objects
        .iter()
        .find_map(|o| match &o.mesh {
            MeshSource::World { level, .. } => Some((level.clone(), o.transform.w_axis.truncate())),
            _ => None,
        })
        .unwrap();
    let world = world_mesh::compiled(&level).unwrap();
    let leaf = |x: DVec3| world.leaf_of(world_mesh::scene_to_world(x.as_vec3() - translate));
    let light_leaf = leaf(position.as_dvec3());
    let lit = |mode| {
        let mut p = Patches::build(&geometry.triangles, 1.0);
        let direct = bake::add_direct_light_in(&mut p, &occluders, &scene, mode, None).unwrap();
        (p, direct)
    };
    let (p, faithful) = lit(Mode::Faithful);
    let (mut in_pvs, mut outside) = (0, 0);
    for (q, d) in p.patches.iter().zip(&faithful).filter(|(q, _)| q.inside()) {
        let x = q.centre + q.normal * 1e-4 * p.size;
        let to = position.as_dvec3() - x;
        let cos = q.normal.dot(to.normalize());
        let want = if world.is_visible(leaf(x), light_leaf) && cos > 0.0 {
            q.albedo * intensity.as_dvec3() * cos / to.length_squared()
        } else {
            DVec3::ZERO
        };
        assert!(
            (*d - want).abs().max_element() <= 1e-9 * want.max_element().max(1.0),
            "patch at {}: {d} against {want}",
            q.centre
        );
        if want == DVec3::ZERO {
            outside += 1;
        } else {
            in_pvs += 1;
        }
    }
    let (_, corrected) = lit(Mode::Corrected);
    let count = |v: &[DVec3]| v.iter().filter(|d| d.max_element() > 0.0).count();
    eprintln!(
        "faithful lights {in_pvs} patches ({outside} outside the PVS or facing away); corrected's shadow rays light {}",
        count(&corrected)
    );
    assert!(in_pvs > 50 && outside > 50, "{in_pvs} / {outside}");
    assert!(
        count(&corrected) < in_pvs,
        "shadow rays light fewer patches than the PVS: {} vs {in_pvs}",
        count(&corrected)
    );
}

/// The Ca3D-Engine thesis's ambient is light-map × N_z (the normal map's tangent-space z): with `ambient_nz`
/// the light-map base is darker where the level's bricks and tiles are normal-mapped, never
/// brighter, and the light-map itself is the same bake.
#[test]
fn the_ambient_term_is_scaled_by_the_normal_maps_n_z() {
    let with = render(scene(0.0), "radiosity");
    let mut flat = scene(0.0);
    for m in &mut flat.methods {
        m.params.retain(|(n, _, _)| n != "ambient_nz");
    }
    let without = render(flat, "radiosity");
    let (mut darker, mut brighter) = (0, 0);
    for (a, b) in with.pixels.iter().zip(&without.pixels) {
        let (la, lb) = (luminance(a), luminance(b));
        darker += usize::from(la < 0.98 * lb);
        brighter += usize::from(la > lb * 1.0001 + 1e-6);
    }
    eprintln!(
        "{darker} of {} pixels darker with N_z, {brighter} brighter",
        with.pixels.len()
    );
    assert_eq!(brighter, 0);
    assert!(
        darker > with.pixels.len() / 10,
        "N_z darkens the normal-mapped surfaces: {darker} pixels"
    );
}
