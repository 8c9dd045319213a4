// Read-only arrays as RGBA32UI storage images used as tables, read with imageLoad
// (src/raytrace/texel_table.rs says why):
// element i of 16 * K bytes is texels K*i .. K*i + K - 1, TABLE_WIDTH texels a row. Floats are
// stored as their bits.
#ifndef PENUMBRA_COMMON_TEXEL_TABLE_GLSL
#define PENUMBRA_COMMON_TEXEL_TABLE_GLSL

// texel_table::TABLE_WIDTH.
const uint TABLE_WIDTH = 4096u;

// Macros rather than functions: a readonly image cannot be passed to a parameter without the
// same qualifier, and every table is declared `layout(rgba32ui) readonly uniform uimage2D`.
#define table_texel(table, i) imageLoad(table, ivec2((i) % TABLE_WIDTH, (i) / TABLE_WIDTH))
#define table_vec4(table, i) uintBitsToFloat(table_texel(table, i))

uint table_component(uvec4 t, uint c) {
    return c == 0u ? t.x : (c == 1u ? t.y : (c == 2u ? t.z : t.w));
}

// Value i of a table of 4-byte values packed four a texel.
#define table_packed(table, i) table_component(table_texel(table, (i) / 4u), (i) % 4u)

#endif
