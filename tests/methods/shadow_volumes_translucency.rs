//! The seed's translucency compromise in the stencil shadow-volume method (digest §1.4, §4.4,
//! §5.6 "Translucency behaviour"), per pixel against the CPU: a translucent pane is neither lit
//! in the opaque path nor a shadow caster, so the floor behind it is lit exactly as without it;
//! the pane gets its own per-light light (scaled by its opacity) where no opaque caster's volume
//! covers it; of two stacked panes only the nearer receives per-light light. And the consumers
//! that draw opaque surfaces only refuse translucent materials with one line (the reference path
//! tracer draws them by stochastic transparency: tests/reference/reference.rs).

use crate::support as common;
use crate::support::shadow_volumes as sv_common;

use glam::Vec3;
use penumbra::lighting::brdf::Surface;
use penumbra::renderer::Renderer;
use penumbra::scene::{Camera, Scene};
use penumbra::util::image_io::HdrImage;
use sv_common::{method, render, render_scene};

const SIZE: (u32, u32) = (96, 96);
const LIGHT: Vec3 = Vec3::new(0.2, 3.0, 0.1);
const INTENSITY: f32 = 6.0;
const FLOOR: Surface = Surface {
    albedo: Vec3::splat(0.7),
    specular: Vec3::ZERO,
    exponent: 32.0,
    emission: Vec3::splat(0.01),
};
/// The opaque caster above pane A: a square at y = 1.8.
const CASTER: (f32, [f32; 4]) = (1.8, [-0.3, 0.1, -0.2, 0.2]);

/// A horizontal translucent pane facing +y: height, [x0, x1, z0, z1], material.
#[derive(Clone, Copy)]
struct Pane {
    y: f32,
    rect: [f32; 4],
    surface: Surface,
    opacity: f32,
}

const PANE_A: Pane = Pane {
    y: 1.0,
    rect: [-1.0, 1.0, -1.0, 1.0],
    surface: Surface {
        albedo: Vec3::new(0.3, 0.6, 0.9),
        specular: Vec3::ZERO,
        exponent: 32.0,
        emission: Vec3::new(0.05, 0.08, 0.02),
    },
    opacity: 0.4,
};
const PANE_B: Pane = Pane {
    y: 0.5,
    rect: [-1.2, 1.4, -1.2, 1.4],
    surface: Surface {
        albedo: Vec3::new(0.9, 0.4, 0.2),
        specular: Vec3::ZERO,
        exponent: 32.0,
        emission: Vec3::new(0.02, 0.03, 0.09),
    },
    opacity: 0.6,
};

fn v3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

fn material(name: &str, s: &Surface, opacity: Option<f32>) -> String {
    let o = opacity.map(|a| format!("opacity = {a}\n")).unwrap_or_default();
    format!(
        "[[materials]]\nname = \"{name}\"\nalbedo = {}\nemission = {}\n{o}\n",
        v3(s.albedo),
        v3(s.emission)
    )
}

fn quad(name: &str, y: f32, [x0, x1, z0, z1]: [f32; 4], material: &str) -> String {
    // edge_u × edge_v = z × x = +y: the quad faces up, towards the light and the eye.
    format!("[[objects]]\nname = \"{name}\"\nmesh = \"quad\"\ncorner = [{x0}, {y}, {z0}]\nedge_u = [0, 0, {}]\nedge_v = [{}, 0, 0]\nmaterial = \"{material}\"\n\n", z1 - z0, x1 - x0)
}

/// The scene: floor, the panes given (material opacities overridable), optionally the caster.
fn scene_text(panes: &[(Pane, Option<f32>)], caster: bool) -> String {
    let mut s = method(&["mode = \"physical\"", "animate = false"]);
    s += "[camera]\nposition = [2.0, 4.5, 3.0]\ntarget = [0, 0.3, 0]\nfov_y_deg = 50\n\n";
    s += &material("floor", &FLOOR, None);
    s += "[[objects]]\nname = \"floor\"\nmesh = \"plane\"\nsize = [8, 8]\nmaterial = \"floor\"\n\n";
    for (i, (p, opacity)) in panes.iter().enumerate() {
        s += &material(&format!("glass{i}"), &p.surface, Some(opacity.unwrap_or(p.opacity)));
        s += &quad(&format!("pane{i}"), p.y, p.rect, &format!("glass{i}"));
    }
    if caster {
        s += &quad("caster", CASTER.0, CASTER.1, "floor");
    }
    s += &format!(
        "[[lights]]\ntype = \"point\"\nposition = {}\nintensity = {INTENSITY}\n",
        v3(LIGHT)
    );
    s
}

