//! The LPV's parameters (scenes/README.md, `lpv`): the document's mode and the corrected one,
//! and each choice either mode makes, which a scene may override.

use crate::error::Result;
use crate::lighting::params::Params;
use crate::scene::{MethodDecl, Scene};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// The document as written (digest §2.5–2.8).
    Faithful,
    /// Kaplanyan & Dachsbacher's LPV with the leaf extensions.
    Corrected,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Injection {
    /// Every RSM texel scattered as a cosine lobe into the cell half a cell along its normal.
    Scatter,
    /// The document's per-cell gather of delta lobes from a few RSM samples.
    Gather,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Lookup {
    /// Irradiance c·coslobe(−n)/cell², ρ/π, half a cell along the normal.
    Irradiance,
    /// The document's point evaluation albedo·clamp(SH(−n), 0, 1).
    Point,
}

/// What the method draws: its indirect term, or a debug view.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum View {
    Indirect,
    /// Full screen: an RSM layer, or the volume's slices.
    RsmFlux,
    RsmTransmitted,
    RsmNormal,
    RsmPosition,
    Slices,
    /// On the surfaces: what the look-up reads there.
    Albedo,
    Normal,
    Position,
    /// Full screen: the G-buffer's normals, or its depth (the distance from the camera over the
    /// volume's side).
    GbufferNormal,
    GbufferDepth,
}

impl View {
    /// The shaders' `VIEW` constant.
    pub fn id(self) -> u32 {
        match self {
            View::Indirect => 0,
            View::RsmFlux => 1,
            View::RsmTransmitted => 2,
            View::RsmNormal => 3,
            View::RsmPosition => 4,
            View::Slices => 5,
            View::Albedo => 6,
            View::Normal => 7,
            View::Position => 8,
            View::GbufferNormal => 9,
            View::GbufferDepth => 10,
        }
    }

    pub fn full_screen(self) -> bool {
        !matches!(self, View::Indirect | View::Albedo | View::Normal | View::Position)
    }

    /// Whether it shows the camera's G-buffer rather than the RSM or the volume.
    pub fn gbuffer(self) -> bool {
        matches!(self, View::GbufferNormal | View::GbufferDepth)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    pub mode: Mode,
    /// Cells per side.
    pub grid: u32,
    pub iterations: u32,
    /// RSM texels per side.
    pub rsm: u32,
    pub injection: Injection,
    pub lookup: Lookup,
    /// Attenuate propagation by the geometry volume.
    pub occlusion: bool,
    /// Clamp a source's negative intensity toward a face.
    pub clamp: bool,
    /// fp16 sets (the document's RGBA16F) rather than fp32.
    pub half: bool,
    /// The gather's samples per cell.
    pub samples: u32,
    /// The gather's compounding transform (the document's listing).
    pub transform_bug: bool,
    /// The published side solid angle 0.4234413544 instead of the exact one.
    pub published_omega: bool,
    /// Which of the scene's lights (point, spot, directional, in order) lights the RSM.
    pub light: usize,
    /// With every spot and sun lighting the volume: at most this many, those sending the most
    /// flux (an RSM and an injection each a frame).
    pub max_lights: usize,
    /// The light turns about the vertical at this many degrees per second (the LPV's light
    /// only: for measuring stability, T13).
    pub light_spin: f64,
    /// Snap the RSM's window to whole texels across the light.
    pub snap: bool,
    /// The document's compositor: the point look-up blended with the direct term (faithful
    /// only; the corrected look-up adds).
    pub blend: bool,
    /// The volume's centre and side (metres); `None`: the cube over the scene's objects. With
    /// cascades the centre is the camera's and the side the finest cascade's.
    pub region: Option<([f32; 3], f32)>,
    pub view: View,
    /// Nested volumes around the camera, each twice the previous one's side (1: one volume over
    /// the scene or the region).
    pub cascades: u32,
    /// Texels per side of the camera's G-buffer, whose surfels add to the geometry volume (0:
    /// no G-buffer pass, the RSM's surfels only).
    pub gbuffer: u32,
}

fn centre_of(v: &toml::Value) -> Option<[f32; 3]> {
    let a = v.as_array().filter(|a| a.len() == 3)?;
    let x: Vec<f32> = a
        .iter()
        .filter_map(Params::float)
        .filter(|x| x.is_finite())
        .map(|x| x as f32)
        .collect();
    (x.len() == 3).then(|| [x[0], x[1], x[2]])
}

/// `view`'s names.
const VIEWS: [(&str, View); 11] = [
    ("indirect", View::Indirect),
    ("rsm_flux", View::RsmFlux),
    ("rsm_transmitted", View::RsmTransmitted),
    ("rsm_normal", View::RsmNormal),
    ("rsm_position", View::RsmPosition),
    ("slices", View::Slices),
    ("albedo", View::Albedo),
    ("normal", View::Normal),
    ("position", View::Position),
    ("gbuffer_normal", View::GbufferNormal),
    ("gbuffer_depth", View::GbufferDepth),
];

/// `centre` and `size`, each checked on its own (how they combine is [`Config::region`]'s).
fn region_keys(decl: &MethodDecl, params: &Params<'_>) -> Result<(Option<[f32; 3]>, Option<f64>)> {
    let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
    let centre = decl
        .param("centre")
        .map(|v| centre_of(v).ok_or_else(|| bad("centre", "3 finite numbers (metres)", v)))
        .transpose()?;
    let size = decl
        .param("size")
        .map(|v| {
            Params::float(v)
                .filter(|x| x.is_finite() && *x > 0.0)
                .ok_or_else(|| bad("size", "a side > 0 (metres)", v))
        })
        .transpose()?;
    Ok((centre, size))
}

impl Config {
    /// The parameters that do nothing with this configuration, and why.
    pub fn inert(&self) -> Vec<(&'static str, &'static str)> {
        if self.occlusion {
            Vec::new()
        } else {
            vec![("gbuffer", "without the geometry volume (`geometry_volume = false`)")]
        }
    }

