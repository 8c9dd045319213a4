//! penumbra: classic real-time lighting methods in one Vulkan renderer, measured side by side.
//!
//! Layers, bottom up (`tests/architecture.rs` keeps every dependency pointing down):
//! - [`backend`] (the only `unsafe` code: Vulkan through ash) and [`world`] (BSP worlds);
//! - [`shaders`], [`graph`] (passes, barriers, timestamps) and [`util`];
//! - [`scene`] (the TOML format and meshes) and [`metrics`];
//! - [`error`];
//! - [`sh`], [`bake`] (the cached bake stage) and [`raytrace`] (the BVH every ray caster shares);
//! - [`environment`], then [`gpu_scene`] (the scene on the GPU);
//! - [`lighting`] (the method interface, shared cores and one folder per technique);
//! - [`renderer`] (frame assembly) and [`reference`](mod@reference) (the path tracer);
//! - [`commands`] (capture, profile, bake, chart, demo).
#![deny(unsafe_code)]

#[allow(unsafe_code)]
pub mod backend;
pub mod bake;
pub mod commands;
pub mod environment;
pub mod error;
pub mod gpu_scene;
pub mod graph;
pub mod lighting;
pub mod metrics;
pub mod raytrace;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod sh;
pub mod shaders;
pub mod util;
pub mod world;

pub use error::{Error, Result};
