#version 460
// Native SH light-maps (the Ca3D-Engine thesis listing 2): GROUPS layers of 4 coefficients, filtered by the
// sampler (bilinear: the decoding is linear, so filtering the stored values is exact).
#include "sh_lightmap/shl.glsl"

layout(set = 0, binding = 3) uniform sampler2DArray layers;

void main() {
    vec3 sum = vec3(0.0);
    for (int k = 0; k < GROUPS; ++k) {
        sum += shade_group(decode(texture(layers, vec3(in_lightmap_uv, float(k)))), k);
    }
    finish(sum, texture(layers, vec3(in_lightmap_uv, 0.0)).rgb, vec3(0.0));
}