    pub fn defaults(mode: Mode) -> Config {
        let corrected = mode == Mode::Corrected;
        Config {
            mode,
            grid: 32,
            // The document runs "as many times as desired" and shows 2 (Fig. 6.1).
            iterations: if corrected { 8 } else { 2 },
            rsm: 256,
            injection: if corrected {
                Injection::Scatter
            } else {
                Injection::Gather
            },
            lookup: if corrected { Lookup::Irradiance } else { Lookup::Point },
            occlusion: corrected,
            clamp: true,
            half: true,
            samples: 8,
            transform_bug: !corrected,
            published_omega: false,
            light: 0,
            max_lights: 8,
            light_spin: 0.0,
            snap: true,
            blend: !corrected,
            region: None,
            view: View::Indirect,
            cascades: 1,
            gbuffer: 0,
        }
    }

    pub fn from_decl(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let mode = params
            .get_choice("mode", &[("faithful", Mode::Faithful), ("corrected", Mode::Corrected)])?
            .unwrap_or(Mode::Corrected);
        let mut c = Config::parse_keys(decl, &params, Config::defaults(mode))?;
        let (centre, size) = region_keys(decl, &params)?;
        c.check_together(decl, &params)?;
        c.region = c.region(decl, &params, centre, size)?;
        Ok(c)
    }

