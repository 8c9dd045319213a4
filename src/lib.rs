//! penumbra: classic real-time lighting methods in one Vulkan renderer, measured side by side.
//!
//! Layers, bottom up: [`backend`] (the only `unsafe` Vulkan code), [`graph`] (passes, barriers,
//! timestamps), [`scene`] (the TOML format and meshes), [`renderer`] (the scene on the GPU and
//! frame assembly), one module per lighting method ([`forward`]), and the commands
//! ([`capture`], [`profile`], [`demo`]).

pub mod backend;
pub mod bake;
pub mod bake_scene;
pub mod capture;
pub mod chart;
pub mod console;
pub mod demo;
pub mod environment;
pub mod error;
pub mod gpu_scene;
pub mod graph;
pub mod image_io;
pub mod lighting;
pub mod lightmap;
pub mod many_lights;
pub mod metrics;
pub mod parallel;
pub mod profile;
pub mod progress;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod sh;
pub mod shaders;
pub mod supersample;
pub mod timing;
pub mod world;

pub use error::{Error, Result};
