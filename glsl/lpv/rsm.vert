#version 460
// The reflective shadow map: the scene from the light (orthographic for the sun, perspective
// for a spot light).
#include "lpv/volume.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "common/scene.glsl"

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    out_world = world.xyz;
    out_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    out_uv = in_uv;
    gl_Position = volume.light_view_proj * world;
}
