//! Seeded scenes that no method was tuned for: rooms of random size joined by doors and
//! openings, thin and thick walls, furniture boxes and random albedos, lit in every way the
//! methods take (spot lamps, ceiling panels, a sun through a window under a sky, many small lights),
//! an open courtyard under sun and sky, and height-field terrain.
//!
//! Every scene is ordinary scene TOML text, so it can be saved and read back as any scene is;
//! the same (suite seed, index) always gives the same text. The theme follows the index
//! (`index % 6`), so any six consecutive scenes hold every theme; the rest (sizes, positions,
//! albedos, light counts and strengths) follows the seed.

use std::fmt::Write as _;

/// The combinations generated scenes declare, besides each method alone.
pub const COMBINATIONS: [&str; 1] = ["lpv_over_shadow_volumes"];

/// What lights a generated scene and what it is built of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Theme {
    /// Rooms lit by spot lights.
    Lamps,
    /// Rooms lit by quad area lights under the ceiling.
    Panels,
    /// Rooms lit by a sun through a window and a sky.
    Sun,
    /// Rooms lit by many small point and spot lights.
    Crowd,
    /// An open courtyard of walls and blocks under a sun and a sky.
    Courtyard,
    /// A height field under a sphere light and a sky.
    Terrain,
}

impl Theme {
    pub const ALL: [Theme; 6] = [
        Theme::Lamps,
        Theme::Panels,
        Theme::Sun,
        Theme::Crowd,
        Theme::Courtyard,
        Theme::Terrain,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Theme::Lamps => "lamps",
            Theme::Panels => "panels",
            Theme::Sun => "sun",
            Theme::Crowd => "crowd",
            Theme::Courtyard => "courtyard",
            Theme::Terrain => "terrain",
        }
    }

    /// Whether the scene is closed rooms (the radiosity target's "room scenes").
    pub fn is_rooms(self) -> bool {
        matches!(self, Theme::Lamps | Theme::Panels | Theme::Sun | Theme::Crowd)
    }

    /// The methods whose needs the theme's scenes meet, each at its defaults, and the
    /// combinations declared over them (written into the scene's `methods`).
    fn methods(self) -> (&'static [&'static str], &'static str) {
        match self {
            Theme::Lamps => (
                &[
                    "forward",
                    "shadow_volumes",
                    "clustered",
                    "vls",
                    "bsp_lights",
                    "radiosity",
                    "lpv",
                ],
                "[[combinations]]\nname = \"lpv_over_shadow_volumes\"\nbase = \"shadow_volumes\"\n\
                 direct = \"shadow_volumes\"\nindirect = \"lpv\"\n\n",
            ),
            Theme::Panels => (&["forward", "clustered", "vls", "bsp_lights", "radiosity"], ""),
            Theme::Sun => (&["forward", "radiosity", "sh_lightmap", "prt"], ""),
            Theme::Crowd => (&["forward", "shadow_volumes", "clustered", "vls", "bsp_lights"], ""),
            Theme::Courtyard => (&["forward", "radiosity", "sh_lightmap", "prt"], ""),
            Theme::Terrain => (&["forward", "heightfield_pyramid", "heightfield_bruteforce"], ""),
        }
    }
}

/// One generated scene.
#[derive(Clone, Debug)]
pub struct Generated {
    /// `gen-<suite seed>-<index>-<theme>`: unique within a suite, and a file name.
    pub name: String,
    pub theme: Theme,
    pub index: u64,
    /// The scene, as scene TOML.
    pub text: String,
}

/// A SplitMix64 stream: small, seedable and the same on every platform.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let u = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * u
    }

    /// Uniform in 0 .. n (n > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }

    pub fn chance(&mut self, p: f32) -> bool {
        self.range(0.0, 1.0) < p
    }
}

