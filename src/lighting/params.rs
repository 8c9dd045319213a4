//! Reading a method's parameters: one error line naming the scene file, line and field (or
//! `methods: <name>.<param>` without a scene), shared by every technique's configuration.

use crate::error::{Error, Result};
use crate::scene::{MethodDecl, Scene};

/// A method declaration's parameters, with what names them in errors.
#[derive(Clone, Copy)]
pub struct Params<'a> {
    pub decl: &'a MethodDecl,
    pub scene: Option<&'a Scene>,
}

impl<'a> Params<'a> {
    pub fn new(decl: &'a MethodDecl, scene: Option<&'a Scene>) -> Params<'a> {
        Params { decl, scene }
    }

    /// `p` holds `got` where `want` was expected.
    pub fn error(&self, p: &str, want: &str, got: &toml::Value) -> Error {
        let message = format!("expected {want}, got {got}");
        match self.scene {
            Some(scene) => scene.method_param_error(self.decl, p, message).into(),
            None => Error::Usage(format!("methods: {}.{p}: {message}", self.decl.name)),
        }
    }

    /// A number (an integer is one too).
    pub fn float(v: &toml::Value) -> Option<f64> {
        v.as_float().or(v.as_integer().map(|i| i as f64))
    }

    /// `v`, the value of `p`, as one of the named `options`.
    pub fn choice<T: Copy>(&self, p: &str, v: &toml::Value, options: &[(&str, T)]) -> Result<T> {
        v.as_str()
            .and_then(|s| options.iter().find(|(o, _)| *o == s))
            .map(|(_, t)| *t)
            .ok_or_else(|| {
                let list: Vec<String> = options.iter().map(|(o, _)| format!("\"{o}\"")).collect();
                self.error(p, &format!("one of {}", list.join(", ")), v)
            })
    }

    /// One warning line for each parameter of `inert` (name, the setting it does nothing in) that
    /// the declaration sets: a value that silently changes nothing misleads whoever set it.
    pub fn inert_warnings(&self, inert: &[(&str, &str)]) -> Vec<String> {
        inert
            .iter()
            .filter(|(p, _)| self.decl.param(p).is_some())
            .map(|(p, why)| {
                let message = format!("does nothing {why}");
                match self.scene {
                    Some(scene) => format!("warning: {}", scene.method_param_error(self.decl, p, message)),
                    None => format!("warning: methods: {}.{p}: {message}", self.decl.name),
                }
            })
            .collect()
    }

    /// Parameter `p` as one of `options`, `None` when the declaration does not set it.
    pub fn get_choice<T: Copy>(&self, p: &str, options: &[(&str, T)]) -> Result<Option<T>> {
        self.decl.param(p).map(|v| self.choice(p, v, options)).transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::Params;
    use crate::scene::Scene;

    /// The warnings a method's declaration (line 1 of a scene) draws for parameters that do
    /// nothing in its setting.
    fn warnings(method: &str) -> Vec<String> {
        let text = format!("methods = [{method}]\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n");
        let scene = Scene::from_str(&text, "inert.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
        let decl = &scene.methods[0];
        let inert = match decl.name.as_str() {
            "sh_lightmap" => crate::lighting::sh_lightmap::config::Config::from_decl(decl, None)
                .unwrap()
                .inert(),
            "prt" => crate::lighting::prt::config::Config::from_decl(decl, None)
                .unwrap()
                .inert(),
            "lpv" => crate::lighting::lpv::config::Config::from_decl(decl, None)
                .unwrap()
                .inert(),
            "bsp_lights" => crate::lighting::bsp_lights::Config::from_decl(decl, None)
                .unwrap()
                .inert(),
            n => panic!("{n}"),
        };
        Params::new(decl, Some(&scene)).inert_warnings(&inert)
    }

    #[test]
    fn parameters_that_do_nothing_draw_one_warning_each() {
        for (method, param) in [
            (r#"{ name = "sh_lightmap", filter = true }"#, "filter"),
            (r#"{ name = "sh_lightmap", cie_zenith = 2 }"#, "cie_zenith"),
            (r#"{ name = "prt", baker = "raster", samples = 256 }"#, "samples"),
            (r#"{ name = "lpv", geometry_volume = false, gbuffer = 64 }"#, "gbuffer"),
            (r#"{ name = "bsp_lights", mode = "corrected", k = 2 }"#, "k"),
        ] {
            let w = warnings(method);
            assert_eq!(w.len(), 1, "{method}: {w:?}");
            assert!(
                w[0].starts_with(&format!("warning: inert.toml:1: methods[0].{param}: does nothing ")),
                "{w:?}"
            );
        }
        // Where they act, nothing.
        for method in [
            r#"{ name = "sh_lightmap", filter = true, reps = 64 }"#,
            r#"{ name = "sh_lightmap", sky = "cie", cie_zenith = 2 }"#,
            r#"{ name = "prt", baker = "rays_cpu", samples = 256 }"#,
            r#"{ name = "lpv", geometry_volume = true, gbuffer = 64 }"#,
            r#"{ name = "bsp_lights", mode = "faithful", k = 2 }"#,
        ] {
            assert_eq!(warnings(method), Vec::<String>::new(), "{method}");
        }
    }

    /// `sh_lightmap` and `prt` light with distant light only: a scene with a point light says
    /// which lights they leave out; one with directional light only says nothing.
    #[test]
    fn distant_light_methods_name_the_lights_they_leave_out() {
        let scene = |light: &str| {
            let text =
                format!("methods = [\"sh_lightmap\"]\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n{light}");
            Scene::from_str(&text, "lights.toml", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
        };
        let bulb = scene("[[lights]]\ntype = \"point\"\nname = \"bulb\"\nposition = [0, 1, 0]\nintensity = 1\n");
        let w = crate::lighting::distant_only_warning(&bulb, "sh_lightmap");
        assert_eq!(
            w.as_deref(),
            Some("warning: lights.toml: sh_lightmap lights with distant light only; it leaves out bulb")
        );
        let sun = scene("[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n");
        assert_eq!(crate::lighting::distant_only_warning(&sun, "sh_lightmap"), None);
    }
}
