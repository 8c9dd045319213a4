//! The border passes (digest §5.4): no darkening at a polygon's edge under uniform light, no
//! step at a seam between coplanar charts, and no light through a wall thinner than a patch.
//! Light-maps are read as the renderer reads them: bilinear, clamped, at the atlas coordinates
//! the triangles carry.

use glam::DVec3;

use crate::lighting::lightmap::atlas::Atlas;
use crate::lighting::lightmap::patches::Patches;
use crate::lighting::lightmap::solve::{Mode, Report, Settings};
use crate::lighting::radiosity::bake::{self, Content};
use crate::scene::Scene;
use crate::util::progress::Progress;

pub(super) struct Baked {
    pub scene: Scene,
    pub p: Patches,
    pub atlas: Atlas,
    pub texels: Vec<[f32; 4]>,
    pub report: Report,
}

pub(super) fn bake_scene(scene: Scene, size: f64, settings: &Settings) -> Baked {
    let geo =
        crate::lighting::lightmap::geometry::scene_geometry(&scene, "radiosity").unwrap_or_else(|e| panic!("{e}"));
    let (p, atlas, texels, report) = bake::bake(
        &geo,
        &scene,
        size,
        settings,
        Content::All,
        bake::Shooter::Cpu,
        &mut Progress::new("test"),
    )
    .unwrap();
    Baked {
        scene,
        p,
        atlas,
        texels,
        report,
    }
}

pub(super) fn bake_text(text: &str, size: f64, settings: &Settings) -> Baked {
    bake_scene(
        Scene::from_str(text, "test.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}")),
        size,
        settings,
    )
}

impl Baked {
    /// The charts of the scene object named `name`.
    pub fn charts_of(&self, name: &str) -> Vec<usize> {
        let o = self
            .scene
            .objects
            .iter()
            .position(|o| o.name == name)
            .unwrap_or_else(|| panic!("no object {name}"));
        (0..self.p.charts.len())
            .filter(|&c| self.p.charts[c].object == o)
            .collect()
    }

    /// The light-map as the renderer samples it at world point `q` of chart `c`
    /// (VK_FILTER_LINEAR, clamp to edge: texel centres at half-integers).
    pub fn sample(&self, c: usize, q: DVec3) -> DVec3 {
        let ch = &self.p.charts[c];
        let (ox, oy) = self.atlas.offsets[c];
        let d = q - ch.origin;
        let (x, y) = (
            d.dot(ch.u) / self.p.size + ox as f64 - 0.5,
            d.dot(ch.v) / self.p.size + oy as f64 - 0.5,
        );
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |i: f64, j: f64| {
            let i = (i.max(0.0) as usize).min(self.atlas.width as usize - 1);
            let j = (j.max(0.0) as usize).min(self.atlas.height as usize - 1);
            let t = self.texels[j * self.atlas.width as usize + i];
            DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
        };
        at(x0, y0) * (1.0 - fx) * (1.0 - fy)
            + at(x0 + 1.0, y0) * fx * (1.0 - fy)
            + at(x0, y0 + 1.0) * (1.0 - fx) * fy
            + at(x0 + 1.0, y0 + 1.0) * fx * fy
    }

    /// Every texel of chart `c`'s rectangle in the atlas.
    pub fn chart_texels(&self, c: usize) -> Vec<[f32; 4]> {
        let ch = &self.p.charts[c];
        let (ox, oy) = self.atlas.offsets[c];
        (0..ch.height)
            .flat_map(|j| (0..ch.width).map(move |i| (i, j)))
            .map(|(i, j)| self.texels[(oy as usize + j) * self.atlas.width as usize + ox as usize + i])
            .collect()
    }
}

fn corrected(threshold: f64) -> Settings {
    Settings {
        threshold,
        ..Settings::default()
    }
}

fn faithful(threshold: f64) -> Settings {
    Settings {
        mode: Mode::Faithful,
        threshold,
        ..Settings::default()
    }
}

fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A quad whose edges lie off the patch grid (so its rim is partial and border patches), lit
/// uniformly by a sun straight down: bilinear reads along its edges are the interior's.
#[test]
fn a_uniformly_lit_quad_does_not_darken_at_its_edges() {
    let text = r#"
methods = ["radiosity"]
[camera]
position = [0, 2, 2]
target = [0, 0, 0]
[[materials]]
name = "grey"
albedo = 0.5
[[objects]]
name = "plane"
mesh = "quad"
corner = [-0.73, 0, -0.61]
edge_u = [0, 0, 1.37]
edge_v = [1.18, 0, 0]
material = "grey"
[[lights]]
type = "directional"
direction = [0, -1, 0]
irradiance = 2
"#;
    for settings in [corrected(1e-4), faithful(1e-4)] {
        let b = bake_text(text, 0.1, &settings);
        let c = b.charts_of("plane")[0];
        let (corner, eu, ev) = (
            DVec3::new(-0.73, 0.0, -0.61),
            DVec3::new(0.0, 0.0, 1.37),
            DVec3::new(1.18, 0.0, 0.0),
        );
        let interior = luminance(b.sample(c, corner + 0.5 * (eu + ev)));
        let inset = 1e-6;
        let mut worst = f64::INFINITY;
        for k in 0..=400 {
            let t = k as f64 / 400.0;
            for q in [
                corner + eu * t + ev * inset,
                corner + eu * t + ev * (1.0 - inset),
                corner + ev * t + eu * inset,
                corner + ev * t + eu * (1.0 - inset),
            ] {
                worst = worst.min(luminance(b.sample(c, q)) / interior);
            }
        }
        eprintln!(
            "{:?}: edge/interior minimum {worst:.6} (interior {interior:.4})",
            settings.mode
        );
        assert!(interior > 0.0);
        assert!(
            worst >= 0.99,
            "{:?}: an edge reads {worst:.4} of the interior",
            settings.mode
        );
    }
}

/// Two coplanar quads (two charts) meeting at x = 0.53, off the 10 cm grid, under a point light,
/// with a shadow whose edge crosses the seam: read on either side of the seam, the light-maps
/// agree within one 8-bit step of the brightest texel.
#[test]
fn coplanar_charts_meet_without_a_step() {
    let text = r#"
methods = ["radiosity"]
[camera]
position = [0, 2, 3]
target = [0, 0, 0]
[[materials]]
name = "grey"
albedo = 0.5
[[objects]]
name = "left"
mesh = "quad"
corner = [-1, 0, -1]
edge_u = [0, 0, 2.5]
edge_v = [1.53, 0, 0]
material = "grey"
[[objects]]
name = "right"
mesh = "quad"
corner = [0.53, 0, -1]
edge_u = [0, 0, 2.5]
edge_v = [1.47, 0, 0]
material = "grey"
[[objects]]
name = "blocker"
mesh = "quad"
corner = [0.2, 0.5, 0.3]
edge_u = [0.7, 0, 0]
edge_v = [0, 0, 1.2]
material = "grey"
[[lights]]
type = "point"
position = [0.5, 1.0, 0.0]
intensity = 1
"#;
    for settings in [corrected(1e-4), faithful(1e-4)] {
        let b = bake_text(text, 0.1, &settings);
        let (l, r) = (b.charts_of("left")[0], b.charts_of("right")[0]);
        let brightest = [l, r]
            .iter()
            .flat_map(|&c| b.chart_texels(c))
            .map(|t| t[0].max(t[1]).max(t[2]) as f64)
            .fold(0.0, f64::max);
        let lsb = brightest / 255.0;
        let (mut worst, mut at) = (0.0f64, 0.0);
        let delta = 1e-7;
        for k in 0..=500 {
            let z = -1.0 + 2.5 * (k as f64 + 0.5) / 501.0;
            let step = (b.sample(l, DVec3::new(0.53 - delta, 0.0, z)) - b.sample(r, DVec3::new(0.53 + delta, 0.0, z)))
                .abs()
                .max_element()
                / lsb;
            if step > worst {
                (worst, at) = (step, z);
            }
        }
        // The shadow's edge (z = 0.6 on the floor) crosses the seam: the floor is lit and dark.
        let (lit, dark) = (
            b.sample(l, DVec3::new(0.4, 0.0, 0.0)).x,
            b.sample(l, DVec3::new(0.4, 0.0, 1.2)).x,
        );
        eprintln!("{:?}: largest step across the seam {worst:.4} LSB at z = {at:.3} (lit {lit:.4}, shadow {dark:.4}, LSB {lsb:.2e})", settings.mode);
        assert!(dark < 0.5 * lit, "the blocker shadows the floor: {dark} vs {lit}");
        assert!(
            worst <= 1.0,
            "{:?}: the seam steps by {worst:.2} LSB at z = {at}",
            settings.mode
        );
    }
}

/// scenes/two_rooms.toml: room A holds both lights, room B shares a 5 cm wall with it. At 20 cm
/// patches room B's floor and ceiling start with a partial column under the wall and their
/// border column overlaps room A's lit patches: pass 2 must refuse those, and every patch and
/// texel of room B stays exactly 0, in both modes.
#[test]
fn no_light_bleeds_through_a_thin_wall() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/two_rooms.toml")).unwrap();
    room_b_stays_dark(&text);
}