/// The scene `index` of the suite seeded `seed`.
pub fn generate(seed: u64, index: u64) -> Generated {
    let theme = Theme::ALL[(index % Theme::ALL.len() as u64) as usize];
    let mut rng = Rng::new(seed ^ index.wrapping_mul(0xd1b5_4a32_d192_ed03) ^ 0x5eed_0f5c_e7e5);
    let name = format!("gen-{seed}-{index:03}-{}", theme.name());
    let mut w = Writer::default();
    let (methods, combinations) = theme.methods();
    let _ = writeln!(
        w.0,
        "# Generated scene {index} of the suite seeded {seed} ({}): `penumbra suite` wrote it.\n",
        theme.name()
    );
    let list: Vec<String> = methods.iter().map(|m| declaration(m)).collect();
    let _ = writeln!(w.0, "methods = [{}]\n", list.join(", "));
    w.0.push_str(combinations);
    match theme {
        Theme::Courtyard => courtyard(&mut w, &mut rng),
        Theme::Terrain => terrain(&mut w, &mut rng),
        _ => {
            let plan = RoomPlan::random(&mut rng, theme == Theme::Sun);
            plan.write(&mut w, &mut rng);
            match theme {
                Theme::Lamps => lamps(&mut w, &mut rng, &plan),
                Theme::Panels => panels(&mut w, &mut rng, &plan),
                Theme::Sun => sun(&mut w, &mut rng, &plan),
                _ => crowd(&mut w, &mut rng, &plan),
            }
        }
    }
    Generated {
        name,
        theme,
        index,
        text: w.0,
    }
}

/// A method at its defaults, but for shadow volumes' lighting model: its default (`faithful`,
/// the document's attenuated Phong with an ambient term) is not radiance, so only its
/// `physical` mode can be judged against the path tracer.
fn declaration(method: &str) -> String {
    match method {
        "shadow_volumes" => "{ name = \"shadow_volumes\", mode = \"physical\" }".into(),
        m => format!("\"{m}\""),
    }
}

/// The scene text under construction, with writers for its tables.
#[derive(Default)]
struct Writer(String);

fn v3(v: [f32; 3]) -> String {
    format!("[{:.3}, {:.3}, {:.3}]", v[0], v[1], v[2])
}

fn normalize(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}

impl Writer {
    fn camera(&mut self, position: [f32; 3], target: [f32; 3], fov_y_deg: f32) {
        let _ = writeln!(
            self.0,
            "[camera]\nposition = {}\ntarget = {}\nfov_y_deg = {fov_y_deg:.1}\n",
            v3(position),
            v3(target)
        );
    }

    fn material(&mut self, name: &str, albedo: [f32; 3]) {
        let _ = writeln!(self.0, "[[materials]]\nname = \"{name}\"\nalbedo = {}\n", v3(albedo));
    }

    /// An axis-aligned box from `lo` to `hi`, turned by `yaw_deg` about its centre's vertical.
    fn block(&mut self, name: &str, lo: [f32; 3], hi: [f32; 3], yaw_deg: f32, material: &str) {
        let size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        if size.iter().any(|&s| s < 1e-3) {
            return;
        }
        let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
        let _ = writeln!(
            self.0,
            "[[objects]]\nname = \"{name}\"\nmesh = \"box\"\nsize = {}\ntranslate = {}\nrotate_deg = [0, {yaw_deg:.1}, 0]\nmaterial = \"{material}\"\n",
            v3(size),
            v3(centre)
        );
    }

    fn point(&mut self, name: &str, position: [f32; 3], intensity: [f32; 3]) {
        let _ = writeln!(
            self.0,
            "[[lights]]\ntype = \"point\"\nname = \"{name}\"\nposition = {}\nintensity = {}\n",
            v3(position),
            v3(intensity)
        );
    }

    fn spot(&mut self, name: &str, position: [f32; 3], target: [f32; 3], intensity: [f32; 3], cone: (f32, f32)) {
        let _ = writeln!(
            self.0,
            "[[lights]]\ntype = \"spot\"\nname = \"{name}\"\nposition = {}\ntarget = {}\nintensity = {}\ninner_deg = {:.1}\nouter_deg = {:.1}\n",
            v3(position),
            v3(target),
            v3(intensity),
            cone.0,
            cone.1
        );
    }

