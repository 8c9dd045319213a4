#version 460
// The scene's surfaces as the camera sees them, for every method that shades the scene's own
// draws per pixel (forward, clustered, the LPV composite): world position, normal, texture
// coordinates and tangent of the interleaved vertex.
#include "common/frame.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "common/scene.glsl"

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) out vec4 out_tangent;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    out_world = world.xyz;
    out_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    out_uv = in_uv;
    out_tangent = vec4(mat3(draw.model) * in_tangent.xyz, in_tangent.w);
    gl_Position = frame.view_proj * world;
}
