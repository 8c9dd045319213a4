//! Tests of the backend and the frame graph on the device: features, barriers, raster state,
//! the GPU spherical-harmonics code and the forward method's known answers. One binary, one
//! module per subject, so the library and the shader compiler are linked once.

#[path = "../support/mod.rs"]
mod support;

mod backend_features;
mod graph_gpu;
mod known_answers;
mod raster_state;
mod sh_gpu;