    /// Each parameter of `decl` over `c` (the mode's defaults), checked on its own; the region's
    /// keys are read apart ([`region_keys`]).
    fn parse_keys(decl: &MethodDecl, params: &Params<'_>, mut c: Config) -> Result<Config> {
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        let int = |p: &str, v: &toml::Value, range: std::ops::RangeInclusive<i64>, want: &str| {
            v.as_integer()
                .filter(|n| range.contains(n))
                .map(|n| n as u32)
                .ok_or_else(|| bad(p, want, v))
        };
        let flag = |p: &str, v: &toml::Value| v.as_bool().ok_or_else(|| bad(p, "true or false", v));
        for (p, v, _) in &decl.params {
            let p = p.as_str();
            match p {
                "mode" => {}
                "grid" => c.grid = int(p, v, 2..=128, "cells per side from 2 to 128")?,
                "iterations" => c.iterations = int(p, v, 0..=256, "a propagation count from 0 to 256")?,
                "rsm" => c.rsm = int(p, v, 16..=4096, "RSM texels per side from 16 to 4096")?,
                "injection" => {
                    c.injection =
                        params.choice(p, v, &[("scatter", Injection::Scatter), ("gather", Injection::Gather)])?
                }
                "lookup" => {
                    c.lookup = params.choice(p, v, &[("irradiance", Lookup::Irradiance), ("point", Lookup::Point)])?
                }
                "geometry_volume" => c.occlusion = flag(p, v)?,
                "clamp" => c.clamp = flag(p, v)?,
                "storage" => c.half = params.choice(p, v, &[("f16", true), ("f32", false)])?,
                "samples" => c.samples = int(p, v, 1..=64, "samples per cell from 1 to 64 (the offset table's size)")?,
                "transform_bug" => c.transform_bug = flag(p, v)?,
                "published_omega" => c.published_omega = flag(p, v)?,
                "light" => c.light = int(p, v, 0..=65535, "the index of a point, spot or directional light")? as usize,
                "max_lights" => c.max_lights = int(p, v, 1..=256, "a light count from 1 to 256")? as usize,
                "light_spin" => {
                    c.light_spin = Params::float(v)
                        .filter(|x| x.is_finite() && x.abs() <= 3600.0)
                        .ok_or_else(|| bad(p, "degrees per second, at most 3600", v))?
                }
                "snap" => c.snap = flag(p, v)?,
                "blend" => c.blend = flag(p, v)?,
                "cascades" => c.cascades = int(p, v, 1..=4, "a cascade count from 1 to 4")?,
                "gbuffer" => c.gbuffer = int(p, v, 0..=4096, "texels per side from 16 to 4096, or 0 for none")?,
                "camera_surfels" => {
                    return Err(bad(
                        p,
                        "nothing: the camera's surfels are now the G-buffer pass, `gbuffer = N` (N texels per side)",
                        v,
                    ))
                }
                "view" => c.view = params.choice(p, v, &VIEWS)?,
                "centre" | "size" => {}
                _ => {}
            }
        }
        Ok(c)
    }

    /// What no single parameter decides: the blend belongs to the point look-up, a G-buffer
    /// large enough to sample, dropped without the geometry volume it feeds, and present for
    /// its own views.
    fn check_together(&mut self, decl: &MethodDecl, params: &Params<'_>) -> Result<()> {
        let c = self;
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        if c.lookup != Lookup::Point && decl.param("blend").and_then(toml::Value::as_bool) == Some(true) {
            return Err(bad(
                "blend",
                "false: the document's blend with the direct term belongs to its point look-up (lookup = \"point\"); the irradiance look-up adds",
                decl.param("blend").unwrap_or(&toml::Value::from(true)),
            ));
        }
        c.blend &= c.lookup == Lookup::Point;
        if (1..16).contains(&c.gbuffer) {
            return Err(bad(
                "gbuffer",
                "texels per side from 16 to 4096, or 0 for none",
                decl.param("gbuffer").unwrap_or(&toml::Value::from(0)),
            ));
        }
        // The G-buffer's surfels feed the geometry volume only: without it the pass would cost
        // its time and change nothing.
        if !c.occlusion {
            c.gbuffer = 0;
        }
        if c.view.gbuffer() && c.gbuffer == 0 {
            return Err(bad(
                "view",
                "a view of the RSM or the volume: the G-buffer's views need `gbuffer` > 0 and the geometry volume",
                decl.param("view").unwrap_or(&toml::Value::from("")),
            ));
        }
        Ok(())
    }

    /// The volume's region from `centre` and `size`: both or neither for one volume; cascades
    /// follow the camera and take the finest one's side alone.
    fn region(
        &self,
        decl: &MethodDecl,
        params: &Params<'_>,
        centre: Option<[f32; 3]>,
        size: Option<f64>,
    ) -> Result<Option<([f32; 3], f32)>> {
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        Ok(match (centre, size, self.cascades) {
            (Some(_), _, 2..) => {
                return Err(bad(
                    "centre",
                    "no centre: cascades follow the camera (`size` sets the finest one's side)",
                    decl.param("centre").unwrap_or(&toml::Value::from(0)),
                ))
            }
            (None, Some(s), 2..) => Some(([0.0; 3], s as f32)),
            (Some(c), Some(s), _) => Some((c, s as f32)),
            (None, None, _) => None,
            (Some(_), None, _) => return Err(bad("size", "a side with `centre`", &toml::Value::from("nothing"))),
            (None, Some(s), _) => return Err(bad("centre", "a centre with `size`", &toml::Value::from(s))),
        })
    }

    /// The propagation scheme: the document's accumulates in place without a wavefront.
    pub fn faithful_propagation(&self) -> bool {
        self.mode == Mode::Faithful
    }
}