/// Where the ray meets the horizontal rectangle at height `y`, if ahead and inside.
fn hit_rect(o: Vec3, d: Vec3, y: f32, [x0, x1, z0, z1]: [f32; 4]) -> Option<Vec3> {
    let t = (y - o.y) / d.y;
    let p = o + d * t;
    (t > 0.0 && (x0..=x1).contains(&p.x) && (z0..=z1).contains(&p.z)).then_some(p)
}

/// Whether the opaque caster (when present) blocks `p` from the light; translucent panes never do.
fn shadowed(p: Vec3, caster: bool) -> bool {
    caster && p.y < CASTER.0 && hit_rect(p, (LIGHT - p).normalize(), CASTER.0, CASTER.1).is_some()
}

/// What the ray through a continuous pixel position meets, and the CPU's colour there:
/// `None` for rays that hit the caster or miss the floor. `lit_through` makes every pane
/// receive light (the physically minded alternative), for the stacked-pane counterfactual.
struct Shade {
    /// (pane index, in shadow) per pane hit, nearest first; then the floor's shadow state.
    class: Vec<(usize, bool)>,
    colour: Vec3,
    /// The colour if every pane layer received its light.
    all_lit: Vec3,
}

fn cpu_shade(cam: &Camera, panes: &[Pane], caster: bool, px: f32, py: f32) -> Option<Shade> {
    let (o, d) = cam.ray(px, py, SIZE.0, SIZE.1);
    if caster && hit_rect(o, d, CASTER.0, CASTER.1).is_some() {
        return None;
    }
    let floor = hit_rect(o, d, 0.0, [-4.0, 4.0, -4.0, 4.0])?;
    // Every surface here is Lambertian (no specular), so a point light's exit radiance is the
    // closed form ρ/π · I cos θ / d², written out rather than taken from the CPU module.
    let light = |p: Vec3, s: &Surface, c: bool| {
        assert_eq!(s.specular, Vec3::ZERO);
        let to = LIGHT - p;
        if shadowed(p, c) {
            Vec3::ZERO
        } else {
            s.albedo / std::f32::consts::PI * INTENSITY * (to.normalize().y.max(0.0) / to.length_squared())
        }
    };
    let floor_colour = FLOOR.emission + light(floor, &FLOOR, caster);
    let mut hits: Vec<(usize, Vec3)> = panes
        .iter()
        .enumerate()
        .filter_map(|(i, p)| hit_rect(o, d, p.y, p.rect).map(|h| (i, h)))
        .collect();
    hits.sort_by(|a, b| a.1.distance(o).total_cmp(&b.1.distance(o)));
    let mut class: Vec<(usize, bool)> = hits.iter().map(|&(i, p)| (i, shadowed(p, caster))).collect();
    class.push((usize::MAX, shadowed(floor, caster)));
    // Composite back to front: each layer `α·own + (1 − α)·behind`; only the nearest layer's
    // own colour includes its light.
    let (mut colour, mut all_lit) = (floor_colour, floor_colour);
    for (k, &(i, p)) in hits.iter().enumerate().rev() {
        let pane = &panes[i];
        let lit = pane.surface.emission + light(p, &pane.surface, caster);
        let own = if k == 0 { lit } else { pane.surface.emission };
        colour = pane.opacity * own + (1.0 - pane.opacity) * colour;
        all_lit = pane.opacity * lit + (1.0 - pane.opacity) * all_lit;
    }
    Some(Shade { class, colour, all_lit })
}

