#version 460
// The light-map base term: static triangles in world space with their light-map and material
// texture coordinates (src/lighting/radiosity/mod.rs, `LightmapVertex`).
#include "common/frame.glsl"

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_lightmap_uv;
layout(location = 3) in vec2 in_uv;

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_lightmap_uv;
layout(location = 3) out vec2 out_uv;

void main() {
    out_world = in_world;
    out_normal = in_normal;
    out_lightmap_uv = in_lightmap_uv;
    out_uv = in_uv;
    gl_Position = frame.view_proj * vec4(in_world, 1.0);
}
