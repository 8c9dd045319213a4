//! The method's parameters (what a scene's `methods` entry may set), their defaults, and the
//! quality sweep `penumbra chart` measures.

use glam::Vec3;

use crate::error::Result;
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema, Scene, SceneError};

pub const NAME: &str = "shadow_volumes";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "casters",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "stencil",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "materials",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "pvs",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "radius_culling",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "atten",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "ambient_nz",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "lightmap",
            kind: ParamKind::FloatArray,
        },
        ParamSchema {
            name: "depth_clamp",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "time_s",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "animate",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "stencil_wrap",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "group_lights",
            kind: ParamKind::Bool,
        },
    ],
};

/// Which lighting model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The seed's Eq. 5: unitless light colours, attenuation instead of 1/d², exponent 32,
    /// tangent-space light and eye vectors, an ambient light-map term scaled by N_z.
    Faithful,
    /// Radiometric point lights (I/d², the renderer's normalised BRDF), same geometry and
    /// shadows: comparable with `penumbra reference --direct-only`.
    Physical,
}

/// Which world faces cast, before the back-facing test (seed §4.3.1; the names are the issue's
/// (a)/(b)/(c) sets of `crate::world::casters`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Casters {
    /// Every face of the world (within the light's radius when culling): the brute force.
    Naive,
    /// The faces of the light's PVS: misses the Fig. 8(c) shadows.
    Pvs,
    /// The light's PVS plus the Potential Shadow-Casters Set (and pyramids over receiving
    /// entities): the seed's choice.
    Pscs,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stencil {
    /// Z-fail, and z-pass without the caps for a light none of whose entity volumes reaches the
    /// near plane (Everitt & Kilgard 2002): the same counts as z-fail, at a fraction of the fill.
    Auto,
    /// Count volume faces behind the surface (Carmack's reverse); caps needed, robust.
    ZFail,
    /// Count faces in front; wrong where the near plane cuts a volume. For comparison.
    ZPass,
}

/// How materials without some maps are drawn (seed §4.5, Tables 1/2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialPath {
    /// A pipeline per map combination, each computing only what its materials have.
    SpecialCase,
    /// One pipeline for every material, with 1×1 default maps standing in for missing ones.
    DefaultMaps,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub mode: Mode,
    pub casters: Casters,
    pub stencil: Stencil,
    pub materials: MaterialPath,
    /// Use the PVS (camera culling of drawn faces, light PVS for receivers and casters). Off:
    /// every leaf sees every leaf, as a world compiled without CaPVS.
    pub pvs: bool,
    /// Skip receivers and casters wholly outside a light's radius.
    pub radius_culling: bool,
    /// Attenuation function 1–4 (faithful mode).
    pub atten: u32,
    /// Multiply the ambient term by the normal map's N_z (faithful mode).
    pub ambient_nz: bool,
    /// The light-map value of the ambient term (faithful mode): the radiosity light-map stands in
    /// as a constant. Default: the scene's constant environment, else 0.
    pub lightmap: Vec3,
    /// Use depth clamp for the far caps where the device has it (else the infinite projection
    /// alone, with the far cap nudged inside the far plane).
    pub depth_clamp: bool,
    /// Entity animation time of the first frame, seconds.
    pub time_s: f32,
    /// Advance the animation by 1/60 s per rendered frame.
    pub animate: bool,
    /// Wrapping stencil increments (off: saturating, a negative control for tests).
    pub stencil_wrap: bool,
    /// Light the lights whose receivers are everything in view together: each light's volumes
    /// leave a bit in a light mask, and one pass over the receivers adds every light where its
    /// bit is set. Off: a pass over the receivers per light, as the seed draws them.
    pub group_lights: bool,
}

impl Config {
    pub fn from_decl(decl: &MethodDecl, scene: &Scene) -> Result<Config> {
        let bad = |name: &str, msg: String| scene.method_param_error(decl, name, msg);
        let string = |name: &str, allowed: &[&str], default: &str| -> std::result::Result<String, SceneError> {
            match decl.param(name).and_then(|v| v.as_str()) {
                None => Ok(default.to_string()),
                Some(s) if allowed.contains(&s) => Ok(s.to_string()),
                Some(s) => Err(bad(
                    name,
                    format!("unknown value {s:?}; expected one of: {}", allowed.join(", ")),
                )),
            }
        };
        let boolean = |name: &str, default: bool| decl.param(name).and_then(|v| v.as_bool()).unwrap_or(default);
        let mode = match string("mode", &["faithful", "physical"], "faithful")?.as_str() {
            "physical" => Mode::Physical,
            _ => Mode::Faithful,
        };
        let casters = match string("casters", &["naive", "pvs", "pscs"], "pscs")?.as_str() {
            "naive" => Casters::Naive,
            "pvs" => Casters::Pvs,
            _ => Casters::Pscs,
        };
        let stencil = match string("stencil", &["auto", "zfail", "zpass"], "auto")?.as_str() {
            "zpass" => Stencil::ZPass,
            "zfail" => Stencil::ZFail,
            _ => Stencil::Auto,
        };
        let materials = match string("materials", &["special", "default_maps"], "special")?.as_str() {
            "default_maps" => MaterialPath::DefaultMaps,
            _ => MaterialPath::SpecialCase,
        };
        let atten = match decl.param("atten").and_then(|v| v.as_integer()) {
            None => 4,
            Some(k @ 1..=4) => k as u32,
            Some(k) => return Err(bad("atten", format!("expected 1, 2, 3 or 4, got {k}")).into()),
        };
        let lightmap = match decl.param("lightmap").and_then(|v| v.as_array()) {
            None => match &scene.environment {
                Some(crate::scene::Environment::Constant { radiance }) => *radiance,
                _ => Vec3::ZERO,
            },
            Some(a) => {
                let xs: Vec<f32> = a
                    .iter()
                    .filter_map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
                    .map(|x| x as f32)
                    .collect();
                match xs[..] {
                    [x] if x >= 0.0 => Vec3::splat(x),
                    [r, g, b] if r >= 0.0 && g >= 0.0 && b >= 0.0 => Vec3::new(r, g, b),
                    _ => return Err(bad("lightmap", "expected 1 or 3 non-negative numbers".into()).into()),
                }
            }
        };
        let time_s = decl
            .param("time_s")
            .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
            .unwrap_or(0.0) as f32;
        Ok(Config {
            mode,
            casters,
            stencil,
            materials,
            pvs: boolean("pvs", true),
            radius_culling: boolean("radius_culling", true),
            atten,
            ambient_nz: boolean("ambient_nz", true),
            lightmap,
            depth_clamp: boolean("depth_clamp", true),
            time_s,
            animate: boolean("animate", true),
            stencil_wrap: boolean("stencil_wrap", true),
            group_lights: boolean("group_lights", true),
        })
    }
}

