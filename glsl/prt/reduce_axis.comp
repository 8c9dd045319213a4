#version 460
// Phase 3 of Staniszewski 2005's baker as the document runs it (src/lighting/prt/raster.rs, Listing
// 2.6): one of the four passes that each sum TAPS neighbours along one axis (8, 4 along x, then
// 8, 4 along y for 32x32 tiles), read with integer fetches (the document's offsets land on
// texel edges, digest 1.6). The fourth pass is reduce_last.comp.

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 11) const int TAPS = 8;
layout(constant_id = 12) const int AXIS = 0;  // 0: x, 1: y

layout(set = 0, binding = 0, rgba32f) uniform readonly image2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

void main() {
    ivec2 o = ivec2(gl_GlobalInvocationID.xy);
    ivec2 in_size = imageSize(src);
    ivec2 out_size = AXIS == 0 ? ivec2(in_size.x / TAPS, in_size.y) : ivec2(in_size.x, in_size.y / TAPS);
    if (o.x >= out_size.x || o.y >= out_size.y) {
        return;
    }
    vec4 sum = vec4(0.0);
    for (int k = 0; k < TAPS; ++k) {
        sum += imageLoad(src, AXIS == 0 ? ivec2(o.x * TAPS + k, o.y) : ivec2(o.x, o.y * TAPS + k));
    }
    imageStore(dst, o, sum);
}
