//! Tests of the reference path tracer (`penumbra reference`).

#[path = "../support/mod.rs"]
mod support;

mod reference;
