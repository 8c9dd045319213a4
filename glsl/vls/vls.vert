#version 460
// Virtualised light sources: every segment its own three vertices (never shared, so the
// boundary between two segments with different light sets shows, as in the thesis), in world
// space, with the segment's id, normal and material (src/lighting/vls/mod.rs, `SegmentVertex`).
#include "common/frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec3 in_albedo;
layout(location = 3) in vec3 in_emission;
layout(location = 4) in uint in_segment;

layout(location = 0) out vec3 out_world;
layout(location = 1) flat out vec3 out_normal;
layout(location = 2) flat out vec3 out_albedo;
layout(location = 3) flat out vec3 out_emission;
layout(location = 4) flat out uint out_segment;

void main() {
    out_world = in_position;
    out_normal = in_normal;
    out_albedo = in_albedo;
    out_emission = in_emission;
    out_segment = in_segment;
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
