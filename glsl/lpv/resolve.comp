#version 460
// Turns the fixed-point injection sums into the first wavefront and the accumulation (and the
// blocking sums into the geometry volume), and clears the sums for the next frame.
#include "lpv/volume.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 1) buffer FixedLight { int v[]; } fixed_light;
layout(set = 0, binding = 2) buffer FixedBlocking { int v[]; } fixed_blocking;
layout(set = 0, binding = 3) writeonly buffer Wavefront { uint w[]; } wavefront;
layout(set = 0, binding = 4) writeonly buffer Accumulation { uint w[]; } accumulation;
layout(set = 0, binding = 5) writeonly buffer Blocking { vec4 b[]; } blocking;

void main() {
    uint cell = gl_GlobalInvocationID.x;
    if (cell >= uint(volume.size.w)) {
        return;
    }
    for (uint ch = 0u; ch < 3u; ++ch) {
        vec4 c;
        for (uint k = 0u; k < 4u; ++k) {
            uint i = (cell * 3u + ch) * 4u + k;
            c[k] = float(fixed_light.v[i]) * volume.units.y * volume.scale.x;
            fixed_light.v[i] = 0;
        }
        uint s = slot(cell, ch);
        SET_STORE(wavefront, s, c);
        SET_STORE(accumulation, s, c);
    }
    vec4 b;
    for (uint k = 0u; k < 4u; ++k) {
        b[k] = float(fixed_blocking.v[cell * 4u + k]) * volume.units.w;
        fixed_blocking.v[cell * 4u + k] = 0;
    }
    blocking.b[cell] = b;
}
