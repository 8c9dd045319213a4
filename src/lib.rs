//! penumbra: classic real-time lighting methods in one Vulkan renderer, measured side by side.
//!
//! Layers, bottom up: [`backend`] (the only `unsafe` Vulkan code), [`graph`] (passes, barriers,
//! timestamps), [`scene`] (the TOML format and meshes), [`renderer`] (the scene on the GPU and
//! frame assembly), one module per lighting method ([`forward`]), and the commands
//! ([`capture`], [`profile`], [`demo`]).

pub mod backend;
pub mod capture;
pub mod chart;
pub mod console;
pub mod demo;
pub mod error;
pub mod forward;
pub mod graph;
pub mod heightfield;
pub mod image_io;
pub mod methods;
pub mod metrics;
pub mod profile;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod sh;
pub mod shaders;
pub mod shadow_volumes;
pub mod world;

pub use error::{Error, Result};
