#version 460
// Virtualised light sources: every segment its own three vertices (never shared, so the
// boundary between two segments with different light sets shows, as in the thesis), in world
// space, with the index of its light set (the segment's, or the segment vertex's), its normal
// and material, its specular colour and exponent last (src/lighting/vls/mod.rs, `SegmentVertex`).
#include "vls/vls.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec3 in_albedo;
layout(location = 3) in vec3 in_emission;
layout(location = 4) in uint in_set;
layout(location = 5) in vec4 in_specular;

layout(location = 0) out vec3 out_world;
layout(location = 1) flat out vec3 out_normal;
layout(location = 2) flat out vec3 out_albedo;
layout(location = 3) flat out vec3 out_emission;
layout(location = 4) flat out uint out_set;
// Per vertex: the vertex's direct light, interpolated (Gouraud, as fixed-function OpenGL).
layout(location = 5) out vec3 out_direct;
layout(location = 6) flat out vec4 out_specular;

void main() {
    out_world = in_position;
    out_normal = in_normal;
    out_albedo = in_albedo;
    out_emission = in_emission;
    out_set = in_set;
    out_specular = in_specular;
    out_direct = vec3(0.0);
    if (PER_VERTEX != 0u && (TERMS & 2u) != 0u) {
        out_direct = vls_direct(in_set, in_position, facing_normal(in_normal, in_position), in_albedo, in_specular);
    }
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
