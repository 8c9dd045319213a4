#version 460
// CaSHL's direct visibility on the GPU (src/lighting/sh_lightmap/gpu.rs), the same bits as
// transfer::visibility_cpu: per inside patch and word of 32 samples of the shared sample set,
// bit s is set when direction s counts for the patch (in front of its chart's plane and of its
// possibly normal-mapped normal) and the ray from the patch's centre, lifted off its plane,
// reaches the sky (transfer::reaches_sky).
//
// One invocation traces the 32 / lanes samples of one lane of one word. llvmpipe ends an
// invocation's loops after 65,535 iterations in total, so the host starts with one invocation
// per word (32 rays) and doubles the lanes (and retries the chunk) whenever an invocation
// reports that its loops were cut short. The lanes of a word combine their bits with atomicOr
// into the chunk's output, which the host clears before each dispatch.
//
// Invocations are ordered word-major, lane-minor: neighbouring invocations trace the same
// directions from neighbouring patches, which keeps a SIMD batch's rays coherent.

layout(local_size_x = 64) in;

struct Patch {
    vec4 origin;  // xyz: the patch centre plus the chart's normal times epsilon
    vec4 plane;   // xyz: the chart's normal
    vec4 normal;  // xyz: the patch's normal
};

// The same values for every dispatch of a bake (lavapipe compiles a shader anew for each set of
// push-constant values): the chunk's first word and the lanes live in buffers.
layout(push_constant) uniform Push {
    uint patch_count;     // inside patches
    uint word_items;      // patch_count * words
    uint sample_count;
    uint triangle_count;
    uint closest;         // 1: the closest hit decides (the scene has sky triangles); 0: any hit blocks
    uint escape;          // 1: a ray that hits nothing reaches the sky
} push;

layout(set = 0, binding = 0) readonly buffer Patches { Patch items[]; } patches;
// World-space unit directions, xyz.
layout(set = 0, binding = 1) readonly buffer Samples { vec4 items[]; } samples;
// One bit per BVH triangle slot: the triangle is a sky surface.
layout(set = 0, binding = 2) readonly buffer Sky { uint items[]; } sky;
// One word per word item of the chunk, from the chunk's first one.
layout(set = 0, binding = 3) buffer Bits { uint items[]; } bits;
// Invocations whose loops the device cut short, for the host (which retries with more lanes).
layout(set = 0, binding = 4) buffer Status { uint cut; } status;
// The chunk's first word item (word * patch_count + patch).
layout(set = 0, binding = 5) readonly buffer Chunk { uint base; } chunk;
// Invocations per word: 1, 2, 4, 8, 16 or 32.
layout(set = 0, binding = 9) readonly buffer Lanes { uint count; } lanes_per_word;

#define BVH_NODES_BINDING 6
#define BVH_TRIANGLES_BINDING 7
#define BVH_SKIPS_BINDING 8
#define BVH_TRIANGLE_COUNT push.triangle_count
#include "common/bvh.glsl"

void main() {
    uint lanes = lanes_per_word.count;
    uint local_word = gl_GlobalInvocationID.x / lanes;
    uint lane = gl_GlobalInvocationID.x % lanes;
    uint item = chunk.base + local_word;
    if (item >= push.word_items) {
        return;
    }
    uint word = item / push.patch_count;
    Patch p = patches.items[item % push.patch_count];
    uint per = 32u / lanes;
    uint first = word * 32u + lane * per;
    uint count = first < push.sample_count ? min(per, push.sample_count - first) : 0u;

    uint mask = 0u;
    bool cut = false;
    // One more iteration than samples: it is reached only if no loop was cut short before it
    // (the device's limit ends every loop of the invocation once spent).
    bool finished = false;
    for (uint s = 0u; s <= count; ++s) {
        if (s == count) {
            finished = true;
            break;
        }
        vec3 d = samples.items[first + s].xyz;
        if (dot(d, p.plane.xyz) <= 0.0 || dot(d, p.normal.xyz) <= 0.0) {
            continue;
        }
        bool reaches;
        if (push.closest != 0u) {
            float t = NO_HIT;
            int slot;
            vec2 uv;
            if (trace_triangles(p.origin.xyz, d, false, t, slot, uv)) {
                reaches = ((sky.items[uint(slot) >> 5u] >> (uint(slot) & 31u)) & 1u) != 0u;
            } else {
                reaches = push.escape != 0u;
            }
        } else {
            bool complete;
            reaches = !occluded(p.origin.xyz, d, NO_HIT, complete) && push.escape != 0u;
            cut = cut || !complete;
        }
        if (reaches) {
            mask |= 1u << ((first + s) & 31u);
        }
    }
    if (cut || !finished) {
        atomicAdd(status.cut, 1u);
        return;
    }
    if (lanes == 1u) {
        bits.items[local_word] = mask;
    } else if (mask != 0u) {
        atomicOr(bits.items[local_word], mask);
    }
}
