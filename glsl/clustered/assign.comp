#version 460
// Clustered pass 2: the lights of every cluster, one workgroup per screen tile. The workgroup
// first marks, in a shared bit mask per band of consecutive depth slices, the lights (of those
// the coarse pass listed for its block of tiles) whose bounding sphere reaches the tile's column
// (its four side planes and the near and far depths) and whose depth extent reaches the band
// (give or take a slice, for rounding). Then each
// invocation takes a slice and tests the lights marked for its band: the sphere against the
// cluster's box, and a spot light's cone against the sphere about the box. Hits are written in
// light order, the first max_per_cluster of them to the cluster's slots; the count written is
// every hit, so that overflow can be read back rather than lost. The bands make this cheap with
// many lights (a slice tests the lights near its depth, not every light of the column). A band
// is a multiple of llvmpipe's SIMD groups of 8 invocations, so the 8 lanes walk the same lights
// and each light is loaded once for them (loads whose address differs between lanes are a loop
// over the lanes there); there are at most BANDS of them, so the masks fit in shared memory
// without a loop over chunks of lights (a barrier inside a loop made the pass twice as slow
// with few lights on llvmpipe). Loop bounds per invocation, with MAX_LIGHTS and 256 slices:
// BANDS * WORDS / 64 words cleared + MAX_LIGHTS / 64 lights * BANDS bands marked + 4 slices *
// (WORDS + MAX_LIGHTS lights) = 32 + 1,024 + 33,792, under llvmpipe's 65,535.
#define CLUSTERS_BINDING 0
#include "clustered/clusters.glsl"

layout(local_size_x = 64) in;

// Matches `MAX_LIGHTS` in src/lighting/clustered/mod.rs.
const uint MAX_LIGHTS = 8192u;

layout(set = 0, binding = 1) readonly buffer Bounds { vec4 b[]; } bounds;
layout(set = 0, binding = 2) readonly buffer Volumes { LightVolume items[]; } volumes;
layout(set = 0, binding = 3) writeonly buffer Counts { uint n[]; } counts;
layout(set = 0, binding = 4) writeonly buffer Indices { uint i[]; } indices;
layout(set = 0, binding = 5) readonly buffer Coarse { uint m[]; } coarse;

const uint WORDS = MAX_LIGHTS / 32u;
const uint MAX_SLICES = 256u;
const uint BANDS = 8u;
// Per band of slices, the lights that may reach it (8 KiB).
shared uint band_lights[BANDS * WORDS];

// The slice of view depth d: 0 before the near plane, at most MAX_SLICES past the far end (an
// infinite depth, a directional light's, included: float-to-int of infinity is undefined).
int slice_of(float d) {
    float k = floor(log(max(d, clusters.depth.x) / clusters.depth.x) * clusters.depth.w);
    return int(min(k, float(MAX_SLICES)));
}

void main() {
    uint column = gl_WorkGroupID.x;
    uvec2 tile = uvec2(column % clusters.grid.x, column / clusters.grid.x);
    if (tile.y >= clusters.grid.y) {
        return;  // the whole workgroup: no barrier is left waiting
    }
    uint lane = gl_LocalInvocationIndex;
    uint light_count = min(clusters.lights.x, MAX_LIGHTS);
    uint words = (light_count + 31u) / 32u;
    uint slices = min(clusters.grid.z, MAX_SLICES);
    // Slices per band: a multiple of 8, and no more than BANDS bands.
    uint band = 8u * ((slices + 8u * BANDS - 1u) / (8u * BANDS));
    uint bands = (slices + band - 1u) / band;
    for (uint w = lane; w < bands * words; w += 64u) {
        band_lights[w] = 0u;
    }
    barrier();
    vec4 planes[4] = column_planes(tile);
    // Only the lights that reach the tile's coarse tile (a superset of those reaching the column:
    // the coarse column holds it), a word of them per invocation.
    uint coarse_base = (tile.x / COARSE + coarse_columns() * (tile.y / COARSE)) * WORDS;
    for (uint w = lane; w < words; w += 64u) {
        uint candidates = coarse.m[coarse_base + w];
        while (candidates != 0u) {
            uint i = w * 32u + uint(findLSB(candidates));
            candidates &= candidates - 1u;
            vec4 s = volumes.items[i].sphere;
            if (reaches_column(s, planes)) {
                uint b0 = uint(max(slice_of(-s.z - s.w) - 1, 0)) / band;
                uint b1 = uint(min(slice_of(-s.z + s.w) + 1, int(slices) - 1)) / band;
                for (uint b = b0; b <= b1; ++b) {
                    atomicOr(band_lights[b * words + i / 32u], 1u << (i % 32u));
                }
            }
        }
    }
    barrier();
    uint cap = clusters.grid.w;
    for (uint k = lane; k < slices; k += 64u) {
        uint c = tile.x + clusters.grid.x * (tile.y + clusters.grid.y * k);
        vec3 lo = bounds.b[2u * c].xyz;
        vec3 hi = bounds.b[2u * c + 1u].xyz;
        // The sphere about the box, for the cone test; grown like the box, for rounding.
        vec3 centre = 0.5 * (lo + hi);
        float radius = 0.5 * length(hi - lo) * (1.0 + 1e-4);
        uint base = c * cap;
        uint n = 0u;
        uint first_word = (k / band) * words;
        for (uint w = 0u; w < words; ++w) {
            uint bits = band_lights[first_word + w];
            while (bits != 0u) {
                uint i = w * 32u + uint(findLSB(bits));
                bits &= bits - 1u;
                vec4 s = volumes.items[i].sphere;
                vec3 d = s.xyz - clamp(s.xyz, lo, hi);
                if (dot(d, d) <= s.w * s.w && cone_reaches(volumes.items[i], centre, radius)) {
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
