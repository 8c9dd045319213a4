#version 460
// Clustered pass 1: the view-space box of every cluster, one invocation each: the 8 corners of
// its tile's frustum between its slice's depths, grown by 1e-4 of the far depth so that a
// fragment on a face (rounded either way) still lies inside.
#define CLUSTERS_BINDING 0
#include "clustered/clusters.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 1) writeonly buffer Bounds { vec4 b[]; } bounds;

void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c >= cluster_count()) {
        return;
    }
    uvec3 t = cluster_coords(c);
    float d0 = slice_start(t.z);
    float d1 = slice_start(t.z + 1u);
    vec2 ndc0 = vec2(t.xy) / vec2(clusters.grid.xy) * 2.0 - 1.0;
    vec2 ndc1 = vec2(t.xy + 1u) / vec2(clusters.grid.xy) * 2.0 - 1.0;
    vec3 lo = vec3(3.0e38);
    vec3 hi = vec3(-3.0e38);
    for (int i = 0; i < 8; ++i) {
        float d = (i & 1) != 0 ? d1 : d0;
        float nx = (i & 2) != 0 ? ndc1.x : ndc0.x;
        float ny = (i & 4) != 0 ? ndc1.y : ndc0.y;
        // NDC y points down: view y is its negation.
        vec3 p = vec3(nx * d * clusters.screen.z, -ny * d * clusters.screen.w, -d);
        lo = min(lo, p);
        hi = max(hi, p);
    }
    vec3 pad = vec3(1e-4 * d1);
    bounds.b[2u * c] = vec4(lo - pad, 0.0);
    bounds.b[2u * c + 1u] = vec4(hi + pad, 0.0);
}
