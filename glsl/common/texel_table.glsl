// Read-only arrays as RGBA32F images used as tables (src/reference/texel_table.rs says why):
// element i of 16 * K bytes is texels K*i .. K*i + K - 1, TABLE_WIDTH texels a row.
#ifndef PENUMBRA_COMMON_TEXEL_TABLE_GLSL
#define PENUMBRA_COMMON_TEXEL_TABLE_GLSL

// texel_table::TABLE_WIDTH.
const uint TABLE_WIDTH = 4096u;

vec4 table_texel(sampler2D table, uint i) {
    return texelFetch(table, ivec2(i % TABLE_WIDTH, i / TABLE_WIDTH), 0);
}

#endif
