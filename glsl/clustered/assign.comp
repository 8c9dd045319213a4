#version 460
// Clustered pass 2: per cluster, every light's bounding sphere against the cluster's box; the
// first max_per_cluster hits go to the cluster's fixed slots, and the count written is every
// hit, so that overflow can be read back rather than lost. One invocation per cluster loops
// over the lights (the light count is capped on the CPU below llvmpipe's loop limit).
#define CLUSTERS_BINDING 0
#include "clustered/clusters.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 1) readonly buffer Bounds { vec4 b[]; } bounds;
layout(set = 0, binding = 2) readonly buffer Volumes { LightVolume items[]; } volumes;
layout(set = 0, binding = 3) writeonly buffer Counts { uint n[]; } counts;
layout(set = 0, binding = 4) writeonly buffer Indices { uint i[]; } indices;

void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c >= cluster_count()) {
        return;
    }
    vec3 lo = bounds.b[2u * c].xyz;
    vec3 hi = bounds.b[2u * c + 1u].xyz;
    uint cap = clusters.grid.w;
    uint base = c * cap;
    uint n = 0u;
    for (uint i = 0u; i < clusters.lights.x; ++i) {
        vec4 s = volumes.items[i].sphere;
        if (s.w < 0.0) {
            continue;
        }
        vec3 d = s.xyz - clamp(s.xyz, lo, hi);
        if (dot(d, d) <= s.w * s.w) {
            if (n < cap) {
                indices.i[base + n] = i;
            }
            ++n;
        }
    }
    counts.n[c] = n;
}
