#version 460
// Phase 3 of Staniszewski 2005's baker as one compute dispatch (src/lighting/prt/raster.rs): one
// workgroup per tile sums its T x T pixels (each invocation a strided share, then a tree in
// shared memory) and writes the 4 coefficients to the receiver's slot; padding is skipped.

#include "prt/mapping.glsl"

layout(local_size_x = 64) in;

layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 10) const int GROUP = 0;

layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 2) readonly buffer Receivers { PrtReceiver items[]; } receivers;
layout(set = 0, binding = 3) buffer Coefficients { vec4 items[]; } coefficients;
layout(set = 0, binding = 4) readonly buffer Batch { uint base; } batch;

shared vec4 partial[64];

void main() {
    int slot = int(gl_WorkGroupID.x);
    uint lane = gl_LocalInvocationID.x;
    ivec2 origin = ivec2(slot % TILES_PER_ROW, slot / TILES_PER_ROW) * TILE;
    vec4 sum = vec4(0.0);
    for (int k = int(lane); k < TILE * TILE; k += 64) {
        sum += imageLoad(src, origin + ivec2(k % TILE, k / TILE));
    }
    partial[lane] = sum;
    barrier();
    for (uint stride = 32u; stride > 0u; stride >>= 1) {
        if (lane < stride) {
            partial[lane] += partial[lane + stride];
        }
        barrier();
    }
    if (lane == 0u && slot < BATCH) {
        uint r = batch.base + uint(slot);
        if (receivers.items[r].position.w != 0.0) {
            coefficients.items[r * 4u + uint(GROUP)] = partial[0];
        }
    }
}