/// A copy of `decl` with `params` set (replacing any the scene gave).
pub fn with_params(decl: &MethodDecl, params: &[(&str, toml::Value)]) -> MethodDecl {
    params
        .iter()
        .fold(decl.clone(), |d, (name, value)| d.with(name, value.clone()))
}

/// The chart's sweep: for each mode, the three caster strategies (the default stencil counting,
/// special-case pipelines, PVS on), then z-fail alone and z-pass alone, the default-map pipeline, and both material paths with the
/// PVS off (the seed's Tables 1/2 columns). The scene's other parameters are kept.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let s = |x: &str| toml::Value::String(x.into());
    let b = toml::Value::Boolean;
    let mut out = Vec::new();
    for mode in ["faithful", "physical"] {
        let points: [(&str, Vec<(&str, toml::Value)>); 8] = [
            ("pscs", vec![("casters", s("pscs"))]),
            ("pvs-only casters", vec![("casters", s("pvs"))]),
            ("naive casters", vec![("casters", s("naive"))]),
            ("pscs z-fail", vec![("casters", s("pscs")), ("stencil", s("zfail"))]),
            ("pscs z-pass", vec![("casters", s("pscs")), ("stencil", s("zpass"))]),
            (
                "pscs default maps",
                vec![("casters", s("pscs")), ("materials", s("default_maps"))],
            ),
            ("pscs PVS off", vec![("casters", s("pscs")), ("pvs", b(false))]),
            (
                "pscs default maps PVS off",
                vec![
                    ("casters", s("pscs")),
                    ("materials", s("default_maps")),
                    ("pvs", b(false)),
                ],
            ),
        ];
        for (label, params) in points {
            let mut all = vec![
                ("mode", s(mode)),
                ("stencil", s("auto")),
                ("materials", s("special")),
                ("pvs", b(true)),
            ];
            for (k, v) in params {
                all.retain(|(n, _)| *n != k);
                all.push((k, v));
            }
            out.push((format!("{NAME} {mode} {label}"), with_params(decl, &all)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(method: &str) -> Scene {
        let text = format!("methods = [{method}]\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n");
        Scene::from_str(&text, "s.toml", std::path::Path::new(".")).unwrap()
    }

    #[test]
    fn defaults_are_the_seeds_choices() {
        let s = scene("\"shadow_volumes\"");
        let c = Config::from_decl(&s.methods[0], &s).unwrap();
        assert_eq!(
            (c.mode, c.casters, c.stencil, c.materials, c.atten),
            (
                Mode::Faithful,
                Casters::Pscs,
                Stencil::Auto,
                MaterialPath::SpecialCase,
                4
            )
        );
        assert!(c.pvs && c.radius_culling && c.ambient_nz && c.depth_clamp && c.stencil_wrap);
    }

    #[test]
    fn bad_values_are_one_line_errors_naming_the_field() {
        for (method, field, hint) in [
            (
                "{ name = \"shadow_volumes\", casters = \"all\" }",
                "methods[0].casters",
                "naive, pvs, pscs",
            ),
            (
                "{ name = \"shadow_volumes\", atten = 5 }",
                "methods[0].atten",
                "1, 2, 3 or 4",
            ),
            (
                "{ name = \"shadow_volumes\", lightmap = [1, 2] }",
                "methods[0].lightmap",
                "1 or 3",
            ),
        ] {
            let s = scene(method);
            let e = Config::from_decl(&s.methods[0], &s).unwrap_err().to_string();
            assert!(
                e.starts_with("s.toml:1: ") && e.contains(field) && e.contains(hint) && !e.contains('\n'),
                "{e}"
            );
        }
    }

    #[test]
    fn the_sweep_covers_strategies_stencil_modes_material_paths_and_the_pvs() {
        let s = scene("\"shadow_volumes\"");
        let points = sweep(&s.methods[0]);
        assert_eq!(points.len(), 16);
        let configs: Vec<Config> = points.iter().map(|(_, d)| Config::from_decl(d, &s).unwrap()).collect();
        for casters in [Casters::Naive, Casters::Pvs, Casters::Pscs] {
            assert!(configs.iter().any(|c| c.casters == casters && c.mode == Mode::Physical));
        }
        for stencil in [Stencil::Auto, Stencil::ZFail, Stencil::ZPass] {
            assert!(configs.iter().any(|c| c.stencil == stencil));
        }
        assert!(configs
            .iter()
            .any(|c| c.materials == MaterialPath::DefaultMaps && !c.pvs));
        assert_eq!(configs.iter().filter(|c| c.mode == Mode::Faithful).count(), 8);
    }
}
