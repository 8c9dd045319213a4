//! The height-field methods' parameters (scene `methods` entries), read from a [`MethodDecl`]
//! with the defaults of the thesis (digest §6): ls = 4, lo = 4, nφ = 32, 4 bands, 64² tables.

use crate::error::{Error, Result};
use crate::scene::{MethodDecl, ParamKind, ParamSchema, Scene, SceneError};

/// Largest SH band count the shaders handle (36 coefficients).
pub const MAX_BANDS: u32 = 6;
/// Largest number of azimuth directions.
pub const MAX_NPHI: u32 = 64;
/// Largest level step.
pub const MAX_LS: u32 = 6;
/// Largest number of pyramid levels (ls·log2(1024) + 1).
pub const MAX_LEVELS: u32 = MAX_LS * 10 + 1;
/// Most sphere lights a scene may give these methods (one pass and one layer each).
pub const MAX_LIGHTS: usize = 8;

/// Where the horizon angles come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Horizon {
    /// The thesis's method: smoothing pyramid, one sample per level, B-spline maximum.
    Pyramid,
    /// Ray-marched on the bilinear height field, exact up to the march step.
    BruteForce,
}

/// Faithful to the thesis as built, or with the digest's corrections (§5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Nearest wedge-table lookup (§5.8: a 64-node local table has no node at 0°); the sphere
    /// light's cap angle from the planar distance d_li (§5.9, the thesis's one symbol for both
    /// distances); the truncated spline maximum at its knots and midpoints only.
    Faithful,
    /// Bilinear table lookup; cap angle from the 3D distance |c − p|; the truncated maximum also
    /// evaluated exactly at d_li (§5.1).
    Corrected,
}

/// How each pyramid level is decimated from the previous one (§5.2: the thesis says "bilinear"
/// in Ch. 4 and "bicubic" in Ch. 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decimation {
    /// Tent filter as wide as the target texel.
    Bilinear,
    /// Cubic B-spline filter scaled to the target texel.
    Bicubic,
}

/// A window on the transfer vector's bands (digest §3.2.2's optional fix, not in the thesis):
/// it damps the ringing of the truncated products — the light leaking from below the surface
/// and past a wall — at the cost of softer shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Window {
    None,
    /// Hanning σ-factors of this width in bands.
    Hanning(f32),
    /// Lanczos σ-factors of this width in bands.
    Lanczos(f32),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub horizon: Horizon,
    pub mode: Mode,
    /// Height-field samples per side the method works at (`None`: the mesh's).
    pub resolution: Option<u32>,
    /// Level step: s_r = 2^(1/ls).
    pub ls: u32,
    /// Level offset (octaves toward finer levels; fractional allowed).
    pub lo: f32,
    /// Azimuth directions.
    pub nphi: u32,
    pub bands: u32,
    /// Wedge-table nodes per horizon angle.
    pub table_size: u32,
    pub decimation: Decimation,
    pub window: Window,
    /// Brute force: march step and largest distance, texels (0: res texels for the environment,
    /// the pyramid's reach over the edge-clamped field, and 2·res toward a light).
    pub march_step: f32,
    pub max_distance: f32,
    /// Seconds of animation per rendered frame.
    pub time_step: f32,
    /// Bilinear height fetches through the sampler when the device can filter R32_SFLOAT
    /// (`true`), or always blended in the shader from four texel fetches (`false`).
    pub hardware_bilinear: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            horizon: Horizon::Pyramid,
            mode: Mode::Corrected,
            resolution: None,
            ls: 4,
            lo: 4.0,
            nphi: 32,
            bands: 4,
            table_size: 64,
            decimation: Decimation::Bilinear,
            window: Window::None,
            march_step: 0.25,
            max_distance: 0.0,
            time_step: 1.0 / 60.0,
            hardware_bilinear: true,
        }
    }
}

const fn p(name: &'static str, kind: ParamKind) -> ParamSchema {
    ParamSchema { name, kind }
}

