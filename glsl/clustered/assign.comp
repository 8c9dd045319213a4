#version 460
// Clustered pass 2: the lights of every cluster, one workgroup per screen tile, in chunks of
// CHUNK lights. For each chunk the workgroup first marks, in a shared bit mask per band of
// BAND consecutive depth slices, the lights whose bounding sphere reaches the tile's column (its
// four side planes and the near and far depths) and whose depth extent reaches the band (give
// or take a slice, for rounding). Then each invocation takes a slice and tests the lights
// marked for its band: the sphere against the cluster's box, and a spot light's cone against
// the sphere about the box. Hits are written in light order, the first max_per_cluster of them
// to the cluster's slots; the count written is every hit, so that overflow can be read back
// rather than lost. The bands make this cheap with many lights (a slice tests the lights at its
// depth, not every light of the column), and a band is as wide as llvmpipe's SIMD groups of 8
// invocations, so the 8 lanes walk the same lights and each light is loaded once for them
// (loads whose address differs between lanes are a loop over the lanes there). Loop bounds per
// invocation, with MAX_LIGHTS and 256 slices: chunks * (CHUNK/64 lights * 32 bands marked +
// clearing 32 * CHUNK/32 / 64 words) + 4 slices * (MAX_LIGHTS/32 words + MAX_LIGHTS lights)
// = 4 * (32 * 32 + 32) + 4 * (256 + 8192) = 38,016, under llvmpipe's 65,535.
#define CLUSTERS_BINDING 0
#include "clustered/clusters.glsl"

layout(local_size_x = 64) in;

// Matches `MAX_LIGHTS` in src/lighting/clustered/mod.rs.
const uint MAX_LIGHTS = 8192u;

layout(set = 0, binding = 1) readonly buffer Bounds { vec4 b[]; } bounds;
layout(set = 0, binding = 2) readonly buffer Volumes { LightVolume items[]; } volumes;
layout(set = 0, binding = 3) writeonly buffer Counts { uint n[]; } counts;
layout(set = 0, binding = 4) writeonly buffer Indices { uint i[]; } indices;

const uint CHUNK = 2048u;
const uint WORDS = CHUNK / 32u;
const uint MAX_SLICES = 256u;
const uint BAND = 8u;
const uint LANES = 64u;
const uint SLICES_PER_LANE = MAX_SLICES / LANES;
// Per band of slices, the chunk's lights that may reach it (8 KiB).
shared uint band_lights[(MAX_SLICES / BAND) * WORDS];

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
    uint slices = min(clusters.grid.z, MAX_SLICES);
    uint cap = clusters.grid.w;
    vec4 planes[4] = column_planes(tile);
    // Hits so far of the slices this invocation owns: lane, lane + LANES, ...
    uint hits[SLICES_PER_LANE];
    for (uint q = 0u; q < SLICES_PER_LANE; ++q) {
        hits[q] = 0u;
    }
    for (uint first = 0u; first < light_count; first += CHUNK) {
        uint chunk = min(CHUNK, light_count - first);
        uint bands = (slices + BAND - 1u) / BAND;
        for (uint w = lane; w < bands * WORDS; w += LANES) {
            band_lights[w] = 0u;
        }
        barrier();
        for (uint j = lane; j < chunk; j += LANES) {
            vec4 s = volumes.items[first + j].sphere;
            if (reaches_column(s, planes)) {
                uint b0 = uint(max(slice_of(-s.z - s.w) - 1, 0)) / BAND;
                uint b1 = uint(min(slice_of(-s.z + s.w) + 1, int(slices) - 1)) / BAND;
                for (uint b = b0; b <= b1; ++b) {
                    atomicOr(band_lights[b * WORDS + j / 32u], 1u << (j % 32u));
                }
            }
        }
        barrier();
        for (uint q = 0u; q < SLICES_PER_LANE; ++q) {
            uint k = lane + q * LANES;
            if (k >= slices) {
                break;
            }
            uint c = tile.x + clusters.grid.x * (tile.y + clusters.grid.y * k);
            vec3 lo = bounds.b[2u * c].xyz;
            vec3 hi = bounds.b[2u * c + 1u].xyz;
            // The sphere about the box, for the cone test; grown like the box, for rounding.
            vec3 centre = 0.5 * (lo + hi);
            float radius = 0.5 * length(hi - lo) * (1.0 + 1e-4);
            uint base = c * cap;
            uint n = hits[q];
            uint words = (chunk + 31u) / 32u;
            for (uint w = 0u; w < words; ++w) {
                uint bits = band_lights[(k / BAND) * WORDS + w];
                while (bits != 0u) {
                    uint i = first + w * 32u + uint(findLSB(bits));
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
            hits[q] = n;
        }
        barrier();
    }
    for (uint q = 0u; q < SLICES_PER_LANE; ++q) {
        uint k = lane + q * LANES;
        if (k < slices) {
            counts.n[tile.x + clusters.grid.x * (tile.y + clusters.grid.y * k)] = hits[q];
        }
    }
}
