#version 460
// The BSP shadow system's relighting (Ridderhof 2002) over the sparse layout: colour(v) = sum over
// v's non-zero entries of s_l * C_l(v), one invocation per segment vertex. A light that does
// not reach a vertex (outside its cone, facing away, in shadow) has no entry there, so the
// work is the matrix's non-zero count, not vertices x lights. Lights below the threshold have
// scale 0 and add nothing. A row holds at most one entry per light: the method refuses more
// lights than llvmpipe's 65,535 loop iterations per invocation allow.

layout(local_size_x = 64) in;

// f16 storage: (light | red << 16, green | blue << 16) per entry; f32: (light, r, g, b).
layout(constant_id = 0) const bool HALF = false;

layout(set = 0, binding = 0) readonly buffer Matrix { uint words[]; } matrix;
// Row v's entries are [starts[v], starts[v + 1]).
layout(set = 0, binding = 1) readonly buffer Rows { uint starts[]; } rows;
// header.x: lights, header.y: vertices; then every light's scale bits.
layout(set = 0, binding = 2) readonly buffer Scales { uvec4 header; uint items[]; } enabled;
layout(set = 0, binding = 3) writeonly buffer Colours { vec4 c[]; } colours;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= enabled.header.y) {
        return;
    }
    vec3 sum = vec3(0.0);
    uint end = rows.starts[v + 1u];
    for (uint e = rows.starts[v]; e < end; ++e) {
        uint light;
        vec3 c;
        if (HALF) {
            uint a = matrix.words[2u * e];
            uint b = matrix.words[2u * e + 1u];
            light = a & 0xffffu;
            c = vec3(unpackHalf2x16(a).y, unpackHalf2x16(b));
        } else {
            light = matrix.words[4u * e];
            c = vec3(uintBitsToFloat(matrix.words[4u * e + 1u]), uintBitsToFloat(matrix.words[4u * e + 2u]), uintBitsToFloat(matrix.words[4u * e + 3u]));
        }
        sum += uintBitsToFloat(enabled.items[light]) * c;
    }
    colours.c[v] = vec4(sum, 1.0);
}
