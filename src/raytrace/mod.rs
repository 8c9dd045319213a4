//! Ray casting shared by the path tracer and every baker that casts rays (radiosity, SH
//! light-maps, PRT, the many-lights shadow feelers): the BVH built on the CPU and its CPU
//! traversal ([`bvh`]), and the read-only tables the compute shaders walk it from
//! (`texel_table`; GLSL side `glsl/common/bvh.glsl` and `glsl/common/texel_table.glsl`).

use bytemuck::{Pod, Zeroable};

pub mod bvh;
pub(crate) mod texel_table;

/// What a ray is intersected with: corner and two edges (`Triangle` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TracedTriangle {
    pub p0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}

impl TracedTriangle {
    /// The triangle with corners `a`, `b`, `c`, stored as `a`, `b - a`, `c - a` (the arithmetic the
    /// CPU walks use, so both sides intersect the same edges).
    pub fn new([a, b, c]: [glam::Vec3; 3]) -> TracedTriangle {
        TracedTriangle {
            p0: a.extend(0.0).into(),
            e1: (b - a).extend(0.0).into(),
            e2: (c - a).extend(0.0).into(),
        }
    }

    /// `triangles` in the order of the BVH's leaves, as the shaders index them.
    pub fn in_leaf_order(bvh: &bvh::Bvh, triangles: &[[glam::Vec3; 3]]) -> Vec<TracedTriangle> {
        bvh.order
            .iter()
            .map(|&t| TracedTriangle::new(triangles[t as usize]))
            .collect()
    }
}
