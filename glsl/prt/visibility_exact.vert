#version 460
// Phase 1 of the corrected raster baker (src/lighting/prt/raster.rs): each occluder triangle
// drawn into every vertex's tile as a conservative rectangle around its projection, and each
// pixel kept only where the ray along the pixel's direction hits the triangle
// (visibility_exact.frag). The document projects corners and rasterises straight edges between
// them, which misses the curved edges of large triangles and of those crossing the horizon
// (digest 1.4 item 4); here coverage is exact at every pixel centre.
//
// The mappings move no point farther than its angular distance (their Jacobians are at most 1
// on the front hemisphere), and every point of a spherical triangle lies within its longest
// edge's angle of each corner: the rectangle is the intersection of the squares of that
// half-size around the projected corners, plus one pixel. A triangle crossing the tangent plane
// gets the whole tile; one wholly behind it, nothing.

#include "prt/mapping.glsl"

layout(constant_id = 0) const int MAPPING = 0;
layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 3) const int TILES_PER_ROW = 32;
layout(constant_id = 4) const int BATCH = 1024;
layout(constant_id = 5) const int ATLAS_W = 1024;
layout(constant_id = 6) const int ATLAS_H = 1024;

struct Triangle {
    vec4 p[3];
};

layout(set = 0, binding = 0) readonly buffer Receivers { PrtReceiver items[]; } receivers;
layout(set = 0, binding = 1) readonly buffer Triangles { Triangle items[]; } triangles;

layout(location = 0) flat out vec3 out_a;  // the corners in the vertex camera's frame
layout(location = 1) flat out vec3 out_b;
layout(location = 2) flat out vec3 out_c;
layout(location = 3) flat out ivec2 out_tile;

const vec2 QUAD[6] = vec2[6](vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));

void main() {
    int slot = gl_InstanceIndex % BATCH;
    ivec2 tile = ivec2(slot % TILES_PER_ROW, slot / TILES_PER_ROW) * TILE;
    PrtReceiver r = receivers.items[gl_InstanceIndex];
    Triangle tri = triangles.items[gl_VertexIndex / 6];
    vec3 l[3];
    for (int k = 0; k < 3; ++k) {
        vec3 e = tri.p[k].xyz - r.position.xyz;
        l[k] = vec3(dot(e, r.tangent.xyz), dot(e, r.bitangent.xyz), dot(e, r.normal.xyz));
    }
    out_a = l[0];
    out_b = l[1];
    out_c = l[2];
    out_tile = tile;
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
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the view volume: nothing drawn
        return;
    }
    vec2 st = mix(lo, hi, QUAD[gl_VertexIndex % 6]);
    vec2 pixel = vec2(tile) + (st + 1.0) * 0.5 * float(TILE);
    gl_Position = vec4(pixel.x / float(ATLAS_W) * 2.0 - 1.0, pixel.y / float(ATLAS_H) * 2.0 - 1.0, 0.5, 1.0);
}
