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

    /// Parameter `p` as one of `options`, `None` when the declaration does not set it.
    pub fn get_choice<T: Copy>(&self, p: &str, options: &[(&str, T)]) -> Result<Option<T>> {
        self.decl.param(p).map(|v| self.choice(p, v, options)).transpose()
    }
}
