#version 460
// Before the corrected raster baker draws (src/lighting/prt/raster.rs): per pair of a batch's
// receiver and a chunk's occluder triangle, the conservative rectangle that
// visibility_exact.vert draws, and only the pairs with something to draw appended to a list the
// draw then reads indirectly. Computing the rectangle here once, instead of in each of its six
// vertex invocations, and dropping the triangles behind a vertex before they reach the
// rasteriser leaves the image as it was: the coverage test per pixel is unchanged
// (visibility_exact.frag). On lavapipe the vertex stage runs on one thread and this pass on all.
//
// The mappings move no point farther than its angular distance (their Jacobians are at most 1
// on the front hemisphere), and every point of a spherical triangle lies within its longest
// edge's angle of each corner: the rectangle is the intersection of the squares of that
// half-size around the projected corners, plus one pixel. A triangle crossing the tangent plane
// gets the whole tile; one wholly behind it, nothing.

#include "prt/mapping.glsl"

layout(local_size_x = 64) in;

layout(constant_id = 0) const int MAPPING = 0;
layout(constant_id = 2) const int TILE = 32;

struct Triangle {
    vec4 p[3];
};

// One rectangle to draw: the triangle's corners in the vertex camera's frame (w of the first:
// the receiver's slot, as bits) and the rectangle in the tile's [-1, 1]^2 (lo, hi).
struct Rect {
    vec4 a;
    vec4 b;
    vec4 c;
    vec4 rect;
};

layout(set = 0, binding = 0) readonly buffer Receivers { PrtReceiver items[]; } receivers;
layout(set = 0, binding = 1) readonly buffer Triangles { Triangle items[]; } triangles;
layout(set = 0, binding = 2) writeonly buffer Rects { Rect items[]; } rects;
// VkDrawIndexedIndirectCommand: indexCount counts six indices (two triangles over four
// vertices) per appended rectangle.
layout(set = 0, binding = 3) buffer Command { uint index_count; uint instance_count; uint first_index; int vertex_offset; uint first_instance; } command;

layout(push_constant) uniform Chunk {
    uint first_slot;      // the batch's first receiver slot
    uint receivers;       // the batch's real receivers (padding slots are never drawn)
    uint first_triangle;  // the chunk's first triangle
    uint triangle_count;  // triangles in the chunk
} chunk;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= chunk.receivers * chunk.triangle_count) {
        return;
    }
    uint slot = chunk.first_slot + i / chunk.triangle_count;
    uint triangle = chunk.first_triangle + i % chunk.triangle_count;
    PrtReceiver r = receivers.items[slot];
    Triangle tri = triangles.items[triangle];
    vec3 l[3];
    for (int k = 0; k < 3; ++k) {
        vec3 e = tri.p[k].xyz - r.position.xyz;
        l[k] = vec3(dot(e, r.tangent.xyz), dot(e, r.bitangent.xyz), dot(e, r.normal.xyz));
    }
    vec2 lo = vec2(-1.0);
    vec2 hi = vec2(1.0);
    bool behind = l[0].z <= 0.0 && l[1].z <= 0.0 && l[2].z <= 0.0;
    bool front = l[0].z > 0.0 && l[1].z > 0.0 && l[2].z > 0.0;
    if (front) {
        vec3 d[3] = vec3[3](normalize(l[0]), normalize(l[1]), normalize(l[2]));
        float c = min(min(dot(d[0], d[1]), dot(d[1], d[2])), dot(d[2], d[0]));
        float delta = acos(clamp(c, -1.0, 1.0)) + 2.0 / float(TILE);
        for (int k = 0; k < 3; ++k) {
            vec2 p = prt_project(MAPPING, d[k]);
            lo = max(lo, p - delta);
            hi = min(hi, p + delta);
        }
        lo = max(lo, vec2(-1.0));
        hi = min(hi, vec2(1.0));
    }
    if (behind || any(greaterThan(lo, hi))) {
        return;
    }
    uint at = atomicAdd(command.index_count, 6u) / 6u;
    rects.items[at] = Rect(vec4(l[0], uintBitsToFloat(slot)), vec4(l[1], 0.0), vec4(l[2], 0.0), vec4(lo, hi));
}
