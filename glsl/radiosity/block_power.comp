#version 460
// Every block's unshot power: the sum over its patches of area x (|r| + |g| + |b|) of the
// unshot radiosity, as solve.rs measures it.
#include "radiosity/shooting.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Patches { Patch items[]; } patches;
layout(set = 0, binding = 1) readonly buffer State { Radiosity items[]; } radiosity;
layout(set = 0, binding = 2) readonly buffer Blocks { Block items[]; } blocks;
layout(set = 0, binding = 3) readonly buffer Members { uint items[]; } members;
layout(set = 0, binding = 4) readonly buffer Shots { Shot shot; } shots;
layout(set = 0, binding = 5) writeonly buffer BlockPower { float items[]; } block_power;

void main() {
    uint b = gl_GlobalInvocationID.x;
    if (b >= push.block_count || shots.shot.state.y != 0u) {
        return;
    }
    uvec4 range = blocks.items[b].range;
    float sum = 0.0;
    for (uint i = 0u; i < range.y; ++i) {
        uint k = members.items[range.x + i];
        vec3 u = abs(radiosity.items[k].unshot.rgb);
        sum += (u.r + u.g + u.b) * patches.items[k].centre.w;
    }
    block_power.items[b] = sum;
}
