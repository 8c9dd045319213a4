#version 460
// Compressed SH light-maps (the Ca3D-Engine thesis listings 3-5): the index map and the representative table
// (sh_lightmap/vq.glsl), optionally with the 4-tap filter of section 5.8.
#include "sh_lightmap/shl.glsl"

vec3 shade_rep(uint r);
#include "sh_lightmap/vq.glsl"

vec3 shade_rep(uint r) {
    vec3 sum = vec3(0.0);
    for (int k = 0; k < GROUPS; ++k) {
        sum += shade_group(group_of(r, k), k);
    }
    return sum;
}

void main() {
    vec2 st = in_lightmap_uv * vec2(textureSize(indices, 0));
    uint centre = index_at(ivec2(floor(st)));
    vec3 sum = FILTER ? shade_filtered(st) : shade_rep(centre);
    vec3 index_colour = vec3(float(centre & 255u), float(centre >> 8u), 0.0) / 255.0;
    finish(sum, texelFetch(table, ivec2(int(centre >> 8u) * GROUPS, int(centre & 255u)), 0).rgb, index_colour);
}