pub const PYRAMID_PARAMS: &[ParamSchema] = &[
    p("mode", ParamKind::String),
    p("window", ParamKind::String),
    p("window_width", ParamKind::Float),
    p("resolution", ParamKind::Int),
    p("ls", ParamKind::Int),
    p("lo", ParamKind::Float),
    p("nphi", ParamKind::Int),
    p("bands", ParamKind::Int),
    p("table_size", ParamKind::Int),
    p("decimation", ParamKind::String),
    p("time_step", ParamKind::Float),
    p("bilinear", ParamKind::String),
];

pub const BRUTE_PARAMS: &[ParamSchema] = &[
    p("mode", ParamKind::String),
    p("window", ParamKind::String),
    p("window_width", ParamKind::Float),
    p("resolution", ParamKind::Int),
    p("nphi", ParamKind::Int),
    p("bands", ParamKind::Int),
    p("table_size", ParamKind::Int),
    p("march_step", ParamKind::Float),
    p("max_distance", ParamKind::Float),
    p("time_step", ParamKind::Float),
    p("bilinear", ParamKind::String),
];

impl Settings {
    /// Reads a declaration of `heightfield_pyramid` or `heightfield_bruteforce`. Types were
    /// checked against the schema when the scene was loaded; ranges are checked here, and an
    /// error names the method and the parameter (see [`Settings::from_scene_decl`] for the
    /// scene's file, line and `methods[i]`).
    pub fn from_decl(decl: &MethodDecl, horizon: Horizon) -> Result<Settings> {
        Self::read(decl, horizon, None)
    }

    /// [`Settings::from_decl`] for a declaration of `scene`: an out-of-range parameter is one
    /// line naming the scene file, the parameter's line and `methods[i].name`.
    pub fn from_scene_decl(decl: &MethodDecl, horizon: Horizon, scene: &Scene) -> Result<Settings> {
        Self::read(decl, horizon, Some(scene))
    }

