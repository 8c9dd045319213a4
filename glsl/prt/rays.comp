#version 460
// The ray-cast PRT transfer on the GPU (src/lighting/prt/raycast.rs, bake_gpu): per receiver,
// T_i = (pi/N) sum_k V(w_k) y_i(w_k) over N stratified cosine-weighted directions w_k given in
// the receiver's frame, V = 0 where a triangle of the receiver's occluder set lies on the ray
// from p + near*w along w closer than t_max = far - near.
//
// One invocation traces `per` consecutive directions of one receiver (a lane) and writes its
// partial sums; reduce_lanes.comp adds up a receiver's lanes in order and scales them by pi/N.
// llvmpipe ends an invocation's loops after 65,535 iterations in total, so an invocation whose
// loops were cut short reports it (its sentinels below), and the host traces the chunk again with
// fewer directions per lane.
//
// Invocations are ordered lane-major, receiver-minor: neighbouring invocations trace the same
// directions from neighbouring receivers, which keeps a SIMD batch's rays coherent.

layout(local_size_x = 64) in;

struct Receiver {
    vec4 position;   // xyz: world position
    vec4 tangent;    // xyz: the frame of its directions (raycast.rs, frame)
    vec4 bitangent;
    vec4 normal;
    uvec4 bvh;       // x: root node of its occluder set's tree, NO_BVH for an empty set
};

// The same values for every dispatch of a bake (lavapipe compiles a shader anew for each set of
// push-constant values): the chunk and the directions per lane live in buffers.
layout(push_constant) uniform Push {
    uint receiver_count;
    uint sample_count;   // N
    uint bands;          // 1..8
    uint triangle_count; // all sets' triangles
    float near;
    float t_max;         // far - near (3e38 for an unbounded far)
} push;

layout(set = 0, binding = 0) readonly buffer Receivers { Receiver items[]; } receivers;
// Local directions (z = normal), xyz.
layout(set = 0, binding = 1) readonly buffer Directions { vec4 items[]; } directions;
// Per chunk receiver and lane, bands^2 partial sums: ((receiver * lanes) + lane) * bands^2 + i.
layout(set = 0, binding = 2) buffer Sums { float items[]; } sums;
// Invocations whose loops the device cut short, for the host (which retries with more lanes).
layout(set = 0, binding = 3) buffer Status { uint cut; } status;
// The chunk's first receiver, its receivers, and directions per lane.
layout(set = 0, binding = 4) readonly buffer ChunkBase { uint first; } chunk_base;
layout(set = 0, binding = 5) readonly buffer ChunkCount { uint count; } chunk_count;
layout(set = 0, binding = 6) readonly buffer PerLane { uint count; } per_lane;

#define BVH_NODES_BINDING 7
#define BVH_TRIANGLES_BINDING 8
#define BVH_TRIANGLE_COUNT push.triangle_count
#include "common/bvh.glsl"
#include "common/sh.glsl"

const uint NO_BVH = 0xffffffffu;

// The bake's band count, set by raycast.rs (0: read push.bands). llvmpipe runs both sides of a
// branch with lanes masked off, so with the bands unknown every direction paid for the general
// 64-coefficient evaluation beside the 16-coefficient one; known, the compiler keeps one.
layout(constant_id = 0) const uint BANDS = 0u;

void main() {
    uint per = per_lane.count;
    uint lanes = (push.sample_count + per - 1u) / per;
    uint n = chunk_count.count;
    uint lane = gl_GlobalInvocationID.x / n;
    uint local_item = gl_GlobalInvocationID.x % n;
    uint item = chunk_base.first + local_item;
    if (lane >= lanes || item >= push.receiver_count) {
        return;
    }
    Receiver r = receivers.items[item];
    uint first = lane * per;
    uint count = min(per, push.sample_count - first);
    uint bands = BANDS != 0u ? BANDS : push.bands;
    bool small = bands <= 4u;

    float acc[SH_MAX_COEFFS];
    for (int i = 0; i < SH_MAX_COEFFS; ++i) {
        acc[i] = 0.0;
    }
    // One more iteration than directions: it is reached only if no loop was cut short before it
    // (the device's limit ends every loop of the invocation once spent).
    bool finished = false;
    for (uint s = 0u; s <= count; ++s) {
        if (s == count) {
            finished = true;
            break;
        }
        vec3 l = directions.items[first + s].xyz;
        // The CPU's fp32 arithmetic, in its order (raycast.rs, world_dir and bake_cpu).
        precise vec3 d = r.tangent.xyz * l.x + r.bitangent.xyz * l.y + r.normal.xyz * l.z;
        if (r.bvh.x != NO_BVH) {
            precise vec3 o = r.position.xyz + d * push.near;
            float t = push.t_max;
            int tri;
            vec2 uv;
            bool blocked = trace_triangles_from(r.bvh.x, o, d, true, t, tri, uv);
            if (blocked) {
                continue;
            }
        }
        vec3 dir = sh_world_to_sh(d);
        if (small) {
            float y[16];
            sh_eval16(dir, y);
            for (int i = 0; i < 16; ++i) {
                acc[i] += y[i];
            }
        } else {
            float y[SH_MAX_COEFFS];
            sh_eval_bands(dir, int(bands), y);
            for (int i = 0; i < SH_MAX_COEFFS; ++i) {
                acc[i] += y[i];
            }
        }
    }
    // The traversal cannot tell it was cut (its loops just end). Once the budget is spent the
    // later loops end early too: this one misses its sentinel, and so does the write loop below
    // (tests/prt_rays.rs, a walk too long for the device, fails without both).
    if (!finished) {
        atomicAdd(status.cut, 1u);
        return;
    }
    uint dim = bands * bands;
    uint at = (local_item * lanes + lane) * dim;
    // The same sentinel for the writes: a cut here would leave sums unwritten.
    bool written = false;
    for (uint i = 0u; i <= dim; ++i) {
        if (i == dim) {
            written = true;
            break;
        }
        sums.items[at + i] = acc[i];
    }
    if (!written) {
        atomicAdd(status.cut, 1u);
    }
}