/// The same rooms with both faces of their wall lifted half a millimetre off the floor, as
/// generated rooms and real assets model walls: a ray a hair above the floor passes under
/// them. Pass 2's ray runs higher, so room B's border texels still take none of room A's light
/// (with its ray at the floor they took room A's floor light, and in a generated room the dark
/// side's floor drew a lit band along the wall).
#[test]
fn no_light_bleeds_under_a_wall_that_stops_short_of_the_floor() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/two_rooms.toml")).unwrap();
    // Room A's face of the wall, then room B's.
    let faces = [
        (
            "corner = [0.0, 0, -2]\nedge_u = [0, 0, 4]\nedge_v = [0, 2.5, 0]",
            "corner = [0.0, 0.0005, -2]\nedge_u = [0, 0, 4]\nedge_v = [0, 2.4995, 0]",
        ),
        (
            "corner = [0.05, 0, -2]\nedge_u = [0, 2.5, 0]",
            "corner = [0.05, 0.0005, -2]\nedge_u = [0, 2.4995, 0]",
        ),
    ];
    let mut lifted = text.clone();
    for (face, raised) in faces {
        assert_eq!(
            lifted.matches(face).count(),
            1,
            "scenes/two_rooms.toml no longer has the wall face {face:?}"
        );
        lifted = lifted.replace(face, raised);
    }
    room_b_stays_dark(&lifted);
}

fn room_b_stays_dark(text: &str) {
    let scene = Scene::from_str(text, "two_rooms.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
    for settings in [corrected(1e-2), faithful(1e-2)] {
        let b = bake_scene(scene.clone(), 0.2, &settings);
        let room = |prefix: &str| {
            names
                .iter()
                .filter(|n| n.starts_with(prefix))
                .flat_map(|n| b.charts_of(n))
                .collect::<Vec<usize>>()
        };
        let (a, dark) = (room("A "), room("B "));
        assert_eq!(dark.len(), 6);
        let patches_b = dark
            .iter()
            .flat_map(|&c| b.p.patches.iter().filter(move |q| q.chart == c))
            .map(|q| q.total.max_element())
            .fold(0.0f64, f64::max);
        let texels_b = dark
            .iter()
            .flat_map(|&c| b.chart_texels(c))
            .map(|t| t[0].max(t[1]).max(t[2]))
            .fold(0.0f32, f32::max);
        let lit_a = a
            .iter()
            .flat_map(|&c| b.chart_texels(c))
            .map(|t| t[0])
            .fold(0.0f32, f32::max);
        eprintln!("{:?}: room B max patch {patches_b}, max texel {texels_b}; room A max texel {lit_a}; pass 2 refused {} contributions", settings.mode, b.report.border_refused);
        assert!(lit_a > 0.05, "room A is lit: {lit_a}");
        assert_eq!(patches_b, 0.0, "{:?}: light reached a patch of room B", settings.mode);
        assert_eq!(texels_b, 0.0, "{:?}: light bled into a texel of room B", settings.mode);
        assert!(
            b.report.border_refused > 0,
            "the anti-bleeding check was never exercised"
        );
    }
}

/// Faithful light-maps are CaLight's RGB8: every texel is a byte over 255 (what the
/// R8G8B8A8_UNORM texture holds, bit for bit); corrected ones are linear floats.
#[test]
fn faithful_texels_are_bytes() {
    use crate::backend::vk;
    use crate::lighting::lightmap::atlas::to_rgb8;
    use crate::lighting::radiosity::lightmap_format;
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/two_rooms.toml")).unwrap();
    let b = bake_text(&text, 0.2, &faithful(1e-2));
    let flat: Vec<f32> = b.texels.iter().flatten().copied().collect();
    let bytes = to_rgb8(&flat);
    let off = flat
        .chunks_exact(4)
        .zip(bytes.chunks_exact(4))
        .map(|(t, c)| {
            (0..3)
                .map(|i| (t[i] - c[i] as f32 / 255.0).abs())
                .fold(0.0f32, f32::max)
        })
        .fold(0.0f32, f32::max);
    let levels: std::collections::BTreeSet<u8> = bytes.chunks_exact(4).map(|c| c[0]).collect();
    eprintln!(
        "faithful: {} distinct red bytes, largest texel-byte difference {off:e}",
        levels.len()
    );
    assert!(off < 1e-6, "a faithful texel is not a byte: {off}");
    assert!(
        levels.len() > 20 && levels.contains(&0) && levels.contains(&255),
        "{levels:?}"
    );
    assert_eq!(lightmap_format(Mode::Faithful), vk::Format::R8G8B8A8_UNORM);
    assert_eq!(lightmap_format(Mode::Corrected), vk::Format::R32G32B32A32_SFLOAT);
    let c = bake_text(&text, 0.2, &corrected(1e-2));
    assert!(
        c.texels
            .iter()
            .any(|t| ((t[0] * 255.0).round() - t[0] * 255.0).abs() > 1e-3),
        "corrected texels are floats"
    );
}
