#version 460
// The light-map base term: static triangles in object space with their light-map and material
// texture coordinates (src/lighting/radiosity/mod.rs, `LightmapVertex`). The position is
// transformed exactly as every method's scene vertex shader does it, so a direct term drawn over
// this base finds the same depths.
#include "common/frame.glsl"
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_lightmap_uv;
layout(location = 3) in vec2 in_uv;

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_lightmap_uv;
layout(location = 3) out vec2 out_uv;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    out_world = world.xyz;
    out_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    out_lightmap_uv = in_lightmap_uv;
    out_uv = in_uv;
    gl_Position = frame.view_proj * world;
}
