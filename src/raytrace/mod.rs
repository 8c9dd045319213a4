//! Ray casting shared by the path tracer and every baker that casts rays (radiosity, SH
//! light-maps, PRT, the many-lights shadow feelers): the BVH built on the CPU and its CPU
//! traversal ([`bvh`]), and the read-only tables the compute shaders walk it from
//! ([`texel_table`]; GLSL side `glsl/common/bvh.glsl` and `glsl/common/texel_table.glsl`).

use bytemuck::{Pod, Zeroable};

pub mod bvh;
pub mod texel_table;

/// What a ray is intersected with: corner and two edges (`Triangle` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TracedTriangle {
    pub p0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}