/// Pixels whose centre and four corners meet the same surfaces in the same shadow states (so
/// rasterisation and the CPU agree on what the pixel shows), with the CPU's shading.
fn judged(cam: &Camera, panes: &[Pane], caster: bool) -> Vec<(u32, u32, Shade)> {
    let mut out = Vec::new();
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let (fx, fy) = (x as f32, y as f32);
            let Some(centre) = cpu_shade(cam, panes, caster, fx + 0.5, fy + 0.5) else {
                continue;
            };
            let uniform = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .all(|&(dx, dy)| {
                    cpu_shade(cam, panes, caster, fx + dx, fy + dy).is_some_and(|s| s.class == centre.class)
                });
            if uniform {
                out.push((x, y, centre));
            }
        }
    }
    out
}

fn pixel(img: &HdrImage, x: u32, y: u32) -> Vec3 {
    Vec3::from_slice(&img.get(x, y)[..3])
}

/// Relative to the expected pixel's brightest channel, as the physical-mode shading test.
fn rel_err(got: Vec3, want: Vec3) -> f32 {
    (got - want).abs().max_element() / want.max_element().max(1e-3)
}

#[test]
fn light_shines_through_a_translucent_pane_which_is_lit_where_no_opaque_volume_covers_it() {
    let (img, scene) = render(&scene_text(&[(PANE_A, None)], true), SIZE);
    let (bare, _) = render(&scene_text(&[], true), SIZE);
    let (opaque, _) = render(&scene_text(&[(PANE_A, Some(1.0))], true), SIZE);
    let cam = &scene.camera;
    let pixels = judged(cam, &[PANE_A], true);
    let (mut outside, mut outside_differs, mut pane_shadow_on_floor) = (0, 0, 0);
    let (mut under, mut pane_lit, mut pane_shadowed) = (0, 0, 0);
    let (mut worst_cpu, mut worst_blend) = (0.0f32, 0.0f32);
    for (x, y, s) in &pixels {
        let got = pixel(&img, *x, *y);
        worst_cpu = worst_cpu.max(rel_err(got, s.colour));
        if s.class.len() == 1 {
            // Not covered by the pane in screen space: the pane changes nothing there.
            outside += 1;
            outside_differs += usize::from(got != pixel(&bare, *x, *y));
            // The same pane made opaque shadows part of this floor.
            pane_shadow_on_floor += usize::from(pixel(&opaque, *x, *y).max_element() < got.max_element() - 1e-3);
        } else {
            // Under the pane: the pane's own shading (CPU) over the floor as rendered without it.
            under += 1;
            let (_, in_shadow) = s.class[0];
            // α·pane (CPU) + (1 − α)·floor, with the floor taken from the pane-less render.
            let want = (s.colour - (1.0 - PANE_A.opacity) * cpu_floor_only(cam, *x, *y))
                + (1.0 - PANE_A.opacity) * pixel(&bare, *x, *y);
            worst_blend = worst_blend.max(rel_err(got, want));
            if in_shadow {
                pane_shadowed += 1;
            } else {
                pane_lit += 1;
            }
        }
    }
    println!(
        "{} pixels judged: {outside} not under the pane ({outside_differs} differ from the pane-less image; the pane made opaque darkens {pane_shadow_on_floor} of them), {under} under it ({pane_lit} lit, {pane_shadowed} in the caster's shadow on the pane); max relative |GPU − CPU| = {worst_cpu:.2e}, under the pane vs the CPU's pane over the rendered floor {worst_blend:.2e}",
        pixels.len()
    );
    assert!(
        outside > 2000 && under > 500 && pane_lit > 400 && pane_shadowed > 20,
        "{outside} / {under} / {pane_lit} / {pane_shadowed}"
    );
    assert_eq!(
        outside_differs, 0,
        "the translucent pane changed floor pixels it does not cover"
    );
    assert!(
        pane_shadow_on_floor > 200,
        "negative control: an opaque pane must shadow the floor beside it ({pane_shadow_on_floor})"
    );
    assert!(worst_cpu < 3e-3, "{worst_cpu}");
    assert!(worst_blend < 3e-3, "{worst_blend}");
}

/// The CPU's floor colour (no panes) at a pixel's centre.
fn cpu_floor_only(cam: &Camera, x: u32, y: u32) -> Vec3 {
    cpu_shade(cam, &[], true, x as f32 + 0.5, y as f32 + 0.5).map_or(Vec3::ZERO, |s| s.colour)
}

