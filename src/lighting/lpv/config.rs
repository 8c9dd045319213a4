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
}

impl Config {
    pub fn defaults(mode: Mode) -> Config {
        let corrected = mode == Mode::Corrected;
        Config {
            mode,
            grid: 32,
            // The document runs "as many times as desired" and shows 2 (Fig. 6.1).
            iterations: if corrected { 8 } else { 2 },
            rsm: 256,
            injection: if corrected { Injection::Scatter } else { Injection::Gather },
            lookup: if corrected { Lookup::Irradiance } else { Lookup::Point },
            occlusion: corrected,
            clamp: true,
            half: true,
            samples: 8,
            transform_bug: !corrected,
            published_omega: false,
            light: 0,
        }
    }

    pub fn from_decl(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        let mode = params.get_choice("mode", &[("faithful", Mode::Faithful), ("corrected", Mode::Corrected)])?.unwrap_or(Mode::Corrected);
        let mut c = Config::defaults(mode);
        let int = |p: &str, v: &toml::Value, range: std::ops::RangeInclusive<i64>, want: &str| v.as_integer().filter(|n| range.contains(n)).map(|n| n as u32).ok_or_else(|| bad(p, want, v));
        let flag = |p: &str, v: &toml::Value| v.as_bool().ok_or_else(|| bad(p, "true or false", v));
        for (p, v, _) in &decl.params {
            let p = p.as_str();
            match p {
                "mode" => {}
                "grid" => c.grid = int(p, v, 2..=128, "cells per side from 2 to 128")?,
                "iterations" => c.iterations = int(p, v, 0..=256, "a propagation count from 0 to 256")?,
                "rsm" => c.rsm = int(p, v, 16..=4096, "RSM texels per side from 16 to 4096")?,
                "injection" => c.injection = params.choice(p, v, &[("scatter", Injection::Scatter), ("gather", Injection::Gather)])?,
                "lookup" => c.lookup = params.choice(p, v, &[("irradiance", Lookup::Irradiance), ("point", Lookup::Point)])?,
                "geometry_volume" => c.occlusion = flag(p, v)?,
                "clamp" => c.clamp = flag(p, v)?,
                "storage" => c.half = params.choice(p, v, &[("f16", true), ("f32", false)])?,
                "samples" => c.samples = int(p, v, 1..=64, "samples per cell from 1 to 64 (the offset table's size)")?,
                "transform_bug" => c.transform_bug = flag(p, v)?,
                "published_omega" => c.published_omega = flag(p, v)?,
                "light" => c.light = int(p, v, 0..=65535, "the index of a point, spot or directional light")? as usize,
                _ => {}
            }
        }
        Ok(c)
    }

    /// The propagation scheme: the document's accumulates in place without a wavefront.
    pub fn faithful_propagation(&self) -> bool {
        self.mode == Mode::Faithful
    }
}