    fn sun_and_sky(&mut self, direction: [f32; 3], irradiance: [f32; 3], sky: [f32; 3]) {
        let _ = writeln!(
            self.0,
            "[[lights]]\ntype = \"directional\"\nname = \"sun\"\ndirection = {}\nirradiance = {}\n\n[environment]\ntype = \"constant\"\nradiance = {}\n",
            v3(normalize(direction)),
            v3(irradiance),
            v3(sky)
        );
    }
}

/// A random albedo: a grey in [lo, hi] tinted by up to ±30 % per channel.
fn albedo(rng: &mut Rng, lo: f32, hi: f32) -> [f32; 3] {
    let grey = rng.range(lo, hi);
    let mut c = [0.0; 3];
    for x in &mut c {
        *x = (grey * rng.range(0.7, 1.3)).clamp(0.05, 0.9);
    }
    c
}

/// A warm-to-cool light colour of a strength in [lo, hi).
fn tint(rng: &mut Rng, lo: f32, hi: f32) -> [f32; 3] {
    let strength = rng.range(lo, hi);
    let warm = rng.range(-0.15, 0.15);
    [strength * (1.0 + warm), strength, strength * (1.0 - warm)]
}

/// Rooms in a row along x, each `depth` deep (z in ±depth/2) and `height` high, walls between
/// neighbours pierced by a door or a wider opening.
struct RoomPlan {
    /// Each room's x extent (inside its walls).
    rooms: Vec<(f32, f32)>,
    depth: f32,
    height: f32,
    /// The opening in the wall after each room but the last: (z from, z to, top).
    openings: Vec<(f32, f32, f32)>,
    /// In the −z outer wall of this room: (x from, x to, sill, top).
    window: Option<(usize, [f32; 4])>,
    outer: f32,
}

impl RoomPlan {
    fn random(rng: &mut Rng, window: bool) -> RoomPlan {
        let count = 2 + rng.below(2) as usize;
        let depth = rng.range(3.0, 5.5);
        let height = rng.range(2.4, 3.2);
        let wall = |rng: &mut Rng| {
            if rng.chance(0.5) {
                rng.range(0.02, 0.06)
            } else {
                rng.range(0.15, 0.35)
            }
        };
        let mut rooms = Vec::new();
        let mut openings = Vec::new();
        let mut x = 0.0;
        for i in 0..count {
            let width = rng.range(2.5, 5.0);
            rooms.push((x, x + width));
            x += width + wall(rng);
            if i + 1 < count {
                let door = rng.chance(0.6);
                let w = if door {
                    rng.range(0.8, 1.2)
                } else {
                    rng.range(1.5, 0.7 * depth)
                };
                let z0 = rng.range(-depth / 2.0 + 0.3, depth / 2.0 - 0.3 - w);
                let top = if door {
                    rng.range(2.0, 2.2)
                } else {
                    height - rng.range(0.0, 0.4)
                };
                openings.push((z0, z0 + w, top.min(height)));
            }
        }
        let window = window.then(|| {
            let room = rng.below(count as u64) as usize;
            let (a, b) = rooms[room];
            let w = rng.range(0.8, (b - a) * 0.6);
            let x0 = rng.range(a + 0.2, b - 0.2 - w);
            (room, [x0, x0 + w, rng.range(0.6, 1.0), height - rng.range(0.2, 0.5)])
        });
        RoomPlan {
            rooms,
            depth,
            height,
            openings,
            window,
            outer: wall(rng),
        }
    }

