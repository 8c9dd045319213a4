#version 460
// Area-light emitters (and any other scene object) drawn with their emission only.
#include "common/frame.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "common/scene.glsl"

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    out_world = world.xyz;
    out_normal = transpose(inverse(mat3(draw.model))) * in_normal;
    gl_Position = frame.view_proj * world;
}
