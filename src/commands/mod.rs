//! The commands of the `penumbra` binary that assemble the layers below: headless capture,
//! profiling, baking, the speed/accuracy chart, the HTML report, the generated-scene suite and the
//! interactive demo, and the supersampling that capture and chart share. No technique is named
//! here; methods are reached through the lighting layer's registry.

pub mod bake;
pub mod capture;
pub mod chart;
pub mod demo;
pub mod profile;
pub mod report;
pub mod suite;
pub(crate) mod supersample;
pub mod views;