    fn write(&self, w: &mut Writer, rng: &mut Rng) {
        let (d, h, t) = (self.depth / 2.0, self.height, self.outer);
        let (x0, x1) = (self.rooms[0].0, self.rooms.last().map_or(0.0, |r| r.1));
        for (name, lo, hi) in [("floor", 0.3, 0.7), ("ceiling", 0.6, 0.85), ("walls", 0.4, 0.85)] {
            w.material(name, albedo(rng, lo, hi));
        }
        w.block("floor", [x0 - t, -0.1, -d - t], [x1 + t, 0.0, d + t], 0.0, "floor");
        w.block("ceiling", [x0 - t, h, -d - t], [x1 + t, h + 0.1, d + t], 0.0, "ceiling");
        w.block("wall -x", [x0 - t, 0.0, -d], [x0, h, d], 0.0, "walls");
        w.block("wall +x", [x1, 0.0, -d], [x1 + t, h, d], 0.0, "walls");
        w.block("wall +z", [x0 - t, 0.0, d], [x1 + t, h, d + t], 0.0, "walls");
        match self.window {
            Some((_, [a, b, sill, top])) => {
                w.block("wall -z left", [x0 - t, 0.0, -d - t], [a, h, -d], 0.0, "walls");
                w.block("wall -z right", [b, 0.0, -d - t], [x1 + t, h, -d], 0.0, "walls");
                w.block("wall -z sill", [a, 0.0, -d - t], [b, sill, -d], 0.0, "walls");
                w.block("wall -z lintel", [a, top, -d - t], [b, h, -d], 0.0, "walls");
            }
            None => w.block("wall -z", [x0 - t, 0.0, -d - t], [x1 + t, h, -d], 0.0, "walls"),
        }
        for (i, &(z0, z1, top)) in self.openings.iter().enumerate() {
            let (a, b) = (self.rooms[i].1, self.rooms[i + 1].0);
            w.block(&format!("wall {i} a"), [a, 0.0, -d], [b, h, z0], 0.0, "walls");
            w.block(&format!("wall {i} b"), [a, 0.0, z1], [b, h, d], 0.0, "walls");
            w.block(&format!("wall {i} lintel"), [a, top, z0], [b, h, z1], 0.0, "walls");
        }
        self.furniture(w, rng);
        self.camera(w, rng);
    }

    fn furniture(&self, w: &mut Writer, rng: &mut Rng) {
        let d = self.depth / 2.0;
        for (r, &(a, b)) in self.rooms.iter().enumerate() {
            for k in 0..1 + rng.below(3) {
                let material = format!("furniture {r} {k}");
                w.material(&material, albedo(rng, 0.15, 0.8));
                let size = [rng.range(0.3, 1.2), rng.range(0.3, 1.4), rng.range(0.3, 1.0)];
                let cx = rng.range(a + 0.7, b - 0.7);
                // Clear of the camera, which stands 0.25 m from the +z wall.
                let cz = rng.range(-d + 0.7, d - 1.5);
                let lo = [cx - size[0] / 2.0, 0.0, cz - size[2] / 2.0];
                let hi = [cx + size[0] / 2.0, size[1], cz + size[2] / 2.0];
                w.block(&material, lo, hi, rng.range(0.0, 90.0), &material);
            }
        }
    }

    /// In the first room by its +z wall, looking at the opening into the next room.
    fn camera(&self, w: &mut Writer, rng: &mut Rng) {
        let (a, b) = self.rooms[0];
        let d = self.depth / 2.0;
        let position = [rng.range(a + 0.3, a + 0.6 * (b - a)), rng.range(1.3, 1.8), d - 0.25];
        let (z0, z1, _) = self.openings[0];
        let target = [b, rng.range(0.8, 1.2), (z0 + z1) / 2.0];
        w.camera(position, target, rng.range(60.0, 75.0));
    }

    /// A random point inside room `r`, `margin` from its walls, at height `y`.
    fn inside(&self, rng: &mut Rng, r: usize, margin: f32, y: f32) -> [f32; 3] {
        let (a, b) = self.rooms[r];
        let d = self.depth / 2.0 - margin;
        [rng.range(a + margin, b - margin), y, rng.range(-d, d)]
    }
}

/// One to three spot lights under the ceiling, each aimed at a point of its room's floor (the
/// lights the light propagation volume takes; points come with the many-light theme).
fn lamps(w: &mut Writer, rng: &mut Rng, plan: &RoomPlan) {
    let h = plan.height;
    for k in 0..1 + rng.below(3) {
        let room = rng.below(plan.rooms.len() as u64) as usize;
        let p = plan.inside(rng, room, 0.4, h - 0.15);
        let target = plan.inside(rng, room, 0.6, 0.0);
        let inner = rng.range(15.0, 35.0);
        let cone = (inner, inner + rng.range(5.0, 20.0));
        let intensity = tint(rng, 3.0, 12.0);
        w.spot(&format!("spot {k}"), p, target, intensity, cone);
    }
}

