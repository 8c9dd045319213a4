#version 460
// The fourth of the document's reduction passes (src/lighting/prt/raster.rs; the first three
// are reduce_axis.comp): TAPS texels along y summed with integer fetches into one texel per
// tile, 4 coefficients, written to the receiver's slot. The empty vertices that pad a batch are
// never written back.

#include "prt/mapping.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 10) const int GROUP = 0;
layout(constant_id = 11) const int TAPS = 4;

layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 2) readonly buffer Receivers { PrtReceiver items[]; } receivers;
layout(set = 0, binding = 3) buffer Coefficients { vec4 items[]; } coefficients;
layout(set = 0, binding = 4) readonly buffer Batch { uint base; } batch;

void main() {
    ivec2 o = ivec2(gl_GlobalInvocationID.xy);
    ivec2 in_size = imageSize(src);
    if (o.x >= in_size.x || o.y >= in_size.y / TAPS) {
        return;
    }
    vec4 sum = vec4(0.0);
    for (int k = 0; k < TAPS; ++k) {
        sum += imageLoad(src, ivec2(o.x, o.y * TAPS + k));
    }
    int slot = o.y * TILES_PER_ROW + o.x;
    if (slot < BATCH) {
        uint r = batch.base + uint(slot);
        if (receivers.items[r].position.w != 0.0) {
            coefficients.items[r * 4u + uint(GROUP)] = sum;
        }
    }
}
