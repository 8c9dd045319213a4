// The compressed SH light-map's look-ups (the Ca3D-Engine thesis listings 3-5, section 5.8), shared by
// compressed.frag and the check kernel glsl/tests/shl_vq_check.comp. Needs GROUPS, ENCODED and
// shade_rep(uint) defined before it is included.
//
// A 16-bit index per texel (R low byte, G high byte) into the 256-row table of representatives,
// fetched with integer coordinates (never filtered: neighbouring indices are unrelated vectors).

layout(set = 0, binding = 3) uniform usampler2D indices;
layout(set = 0, binding = 6) uniform sampler2D table;

uint index_at(ivec2 p) {
    ivec2 size = textureSize(indices, 0);
    uvec4 t = texelFetch(indices, clamp(p, ivec2(0), size - 1), 0);
    return t.r | (t.g << 8);
}

// Representative r's group k lies at x = (r >> 8) * GROUPS + k, y = r & 255.
vec4 group_of(uint r, int k) {
    vec4 t = texelFetch(table, ivec2(int(r >> 8u) * GROUPS + k, int(r & 255u)), 0);
    return ENCODED ? 4.0 * (t - 0.5) : t;
}

// The "bilinear by multisampling" filter: four taps at (+-1/4, +-1/4) texels around `st` (texel
// units), decoded and averaged, with one look-up when all four indices agree.
vec3 shade_filtered(vec2 st) {
    uint i0 = index_at(ivec2(floor(st + vec2(-0.25, -0.25))));
    uint i1 = index_at(ivec2(floor(st + vec2(0.25, -0.25))));
    uint i2 = index_at(ivec2(floor(st + vec2(-0.25, 0.25))));
    uint i3 = index_at(ivec2(floor(st + vec2(0.25, 0.25))));
    if (i0 == i1 && i0 == i2 && i0 == i3) {
        return shade_rep(i0);
    }
    return 0.25 * (shade_rep(i0) + shade_rep(i1) + shade_rep(i2) + shade_rep(i3));
}
