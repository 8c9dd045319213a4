#version 460
// Emission of the material (one-sided emitters are black from behind), nothing else.
#include "common/frame.glsl"
#include "common/scene.glsl"

layout(set = 0, binding = 2) readonly buffer Materials { Material items[]; } materials;

layout(location = 0) in vec3 in_world;
layout(location = 1) in vec3 in_normal;
layout(location = 0) out vec4 out_radiance;

void main() {
    Material m = materials.items[draw.material];
    vec3 emission = m.emission.rgb;
    if (m.maps.y != 0u && dot(in_normal, frame.camera_pos.xyz - in_world) < 0.0) emission = vec3(0.0);
    out_radiance = vec4(emission, 1.0);
}
