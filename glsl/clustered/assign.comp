#version 460
// Clustered pass 2: the lights of every cluster, one workgroup per screen tile. The workgroup
// first keeps the lights whose bounding sphere reaches the tile's column (its four side planes
// and the near and far depths) in a shared bit mask; then each invocation takes a slice, tests
// the kept lights' spheres against that cluster's box in light order, and writes the first
// max_per_cluster hits to the cluster's slots. The count written is every hit, so that overflow
// can be read back rather than lost. Loop bounds: lights/64 + (slices/64) * (lights/32 + lights)
// iterations per invocation, under llvmpipe's 65,535 with MAX_LIGHTS and 256 slices.
#define CLUSTERS_BINDING 0
#include "clustered/clusters.glsl"

layout(local_size_x = 64) in;

// Matches `MAX_LIGHTS` in src/lighting/clustered/mod.rs.
const uint MAX_LIGHTS = 8192u;

layout(set = 0, binding = 1) readonly buffer Bounds { vec4 b[]; } bounds;
layout(set = 0, binding = 2) readonly buffer Volumes { LightVolume items[]; } volumes;
layout(set = 0, binding = 3) writeonly buffer Counts { uint n[]; } counts;
layout(set = 0, binding = 4) writeonly buffer Indices { uint i[]; } indices;

shared uint column_lights[MAX_LIGHTS / 32u];

void main() {
    uint column = gl_WorkGroupID.x;
    uint lane = gl_LocalInvocationIndex;
    uint light_count = min(clusters.lights.x, MAX_LIGHTS);
    uint words = (light_count + 31u) / 32u;
    for (uint w = lane; w < words; w += 64u) {
        column_lights[w] = 0u;
    }
    barrier();
    uvec2 tile = uvec2(column % clusters.grid.x, column / clusters.grid.x);
    if (tile.y < clusters.grid.y) {
        vec4 planes[4] = column_planes(tile);
        for (uint i = lane; i < light_count; i += 64u) {
            if (reaches_column(volumes.items[i].sphere, planes)) {
                atomicOr(column_lights[i / 32u], 1u << (i % 32u));
            }
        }
    }
    barrier();
    if (tile.y >= clusters.grid.y) {
        return;
    }
    uint cap = clusters.grid.w;
    for (uint k = lane; k < clusters.grid.z; k += 64u) {
        uint c = tile.x + clusters.grid.x * (tile.y + clusters.grid.y * k);
        vec3 lo = bounds.b[2u * c].xyz;
        vec3 hi = bounds.b[2u * c + 1u].xyz;
        uint base = c * cap;
        uint n = 0u;
        for (uint w = 0u; w < words; ++w) {
            uint bits = column_lights[w];
            while (bits != 0u) {
                uint i = w * 32u + uint(findLSB(bits));
                bits &= bits - 1u;
                vec4 s = volumes.items[i].sphere;
                vec3 d = s.xyz - clamp(s.xyz, lo, hi);
                if (dot(d, d) <= s.w * s.w) {
                    if (n < cap) {
                        indices.i[base + n] = i;
                    }
                    ++n;
                }
            }
        }
        counts.n[c] = n;
    }
}
