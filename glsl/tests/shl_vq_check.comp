#version 460
// Check kernel for the compressed SH light-map look-ups (glsl/sh_lightmap/vq.glsl), used by
// tests/sh_lightmap_gpu.rs. MODE 0: per texel of a 256 x 256 index map, the index read back by
// index_at and the index a LINEAR sampler gives at the seed's texel-edge coordinates (2 uints).
// MODE 1: per (representative, group), the decoded group (4 floats). MODE 2: the 4-tap filter
// along x at 256 positions over texels 2..6 of row 0 (1 float: shade_filtered's red).
layout(local_size_x = 64) in;

layout(constant_id = 0) const int BANDS = 4;
layout(constant_id = 1) const bool ENCODED = true;
layout(constant_id = 2) const int MODE = 0;
layout(constant_id = 3) const int COUNT = 65536;

const int GROUPS = (BANDS * BANDS + 3) / 4;

vec3 shade_rep(uint r);
#include "sh_lightmap/vq.glsl"

vec3 shade_rep(uint r) {
    return vec3(group_of(r, 0).x);
}

layout(set = 0, binding = 7) uniform sampler2D indices_linear;
layout(set = 0, binding = 8) writeonly buffer Result { uint items[]; } result;

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= uint(COUNT)) {
        return;
    }
    if (MODE == 0) {
        ivec2 p = ivec2(int(id & 255u), int(id >> 8));
        result.items[2u * id] = index_at(p);
        // The seed's addressing (texel edges) through a filtering sampler.
        vec4 t = texture(indices_linear, (vec2(p) + vec2(0.0, 0.5)) / 256.0);
        result.items[2u * id + 1u] = uint(round(t.r * 255.0)) | (uint(round(t.g * 255.0)) << 8);
    } else if (MODE == 1) {
        uint r = id / uint(GROUPS);
        int k = int(id % uint(GROUPS));
        vec4 g = group_of(r, k);
        for (int c = 0; c < 4; ++c) {
            result.items[4u * id + uint(c)] = floatBitsToUint(g[c]);
        }
    } else {
        float x = 2.0 + 4.0 * (float(id) + 0.5) / float(COUNT);
        result.items[id] = floatBitsToUint(shade_filtered(vec2(x, 0.5)).r);
    }
}