/// One or two quad lights just under the ceiling, facing down.
fn panels(w: &mut Writer, rng: &mut Rng, plan: &RoomPlan) {
    for k in 0..1 + rng.below(2) {
        let room = rng.below(plan.rooms.len() as u64) as usize;
        let (sx, sz) = (rng.range(0.4, 1.2), rng.range(0.4, 1.2));
        let c = plan.inside(rng, room, 0.3 + sx.max(sz) / 2.0, plan.height - 0.01);
        let radiance = tint(rng, 4.0, 15.0);
        let _ = writeln!(
            w.0,
            "[[lights]]\ntype = \"quad\"\nname = \"panel {k}\"\ncorner = {}\nedge_u = [{sx:.3}, 0, 0]\nedge_v = [0, 0, {sz:.3}]\nradiance = {}\n",
            v3([c[0] - sx / 2.0, c[1], c[2] - sz / 2.0]),
            v3(radiance)
        );
    }
}

/// A sun through the window (it travels toward +z and down, so it enters the room) and a sky.
fn sun(w: &mut Writer, rng: &mut Rng, plan: &RoomPlan) {
    let direction = [rng.range(-0.5, 0.5), -rng.range(0.5, 1.3), 1.0];
    let _ = plan;
    let (irradiance, sky) = (tint(rng, 3.0, 8.0), sky(rng));
    w.sun_and_sky(direction, irradiance, sky);
}

fn sky(rng: &mut Rng) -> [f32; 3] {
    let s = rng.range(0.2, 0.8);
    [s * 0.8, s * 0.9, s * 1.1]
}

/// Many dim point and spot lights spread over every room.
fn crowd(w: &mut Writer, rng: &mut Rng, plan: &RoomPlan) {
    let count = 12 + rng.below(29);
    for k in 0..count {
        let room = rng.below(plan.rooms.len() as u64) as usize;
        // Above the furniture (at most 1.4 m), so that no light is shut inside a box.
        let y = rng.range(1.5, plan.height - 0.3);
        let p = plan.inside(rng, room, 0.3, y);
        if rng.chance(0.7) {
            w.point(&format!("light {k}"), p, tint(rng, 0.1, 0.8));
        } else {
            let target = plan.inside(rng, room, 0.5, 0.0);
            let inner = rng.range(15.0, 35.0);
            let cone = (inner, inner + rng.range(5.0, 15.0));
            w.spot(&format!("light {k}"), p, target, tint(rng, 0.5, 2.0), cone);
        }
    }
}

/// A ground, walls of random thickness and blocks, seen from above under a sun and a sky.
fn courtyard(w: &mut Writer, rng: &mut Rng) {
    let half = rng.range(3.0, 6.0);
    w.material("ground", albedo(rng, 0.3, 0.7));
    w.material("walls", albedo(rng, 0.4, 0.85));
    w.block("ground", [-half, -0.1, -half], [half, 0.0, half], 0.0, "ground");
    for k in 0..2 + rng.below(3) {
        let (len, thick, h) = (rng.range(1.5, half * 1.5), rng.range(0.05, 0.4), rng.range(1.0, 3.0));
        let c = [rng.range(-half + 1.0, half - 1.0), rng.range(-half + 1.0, half - 1.0)];
        let lo = [c[0] - len / 2.0, 0.0, c[1] - thick / 2.0];
        let hi = [c[0] + len / 2.0, h, c[1] + thick / 2.0];
        w.block(&format!("wall {k}"), lo, hi, rng.range(0.0, 180.0), "walls");
    }
    for k in 0..1 + rng.below(4) {
        let material = format!("block {k}");
        w.material(&material, albedo(rng, 0.15, 0.8));
        let s = [rng.range(0.3, 1.2), rng.range(0.3, 1.5), rng.range(0.3, 1.2)];
        let c = [rng.range(-half + 0.8, half - 0.8), rng.range(-half + 0.8, half - 0.8)];
        let lo = [c[0] - s[0] / 2.0, 0.0, c[1] - s[2] / 2.0];
        let hi = [c[0] + s[0] / 2.0, s[1], c[1] + s[2] / 2.0];
        w.block(&material, lo, hi, rng.range(0.0, 90.0), &material);
    }
    let yaw = rng.range(0.0, std::f32::consts::TAU);
    let dist = half * rng.range(1.1, 1.6);
    w.camera(
        [dist * yaw.cos(), rng.range(2.5, 5.0), dist * yaw.sin()],
        [0.0, 0.5, 0.0],
        rng.range(45.0, 65.0),
    );
    let direction = [rng.range(-1.0, 1.0), -rng.range(0.4, 1.5), rng.range(-1.0, 1.0)];
    let (irradiance, sky) = (tint(rng, 2.0, 6.0), sky(rng));
    w.sun_and_sky(direction, irradiance, sky);
}

