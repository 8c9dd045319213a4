// The cluster grid every clustered pass shares: screen tiles times exponential depth slices.
// Matches `ClusterBlock` and `LightVolume` in src/lighting/clustered/assign.rs. Define
// CLUSTERS_BINDING before including.
#ifndef PENUMBRA_CLUSTERS_GLSL
#define PENUMBRA_CLUSTERS_GLSL

struct LightVolume {
    vec4 sphere;  // view-space bounding sphere; w < 0: reaches nowhere, infinite: everywhere
    vec4 range;   // x: distance from the light's position past which it is not summed
    vec4 apex;    // a spot light's view-space position; w: cos of its outer half-angle
    vec4 axis;    // its view-space unit axis; w: sin of the outer half-angle, < 0 for no cone
};

layout(set = 0, binding = CLUSTERS_BINDING) uniform ClusterBlock {
    mat4 view;      // world to view
    uvec4 grid;     // columns, rows, slices, index slots per cluster
    uvec4 lights;   // x: light count
    vec4 screen;    // width, height (pixels); aspect/f, 1/f
    vec4 depth;     // near, far, ln(far/near), slices/ln(far/near)
} clusters;

uint cluster_count() {
    return clusters.grid.x * clusters.grid.y * clusters.grid.z;
}

uvec3 cluster_coords(uint c) {
    return uvec3(c % clusters.grid.x, (c / clusters.grid.x) % clusters.grid.y, c / (clusters.grid.x * clusters.grid.y));
}

// The view depth where slice k starts; the first starts at the near plane, the last ends at far.
float slice_start(uint k) {
    if (k == 0u) {
        return clusters.depth.x;
    }
    if (k >= clusters.grid.z) {
        return clusters.depth.y;
    }
    return clusters.depth.x * exp(clusters.depth.z * float(k) / float(clusters.grid.z));
}

// The cluster of a fragment at window position `frag` and view depth `d`; depths past the far
// end fall in the last slice.
uint cluster_at(vec2 frag, float d) {
    uint x = min(uint(frag.x * float(clusters.grid.x) / clusters.screen.x), clusters.grid.x - 1u);
    uint y = min(uint(frag.y * float(clusters.grid.y) / clusters.screen.y), clusters.grid.y - 1u);
    float s = floor(log(max(d, clusters.depth.x) / clusters.depth.x) * clusters.depth.w);
    uint k = uint(clamp(s, 0.0, float(clusters.grid.z - 1u)));
    return x + clusters.grid.x * (y + clusters.grid.y * k);
}

// Columns per side of a coarse tile: the coarse pass (glsl/clustered/coarse.comp) lists, for each
// block of COARSE x COARSE columns, the lights that reach it, and the assignment tests only those
// against each of its columns.
const uint COARSE = 4u;

// Coarse tiles across the screen.
uint coarse_columns() {
    return (clusters.grid.x + COARSE - 1u) / COARSE;
}

// The four side planes through the eye of the column over tiles t0 (inclusive) to t1
// (exclusive) (view space, unit normals pointing inward, w unused).
vec4[4] span_planes(uvec2 t0, uvec2 t1) {
    vec2 ndc0 = vec2(t0) / vec2(clusters.grid.xy) * 2.0 - 1.0;
    vec2 ndc1 = vec2(t1) / vec2(clusters.grid.xy) * 2.0 - 1.0;
    float sx = clusters.screen.z;
    float sy = clusters.screen.w;
    // View x = ndc x * depth * sx and view y = -ndc y * depth * sy, with depth = -view z.
    return vec4[4](vec4(normalize(vec3(1.0, 0.0, ndc0.x * sx)), 0.0), vec4(normalize(vec3(-1.0, 0.0, -ndc1.x * sx)), 0.0),
                   vec4(normalize(vec3(0.0, 1.0, -ndc1.y * sy)), 0.0), vec4(normalize(vec3(0.0, -1.0, ndc0.y * sy)), 0.0));
}

// The four side planes of tile `t`'s column.
vec4[4] column_planes(uvec2 t) {
    return span_planes(t, t + 1u);
}

// Whether a bounding sphere reaches the column between the near and far depths: not wholly
// outside any side plane or depth. Conservative (a sphere near a corner may pass), and grown by
// 1e-4 of its distance, like the cluster boxes, for fragments on an edge.
bool reaches_column(vec4 s, vec4 planes[4]) {
    if (s.w < 0.0) {
        return false;
    }
    float r = s.w + 1e-4 * length(s.xyz);
    for (int p = 0; p < 4; ++p) {
        if (dot(planes[p].xyz, s.xyz) < -r) {
            return false;
        }
    }
    return -s.z + r >= clusters.depth.x && -s.z - r <= clusters.depth.y;
}

// Whether a spot light's cone, cut at its range, may reach the sphere (centre c, radius r)
// about a cluster's box; always true for lights without a cone. The signed distance of c from
// the cone's side, cos(a) * (distance off the axis) - sin(a) * (distance along it), is never
// more than its distance from the cone, for any half-angle a, so a sphere farther than r from
// the side is wholly outside (Wronski, "Cull that cone", 2017). Also outside: a sphere wholly
// behind the apex of a cone no wider than a hemisphere, or farther along the axis than the
// range.
bool cone_reaches(LightVolume v, vec3 c, float r) {
    if (v.axis.w < 0.0) {
        return true;
    }
    vec3 to_c = c - v.apex.xyz;
    float along = dot(to_c, v.axis.xyz);
    float off = sqrt(max(dot(to_c, to_c) - along * along, 0.0));
    float beside = v.apex.w * off - v.axis.w * along;
    return beside <= r && (along >= -r || v.apex.w < 0.0) && along <= r + v.range.x;
}

#endif
