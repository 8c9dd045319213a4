// Read-only arrays as RGBA32UI images used as tables (src/reference/texel_table.rs says why):
// element i of 16 * K bytes is texels K*i .. K*i + K - 1, TABLE_WIDTH texels a row. Floats are
// stored as their bits.
#ifndef PENUMBRA_COMMON_TEXEL_TABLE_GLSL
#define PENUMBRA_COMMON_TEXEL_TABLE_GLSL

// texel_table::TABLE_WIDTH.
const uint TABLE_WIDTH = 4096u;

uvec4 table_texel(usampler2D table, uint i) {
    return texelFetch(table, ivec2(i % TABLE_WIDTH, i / TABLE_WIDTH), 0);
}

vec4 table_vec4(usampler2D table, uint i) {
    return uintBitsToFloat(table_texel(table, i));
}

// Value i of a table of 4-byte values packed four a texel.
uint table_packed(usampler2D table, uint i) {
    uvec4 t = table_texel(table, i / 4u);
    uint c = i % 4u;
    return c == 0u ? t.x : (c == 1u ? t.y : (c == 2u ? t.z : t.w));
}

#endif
