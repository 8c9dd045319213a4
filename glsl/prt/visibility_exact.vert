#version 460
// Phase 1 of the corrected raster baker (src/lighting/prt/raster.rs): each occluder triangle
// drawn into a vertex's tile as the conservative rectangle around its projection that
// cull.comp computed and listed, and each pixel kept only where the ray along the pixel's
// direction hits the triangle (visibility_exact.frag). The document projects corners and
// rasterises straight edges between them, which misses the curved edges of large triangles and
// of those crossing the horizon (digest 1.4 item 4); here coverage is exact at every pixel
// centre. Four vertices (two indexed triangles) per listed rectangle, drawn indirectly.

#include "prt/mapping.glsl"

layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 5) const int ATLAS_W = 1024;
layout(constant_id = 6) const int ATLAS_H = 1024;

// As cull.comp wrote it.
struct Rect {
    vec4 a;
    vec4 b;
    vec4 c;
    vec4 rect;
};

layout(set = 0, binding = 2) readonly buffer Rects { Rect items[]; } rects;

layout(location = 0) flat out vec3 out_a;  // the corners in the vertex camera's frame
layout(location = 1) flat out vec3 out_b;
layout(location = 2) flat out vec3 out_c;
layout(location = 3) flat out ivec2 out_tile;

const vec2 CORNER[4] = vec2[4](vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));

void main() {
    Rect rect = rects.items[gl_VertexIndex / 4];
    // Batches start at multiples of BATCH, so the tile is the slot's place in its batch.
    int slot = int(floatBitsToUint(rect.a.w)) % BATCH;
    ivec2 tile = ivec2(slot % TILES_PER_ROW, slot / TILES_PER_ROW) * TILE;
    out_a = rect.a.xyz;
    out_b = rect.b.xyz;
    out_c = rect.c.xyz;
    out_tile = tile;
    vec2 st = mix(rect.rect.xy, rect.rect.zw, CORNER[gl_VertexIndex % 4]);
    vec2 pixel = vec2(tile) + (st + 1.0) * 0.5 * float(TILE);
    gl_Position = vec4(pixel.x / float(ATLAS_W) * 2.0 - 1.0, pixel.y / float(ATLAS_H) * 2.0 - 1.0, 0.5, 1.0);
}