    // long: one parameter after another, each read and range-checked.
    fn read(decl: &MethodDecl, horizon: Horizon, scene: Option<&Scene>) -> Result<Settings> {
        let mut s = Settings {
            horizon,
            ..Settings::default()
        };
        let bad = |name: &str, msg: String| match scene {
            Some(scene) => {
                let index = scene.methods.iter().position(|m| m == decl).unwrap_or(0);
                let line = decl
                    .params
                    .iter()
                    .find(|(n, _, _)| n == name)
                    .map(|p| p.2)
                    .filter(|&l| l > 0);
                Error::Scene(SceneError::new(
                    &scene.source,
                    line,
                    format!("methods[{index}].{name}"),
                    msg,
                ))
            }
            None => Error::Usage(format!("methods: {}.{name}: {msg}", decl.name)),
        };
        let int = |name: &str, lo: i64, hi: i64| -> Result<Option<u32>> {
            match decl.param(name) {
                None => Ok(None),
                Some(v) => match v.as_integer() {
                    Some(i) if (lo..=hi).contains(&i) => Ok(Some(i as u32)),
                    _ => Err(bad(name, format!("expected an integer from {lo} to {hi}, got {v}"))),
                },
            }
        };
        let num = |name: &str, what: &str, ok: &dyn Fn(f64) -> bool| -> Result<Option<f32>> {
            match decl.param(name) {
                None => Ok(None),
                Some(v) => match v.as_float().or_else(|| v.as_integer().map(|i| i as f64)) {
                    Some(x) if x.is_finite() && ok(x) => Ok(Some(x as f32)),
                    _ => Err(bad(name, format!("expected {what}, got {v}"))),
                },
            }
        };
        let string = |name: &str, options: &[&str]| -> Result<Option<String>> {
            match decl.param(name) {
                None => Ok(None),
                Some(v) => match v.as_str() {
                    Some(x) if options.contains(&x) => Ok(Some(x.to_string())),
                    _ => Err(bad(
                        name,
                        format!(
                            "expected one of {}, got {v}",
                            options
                                .iter()
                                .map(|o| format!("\"{o}\""))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )),
                },
            }
        };
        if let Some(m) = string("mode", &["faithful", "corrected"])? {
            s.mode = if m == "faithful" {
                Mode::Faithful
            } else {
                Mode::Corrected
            };
        }
        if let Some(r) = int("resolution", 8, 1024)? {
            if !r.is_power_of_two() {
                return Err(bad(
                    "resolution",
                    format!("expected a power of two from 8 to 1024, got {r}"),
                ));
            }
            s.resolution = Some(r);
        }
        if let Some(v) = int("ls", 1, MAX_LS as i64)? {
            s.ls = v;
        }
        if let Some(v) = num("lo", "a number from 0 to 10", &|x| (0.0..=10.0).contains(&x))? {
            s.lo = v;
        }
        if let Some(v) = int("nphi", 3, MAX_NPHI as i64)? {
            s.nphi = v;
        }
        if let Some(v) = int("bands", 1, MAX_BANDS as i64)? {
            s.bands = v;
        }
        if let Some(v) = int("table_size", 2, 256)? {
            s.table_size = v;
        }
        if let Some(d) = string("decimation", &["bilinear", "bicubic"])? {
            s.decimation = if d == "bilinear" {
                Decimation::Bilinear
            } else {
                Decimation::Bicubic
            };
        }
        if let Some(v) = num("march_step", "a number of texels from 0.01 to 16", &|x| {
            (0.01..=16.0).contains(&x)
        })? {
            s.march_step = v;
        }
        if let Some(v) = num(
            "max_distance",
            "a number of texels ≥ 0 (0: the field's resolution)",
            &|x| x >= 0.0,
        )? {
            s.max_distance = v;
        }
        if let Some(v) = num("time_step", "a number of seconds ≥ 0", &|x| x >= 0.0)? {
            s.time_step = v;
        }
        if let Some(b) = string("bilinear", &["hardware", "shader"])? {
            s.hardware_bilinear = b == "hardware";
        }
        let width = num("window_width", "a number of bands from 0.5 to 16", &|x| {
            (0.5..=16.0).contains(&x)
        })?;
        match string("window", &["none", "hanning", "lanczos"])?.as_deref() {
            Some("hanning") => s.window = Window::Hanning(width.unwrap_or(s.bands as f32 + 1.0)),
            Some("lanczos") => s.window = Window::Lanczos(width.unwrap_or(s.bands as f32 + 1.0)),
            _ if width.is_some() => {
                return Err(bad("window_width", "needs window = \"hanning\" or \"lanczos\"".into()))
            }
            _ => {}
        }
        Ok(s)
    }

    /// The window's factor per band (1 without a window), `bands` values.
    pub fn window_factors(&self) -> Vec<f32> {
        let bands = self.bands as usize;
        let f = match self.window {
            Window::None => return vec![1.0; bands],
            Window::Hanning(w) => crate::sh::hanning(bands, w as f64),
            Window::Lanczos(w) => crate::sh::lanczos(bands, w as f64),
        };
        // The width was range-checked when read, so the window cannot fail.
        f.map(|v| v.iter().map(|&x| x as f32).collect())
            .unwrap_or_else(|_| vec![1.0; bands])
    }

    /// The configuration as `key=value` pairs for labels (only what the horizon kind uses).
    pub fn label(&self) -> String {
        let mode = match self.mode {
            Mode::Faithful => "faithful".to_string(),
            Mode::Corrected => "corrected".to_string(),
        };
        let mode = match self.window {
            Window::None => mode,
            Window::Hanning(w) => format!("{mode} hanning={w}"),
            Window::Lanczos(w) => format!("{mode} lanczos={w}"),
        };
        match self.horizon {
            Horizon::Pyramid => format!(
                "nphi={} ls={} lo={} bands={} {mode}",
                self.nphi, self.ls, self.lo, self.bands
            ),
            Horizon::BruteForce => format!(
                "nphi={} step={} bands={} {mode}",
                self.nphi, self.march_step, self.bands
            ),
        }
    }
}
