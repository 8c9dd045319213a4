#version 460
// The BSP shadow system's relighting (Ridderhof 2002): colour(v) = sum over the active lights of
// s_l * C_l(v), one invocation per segment vertex. The matrix is light-major, so neighbouring
// invocations read neighbouring words. The loop runs once per active light: the method refuses
// more lights than llvmpipe's 65,535 loop iterations per invocation allow.

layout(local_size_x = 64) in;

// f16 storage: three halves per vertex and light, two to a word.
layout(constant_id = 0) const bool HALF = false;

layout(set = 0, binding = 0) readonly buffer Matrix { uint words[]; } matrix;
// header.x: active lights, header.y: vertices; then (light index, scale bits) per active light.
layout(set = 0, binding = 1) readonly buffer Active { uvec4 header; uvec2 items[]; } enabled;
layout(set = 0, binding = 2) writeonly buffer Colours { vec4 c[]; } colours;

float entry(uint e) {
    if (HALF) {
        vec2 pair = unpackHalf2x16(matrix.words[e >> 1u]);
        return (e & 1u) == 0u ? pair.x : pair.y;
    }
    return uintBitsToFloat(matrix.words[e]);
}

void main() {
    uint v = gl_GlobalInvocationID.x;
    uint vertices = enabled.header.y;
    if (v >= vertices) {
        return;
    }
    vec3 sum = vec3(0.0);
    uint count = enabled.header.x;
    for (uint i = 0u; i < count; ++i) {
        uvec2 item = enabled.items[i];
        uint e = 3u * (item.x * vertices + v);
        // Channels written out: a loop here would count against llvmpipe's iteration limit.
        sum += uintBitsToFloat(item.y) * vec3(entry(e), entry(e + 1u), entry(e + 2u));
    }
    colours.c[v] = vec4(sum, 1.0);
}
