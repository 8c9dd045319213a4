#version 460
// Phase 2 of Staniszewski 2005's baker (src/lighting/prt/raster.rs), Listing 2.5: per atlas pixel,
// visibility x weight x four SH basis functions of the pixel's world direction (coefficients
// 4 GROUP .. 4 GROUP + 3). The weight is cos * solid angle of the pixel for the mapping (exact),
// or the document's 8-bit cosine texture times 2 pi / T^2 (legacy). The direction comes from the
// mapping's analytic inverse, the SH from sh.glsl (the document's colour-coded sphere and
// 32x64 basis textures carry half-texel errors, digest 3.2 item 2).

#include "common/sh.glsl"
#include "prt/mapping.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 0) const int MAPPING = 0;
layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 10) const int GROUP = 0;
// 1: the direction is the sphere's colour and the basis comes from Listing 2.2's textures
// (32 rows of theta = k pi / 31, 64 columns of phi = l 2 pi / 63, sampled linearly at the
// colour: the document's half-texel misalignment included); 0: the mapping's inverse, sh.glsl.
layout(constant_id = 14) const int SPHERE = 0;

layout(set = 0, binding = 0) readonly buffer Receivers { PrtReceiver items[]; } receivers;
// B: visibility; R, G: the colour-coded sphere's phi / 2 pi and theta / pi (faithful directions).
layout(set = 0, binding = 1, rgba32f) uniform readonly image2D visibility;
layout(set = 0, binding = 2) readonly buffer Weights { float items[]; } weights;
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2D product;
// The batch's first receiver slot (a multiple of BATCH).
layout(set = 0, binding = 4) readonly buffer Batch { uint base; } batch;
// Listing 2.2's basis textures, one layer per group of four coefficients.
layout(set = 0, binding = 5) uniform sampler2DArray sh_basis;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(product);
    if (p.x >= size.x || p.y >= size.y) {
        return;
    }
    ivec2 tile = p / TILE;
    ivec2 q = p - tile * TILE;
    int slot = tile.y * TILES_PER_ROW + tile.x;
    float w = weights.items[q.y * TILE + q.x];
    vec4 value = vec4(0.0);
    if (slot < BATCH && w != 0.0) {
        vec4 texel = imageLoad(visibility, p);
        vec4 basis;
        if (SPHERE == 1) {
            basis = textureLod(sh_basis, vec3(texel.rg, float(GROUP)), 0.0);
        } else {
            PrtReceiver r = receivers.items[batch.base + uint(slot)];
            vec2 st = -1.0 + (2.0 * vec2(q) + 1.0) / float(TILE);
            vec3 d = prt_unproject_clamped(MAPPING, st);
            vec3 world = r.tangent.xyz * d.x + r.bitangent.xyz * d.y + r.normal.xyz * d.z;
            float y[16];
            sh_eval16(sh_world_to_sh(world), y);
            basis = vec4(y[4 * GROUP], y[4 * GROUP + 1], y[4 * GROUP + 2], y[4 * GROUP + 3]);
        }
        value = texel.b * w * basis;
    }
    imageStore(product, p, value);
}
