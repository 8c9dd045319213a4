//! The method's parameters, each checked with one error line naming the scene file, line and field.

use crate::error::Result;
use crate::lighting::lightmap::solve::{self, Mode};
use crate::lighting::params::Params;
use crate::scene::{MethodDecl, Scene};

/// How the coefficients are stored on the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// The seed's ⌈n²/4⌉ RGBA8 layers, range-encoded `c/4 + ½` ([−2, 2], step 4/255).
    Rgba8,
    Half,
    Single,
}

/// Where the run-time light comes from (the Ca3D-Engine thesis §5.5: distant lights only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sky {
    /// The scene's environment (constant, equirect or cube), projected once.
    Scene,
    /// The CIE clear sky around the sun (the scene's first directional light), projected every
    /// frame as the sun moves.
    Cie,
}

/// Debug views (the Ca3D-Engine thesis Figs. 16/17 and 20).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Final = 0,
    /// The first layer's (or the representative's first group's) stored texel as RGB.
    FirstLayer = 1,
    /// The index map as colour (low byte red, high byte green).
    Indices = 2,
    /// The SH light alone, without the diffuse colour.
    Bare = 3,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    pub transfer: super::transfer::Settings,
    pub samples: usize,
    pub patch_size: f64,
    /// VQ representatives (0: uncompressed).
    pub reps: usize,
    /// The 4-tap "bilinear by multisampling" filter of the compressed path.
    pub filter: bool,
    pub storage: Storage,
    /// Normal-map samples per patch (0: normal maps ignored by the bake).
    pub normal_samples: usize,
    /// The directional lights turn about the vertical at this rate (degrees per second).
    pub sun_speed: f64,
    pub sky: Sky,
    /// The CIE sky's zenith radiance (W/(m²·sr)).
    pub cie_zenith: f64,
    pub view: View,
    pub on_gpu: Option<bool>,
}

impl Config {
    pub fn defaults(mode: Mode) -> Config {
        let faithful = mode == Mode::Faithful;
        let solve = solve::Settings {
            mode,
            threshold: if faithful { 0.1 } else { solve::CORRECTED_THRESHOLD },
            ..solve::Settings::default()
        };
        Config {
            transfer: super::transfer::Settings {
                solve,
                bands: 4,
                bounces: true,
                tone: faithful,
            },
            samples: 10_000,
            patch_size: 0.25,
            reps: 0,
            filter: false,
            storage: if faithful { Storage::Rgba8 } else { Storage::Half },
            normal_samples: 16,
            sun_speed: 0.0,
            sky: Sky::Scene,
            cie_zenith: 1.0,
            view: View::Final,
            on_gpu: None,
        }
    }

    /// The parameters that do nothing with this configuration, and why.
    pub fn inert(&self) -> Vec<(&'static str, &'static str)> {
        let mut out = Vec::new();
        if self.reps == 0 {
            out.push(("filter", "without `reps` (it filters the representatives' index map)"));
        }
        if self.sky != Sky::Cie {
            out.push(("cie_zenith", "without `sky = \"cie\"`"));
        }
        out
    }

    // long: one key-by-key parser, a match arm per parameter.
    pub fn from_decl(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        let float = Params::float;
        let mode = params
            .get_choice("mode", &[("faithful", Mode::Faithful), ("corrected", Mode::Corrected)])?
            .unwrap_or(Mode::Corrected);
        let mut c = Config::defaults(mode);
        for (p, v, _) in &decl.params {
            match p.as_str() {
                "mode" => {}
                "bands" => {
                    c.transfer.bands =
                        v.as_integer()
                            .filter(|b| (2..=8).contains(b))
                            .ok_or_else(|| bad(p, "a band count from 2 to 8", v))? as usize
                }
                "samples" => {
                    c.samples = v
                        .as_integer()
                        .filter(|n| {
                            (super::samples::MIN_SAMPLES as i64..=super::samples::MAX_SAMPLES as i64).contains(n)
                        })
                        .ok_or_else(|| bad(p, "a sample count from 20 to 100000", v))?
                        as usize
                }
                "patch_size" => {
                    c.patch_size = float(v)
                        .filter(|x| x.is_finite() && *x > 0.0)
                        .ok_or_else(|| bad(p, "a size in metres above 0", v))?
                }
                "block" => {
                    c.transfer.solve.block =
                        v.as_integer()
                            .filter(|b| (1..=16).contains(b))
                            .ok_or_else(|| bad(p, "an integer from 1 to 16", v))? as usize
                }
                "threshold" => {
                    c.transfer.solve.threshold = float(v)
                        .filter(|x| *x > 0.0 && *x < 1.0)
                        .ok_or_else(|| bad(p, "a fraction in (0, 1)", v))?
                }
                "bounces" => c.transfer.bounces = v.as_bool().ok_or_else(|| bad(p, "true or false", v))?,
                "tone" => c.transfer.tone = v.as_bool().ok_or_else(|| bad(p, "true or false", v))?,
                "reps" => {
                    c.reps = v
                        .as_integer()
                        .filter(|r| (0..=65_536).contains(r))
                        .ok_or_else(|| bad(p, "0 (uncompressed) or a representative count up to 65536", v))?
                        as usize
                }
                "filter" => c.filter = v.as_bool().ok_or_else(|| bad(p, "true or false", v))?,
                "storage" => {
                    c.storage = match v.as_str() {
                        Some("rgba8") => Storage::Rgba8,
                        Some("f16") => Storage::Half,
                        Some("f32") => Storage::Single,
                        _ => return Err(bad(p, "\"rgba8\", \"f16\" or \"f32\"", v)),
                    }
                }
                "normal_samples" => {
                    c.normal_samples =
                        v.as_integer()
                            .filter(|k| (0..=1024).contains(k))
                            .ok_or_else(|| bad(p, "a sample count from 0 to 1024", v))? as usize
                }
                "sun_speed" => {
                    c.sun_speed = float(v)
                        .filter(|x| x.is_finite() && x.abs() <= 3600.0)
                        .ok_or_else(|| bad(p, "degrees per second, at most 3600", v))?
                }
                "sky" => {
                    c.sky = match v.as_str() {
                        Some("scene") => Sky::Scene,
                        Some("cie") => Sky::Cie,
                        _ => return Err(bad(p, "\"scene\" or \"cie\"", v)),
                    }
                }
                "cie_zenith" => {
                    c.cie_zenith = float(v)
                        .filter(|x| x.is_finite() && *x >= 0.0)
                        .ok_or_else(|| bad(p, "a radiance >= 0", v))?
                }
                "view" => {
                    c.view = match v.as_str() {
                        Some("final") => View::Final,
                        Some("first_layer") => View::FirstLayer,
                        Some("indices") => View::Indices,
                        Some("bare") => View::Bare,
                        _ => return Err(bad(p, "\"final\", \"first_layer\", \"indices\" or \"bare\"", v)),
                    }
                }
                "baker" => {
                    c.on_gpu = match v.as_str() {
                        Some("auto") => None,
                        Some("gpu") => Some(true),
                        Some("cpu") => Some(false),
                        _ => return Err(bad(p, "\"auto\", \"gpu\" or \"cpu\"", v)),
                    }
                }
                _ => {}
            }
        }
        if c.view == View::Indices && c.reps == 0 {
            return Err(bad(
                "view",
                "a view of this storage (\"indices\" needs reps > 0)",
                &toml::Value::from("indices"),
            ));
        }
        Ok(c)
    }
}
