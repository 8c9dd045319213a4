#version 460
// Clustered pass 1b: for each coarse tile (COARSE x COARSE screen tiles), the lights whose
// bounding sphere reaches its column through the eye, as a bit mask of WORDS words. The
// assignment (assign.comp) then tests against each of its columns only the lights of its coarse
// tile instead of every light: the test of every light against every column grew with the light
// count and was about 40 % of the assignment at 1,024 lights. The coarse column holds each of its
// columns, so a light reaching a column reaches it too: the assignment is the same. One
// workgroup per coarse tile, a word (32 lights) per invocation: at most WORDS / 64 * 32 = 128
// loop iterations an invocation.
#define CLUSTERS_BINDING 0
#include "clustered/clusters.glsl"

layout(local_size_x = 64) in;

// Matches `MAX_LIGHTS` in src/lighting/clustered/mod.rs.
const uint MAX_LIGHTS = 8192u;
const uint WORDS = MAX_LIGHTS / 32u;

layout(set = 0, binding = 1) readonly buffer Volumes { LightVolume items[]; } volumes;
layout(set = 0, binding = 2) writeonly buffer Coarse { uint m[]; } coarse;

void main() {
    uint id = gl_WorkGroupID.x;
    uint across = coarse_columns();
    uvec2 t0 = uvec2(id % across, id / across) * COARSE;
    if (t0.y >= clusters.grid.y) {
        return;
    }
    uvec2 t1 = min(t0 + COARSE, clusters.grid.xy);
    vec4 planes[4] = span_planes(t0, t1);
    uint light_count = min(clusters.lights.x, MAX_LIGHTS);
    uint words = (light_count + 31u) / 32u;
    for (uint w = gl_LocalInvocationIndex; w < words; w += 64u) {
        uint bits = 0u;
        uint last = min(32u, light_count - w * 32u);
        for (uint b = 0u; b < last; ++b) {
            if (reaches_column(volumes.items[w * 32u + b].sphere, planes)) {
                bits |= 1u << b;
            }
        }
        coarse.m[id * WORDS + w] = bits;
    }
}