#[test]
fn of_two_stacked_panes_only_the_nearer_receives_per_light_light() {
    let panes = [PANE_A, PANE_B];
    let (img, scene) = render(&scene_text(&[(PANE_A, None), (PANE_B, None)], false), SIZE);
    let pixels = judged(&scene.camera, &panes, false);
    let (mut both, mut only_a, mut only_b) = (0, 0, 0);
    let (mut worst, mut worst_both) = (0.0f32, 0.0f32);
    let mut counterfactual = f32::INFINITY;
    for (x, y, s) in &pixels {
        let got = pixel(&img, *x, *y);
        let e = rel_err(got, s.colour);
        worst = worst.max(e);
        match s.class.iter().map(|c| c.0).collect::<Vec<_>>()[..] {
            [0, 1, _] => {
                both += 1;
                worst_both = worst_both.max(e);
                // Had the farther pane received its light, the pixel would be this much brighter.
                counterfactual = counterfactual.min(rel_err(s.all_lit, s.colour));
            }
            [0, _] => only_a += 1,
            [1, _] => only_b += 1,
            _ => {}
        }
    }
    println!("{} pixels judged: {both} through both panes, {only_a} pane A only, {only_b} pane B only; max relative |GPU − CPU| = {worst:.2e} ({worst_both:.2e} through both); lighting the farther pane too would change every two-pane pixel by ≥ {counterfactual:.2e}", pixels.len());
    assert!(
        both > 500 && only_a > 100 && only_b > 100,
        "{both} / {only_a} / {only_b}"
    );
    assert!(worst < 3e-3, "{worst}");
    assert!(
        counterfactual > 2e-2,
        "the fixture must tell the two behaviours apart: {counterfactual}"
    );
}

#[test]
fn opaque_only_consumers_refuse_translucent_materials_with_one_line() {
    let text = |m: &str| {
        scene_text(&[(PANE_A, None)], false).replace(
            "name = \"shadow_volumes\"\nmode = \"physical\"\nanimate = false",
            &format!("name = \"{m}\""),
        )
    };
    let clustered = Scene::from_str(&text("clustered"), "glass.toml", std::path::Path::new(".")).unwrap();
    let e = Renderer::new(common::test_gpu(), clustered, None, (16, 16), 1)
        .err()
        .expect("clustered must refuse")
        .to_string();
    println!("{e}");
    assert!(
        !e.contains('\n')
            && e.contains("glass.toml")
            && e.contains("materials[1] (glass0).opacity")
            && e.contains("clustered"),
        "{e}"
    );
    // The height-field methods, on a terrain whose ground material is made translucent.
    let mut terrain =
        Scene::from_file(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/terrain_sine.toml")).unwrap();
    let ground = terrain.materials.iter().position(|m| m.name == "ground").unwrap();
    terrain.materials[ground].opacity = 0.5;
    let e = Renderer::new(common::test_gpu(), terrain, None, (16, 16), 1)
        .err()
        .expect("the height-field method must refuse")
        .to_string();
    println!("{e}");
    assert!(
        !e.contains('\n')
            && e.contains("terrain_sine.toml")
            && e.contains(&format!("materials[{ground}] (ground).opacity"))
            && e.contains("heightfield_pyramid"),
        "{e}"
    );
    // A translucent BSP world: its PVS would still treat the glass as a wall.
    let world = format!("{}[camera]\nposition = [3, 1.7, -3]\ntarget = [6, 1, -6]\n\n[[materials]]\nname = \"glass\"\nopacity = 0.5\n\n[[objects]]\nname = \"world\"\nmesh = \"bsp_rooms\"\nseed = 1\nwall_material = \"glass\"\n", method(&[]));
    let scene = Scene::from_str(&world, "world.toml", std::path::Path::new(".")).unwrap();
    let e = Renderer::new(common::test_gpu(), scene, None, (16, 16), 1)
        .err()
        .expect("a translucent world must be refused")
        .to_string();
    println!("{e}");
    assert!(
        !e.contains('\n') && e.contains("world.toml") && e.contains("\"glass\".opacity"),
        "{e}"
    );
    let _ = render_scene;
}
