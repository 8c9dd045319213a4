#version 460
// Adds up each receiver's lanes of rays.comp (src/lighting/prt/raycast.rs, bake_gpu) in lane
// order and scales them by pi/N, so that the host reads bands^2 coefficients per receiver
// rather than every lane's partial sums. On an H200 reading and adding those on the CPU (117 MB
// for 114k receivers at N = 1024) took 130 ms against 49 ms of tracing, and the host-visible
// buffer they needed cost about 40 ms to set up.
//
// One invocation per receiver and coefficient. The sum is compensated (Kahan) in fp32: a
// receiver traced one ray per lane has N lanes, and a plain fp32 sum of 1,024 terms would drift
// by up to ~1e-4 of T00, the tolerance the GPU bake is held to against the CPU's.

layout(local_size_x = 64) in;

// The same values for every dispatch of a bake (lavapipe compiles a shader anew for each set of
// push-constant values): the chunk and the directions per lane live in buffers.
layout(push_constant) uniform Push {
    uint sample_count; // N
    uint dim;          // bands^2
    float weight;      // pi / N
} push;

// rays.comp's partial sums: ((receiver * lanes) + lane) * dim + i.
layout(set = 0, binding = 0) readonly buffer Sums { float items[]; } sums;
// The chunk's transfer: receiver * dim + i.
layout(set = 0, binding = 1) writeonly buffer Transfer { float items[]; } transfer;
layout(set = 0, binding = 2) buffer Status { uint cut; } status;
layout(set = 0, binding = 3) readonly buffer ChunkCount { uint count; } chunk_count;
layout(set = 0, binding = 4) readonly buffer PerLane { uint count; } per_lane;

void main() {
    uint per = per_lane.count;
    uint lanes = (push.sample_count + per - 1u) / per;
    uint at = gl_GlobalInvocationID.x;
    if (at >= chunk_count.count * push.dim) {
        return;
    }
    uint receiver = at / push.dim;
    uint i = at % push.dim;
    uint base = receiver * lanes * push.dim + i;
    precise float sum = 0.0;
    precise float lost = 0.0;
    // One more iteration than lanes: reached only if the device did not cut the loop short
    // (llvmpipe ends an invocation's loops after 65,535 iterations; N can exceed that).
    bool finished = false;
    for (uint lane = 0u; lane <= lanes; ++lane) {
        if (lane == lanes) {
            finished = true;
            break;
        }
        precise float y = sums.items[base + lane * push.dim] - lost;
        precise float t = sum + y;
        lost = (t - sum) - y;
        sum = t;
    }
    if (!finished) {
        atomicAdd(status.cut, 1u);
        return;
    }
    transfer.items[at] = sum * push.weight;
}
