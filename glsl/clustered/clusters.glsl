// The cluster grid every clustered pass shares: screen tiles times exponential depth slices.
// Matches `ClusterBlock` and `LightVolume` in src/lighting/clustered/assign.rs. Define
// CLUSTERS_BINDING before including.
#ifndef PENUMBRA_CLUSTERS_GLSL
#define PENUMBRA_CLUSTERS_GLSL

struct LightVolume {
    vec4 sphere;  // view-space bounding sphere; w < 0: reaches nowhere, infinite: everywhere
    vec4 range;   // x: distance from the light's position past which it is not summed
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

#endif