/// A height field of a random shape under a sphere light and a sky.
fn terrain(w: &mut Writer, rng: &mut Rng) {
    let size = rng.range(6.0, 10.0);
    w.material("ground", albedo(rng, 0.4, 0.8));
    let shape = match rng.below(6) {
        0 => format!("generator = \"sine\"\nwavelength = {:.2}", rng.range(0.8, 2.5)),
        1 => format!("generator = \"cones\"\ncount = {}", 3 + rng.below(6)),
        2 => format!("generator = \"fbm\"\noctaves = 4\nseed = {}", rng.below(1000)),
        3 => format!("generator = \"eggtray\"\nwavelength = {:.2}", rng.range(1.0, 2.5)),
        4 => format!(
            "generator = \"city\"\nwavelength = {:.2}\nseed = {}",
            rng.range(1.0, 2.5),
            rng.below(1000)
        ),
        _ => format!("generator = \"step\"\nposition = {:.2}", rng.range(-1.0, 1.0)),
    };
    let _ = writeln!(
        w.0,
        "[[objects]]\nname = \"terrain\"\nmesh = \"heightfield\"\nmaterial = \"ground\"\nsize = {size:.2}\nresolution = {}\nheight = {:.2}\n{shape}\n",
        [64, 128][rng.below(2) as usize],
        rng.range(0.2, 0.8),
    );
    let yaw = rng.range(0.0, std::f32::consts::TAU);
    let dist = size * rng.range(0.6, 0.9);
    w.camera(
        [dist * yaw.cos(), rng.range(2.5, 5.0), dist * yaw.sin()],
        [0.0, 0.0, 0.0],
        rng.range(45.0, 60.0),
    );
    // A sphere light and a sky: the lights the height-field methods take.
    let a = rng.range(0.0, std::f32::consts::TAU);
    let r = size * 0.55;
    let _ = writeln!(
        w.0,
        "[[lights]]\ntype = \"sphere\"\nname = \"lamp\"\ncenter = {}\nradius = {:.2}\nradiance = {:.1}\n",
        v3([r * a.cos(), rng.range(1.0, 2.5), r * a.sin()]),
        rng.range(0.2, 0.4),
        rng.range(30.0, 80.0)
    );
    let _ = writeln!(w.0, "[environment]\ntype = \"constant\"\nradiance = {}\n", v3(sky(rng)));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every theme, over many seeds, reads back as a valid scene declaring its methods; the
    /// same seed gives the same text and another seed another.
    #[test]
    fn generated_scenes_parse_and_are_reproducible() {
        for seed in [1u64, 7, 12345] {
            for index in 0..12 {
                let g = generate(seed, index);
                assert_eq!(g.text, generate(seed, index).text);
                let scene = crate::scene::Scene::from_str(&g.text, &g.name, std::path::Path::new("/"))
                    .unwrap_or_else(|e| panic!("{}: {e}\n{}", g.name, g.text));
                let (methods, _) = g.theme.methods();
                assert_eq!(scene.methods.len(), methods.len(), "{}", g.name);
                assert!(!scene.lights.is_empty() || scene.environment.is_some(), "{}", g.name);
            }
        }
        assert_ne!(generate(1, 0).text, generate(2, 0).text);
        assert_ne!(generate(1, 0).text, generate(1, 6).text);
    }
}
