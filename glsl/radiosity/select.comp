#version 460
// One workgroup chooses the next shooter (solve.rs's selection): corrected, the block with the
// most unshot power; faithful (CaLight), the best of `samples_per_chart` random blocks per chart,
// or the full search when that best is below the stop. It logs the total unshot power, decides
// whether the solve is done, and writes the shot: the block's flux, centre, area and square.
#include "radiosity/shooting.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Patches { Patch items[]; } patches;
layout(set = 0, binding = 1) readonly buffer State { Radiosity items[]; } radiosity;
layout(set = 0, binding = 2) readonly buffer Blocks { Block items[]; } blocks;
layout(set = 0, binding = 3) readonly buffer Members { uint items[]; } members;
layout(set = 0, binding = 4) buffer Shots { Shot shot; } shots;
layout(set = 0, binding = 5) readonly buffer BlockPower { float items[]; } block_power;
// Per chart: x first block, y block count (blocks are laid out chart by chart).
layout(set = 0, binding = 6) readonly buffer Charts { uvec2 items[]; } charts;
// The total unshot power before each shot (the progress, and the unshot-energy test).
layout(set = 0, binding = 7) buffer UnshotLog { float items[]; } unshot_log;

shared float best_full[64];
shared uint best_full_block[64];
shared float best_sampled[64];
shared uint best_sampled_block[64];
shared float total[64];

uint hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Ties go to the lower block, as in the CPU's scan.
void keep_better(inout float v, inout uint i, float w, uint j) {
    if (w > v || (w == v && j < i)) {
        v = w;
        i = j;
    }
}

void main() {
    // Every invocation reads the same flag, so the early return keeps the barriers uniform.
    if (shots.shot.state.y != 0u) {
        return;
    }
    uint t = gl_LocalInvocationID.x;
    float fv = -1.0;
    uint fi = 0u;
    float sum = 0.0;
    for (uint b = t; b < push.block_count; b += 64u) {
        float w = block_power.items[b];
        sum += w;
        keep_better(fv, fi, w, b);
    }
    float sv = -1.0;
    uint si = 0u;
    // The shot's number: a fresh draw of candidates every shot, reproducible.
    uint seed = shots.shot.shots.x * 0x9e3779b9u;
    if (push.mode == MODE_FAITHFUL) {
        for (uint c = t; c < push.chart_count; c += 64u) {
            uvec2 range = charts.items[c];
            for (uint s = 0u; range.y > 0u && s < push.samples_per_chart; ++s) {
                uint b = range.x + hash(seed ^ hash(c * 64u + s)) % range.y;
                keep_better(sv, si, block_power.items[b], b);
            }
        }
    }
    best_full[t] = fv;
    best_full_block[t] = fi;
    best_sampled[t] = sv;
    best_sampled_block[t] = si;
    total[t] = sum;
    barrier();
    for (uint half_size = 32u; half_size > 0u; half_size >>= 1u) {
        if (t < half_size) {
            float v = best_full[t];
            uint i = best_full_block[t];
            keep_better(v, i, best_full[t + half_size], best_full_block[t + half_size]);
            best_full[t] = v;
            best_full_block[t] = i;
            v = best_sampled[t];
            i = best_sampled_block[t];
            keep_better(v, i, best_sampled[t + half_size], best_sampled_block[t + half_size]);
            best_sampled[t] = v;
            best_sampled_block[t] = i;
            total[t] += total[t + half_size];
        }
        barrier();
    }
    if (t != 0u) {
        return;
    }
    float unshot = total[0];
    uint best = best_full_block[0];
    float best_power = best_full[0];
    if (push.mode == MODE_FAITHFUL) {
        if (best_sampled[0] > push.stop) {
            best = best_sampled_block[0];
            best_power = best_sampled[0];
        } else {
            shots.shot.state.z += 1u;
        }
    }
    uint logged = shots.shot.state.w;
    if (logged < push.log_capacity) {
        unshot_log.items[logged] = unshot;
        shots.shot.state.w = logged + 1u;
    }
    // CaLight stops when no shooter is above the stop, which leaves up to (blocks x stop) of
    // the light unshot; the corrected solve stops on the total instead.
    bool done = push.mode == MODE_FAITHFUL ? best_power <= push.stop : unshot <= push.stop;
    if (done || best_power <= 0.0 || shots.shot.shots.x >= push.max_shots) {
        shots.shot.state.y = 1u;
        return;
    }
    Block block = blocks.items[best];
    float area = 0.0;
    vec3 flux = vec3(0.0);
    vec3 centre = vec3(0.0);
    vec3 normals = vec3(0.0);
    for (uint i = 0u; i < block.range.y; ++i) {
        uint k = members.items[block.range.x + i];
        float a = patches.items[k].centre.w;
        area += a;
        flux += radiosity.items[k].unshot.rgb * a;
        centre += patches.items[k].centre.xyz * a;
        normals += patches.items[k].normal.xyz;
    }
    vec3 c0 = block.corners[0].xyz;
    shots.shot.centre = vec4(centre / area, 0.0);
    // The members' mean normal, as the CPU solve's block takes it (solve.rs): on a curved chart
    // each patch faces as the surface under it does.
    vec3 first = patches.items[members.items[block.range.x]].normal.xyz;
    shots.shot.normal = vec4(length(normals) > 0.0 ? normalize(normals) : first, 0.0);
    shots.shot.flux = vec4(flux, 0.0);
    for (uint k = 0u; k < 4u; ++k) {
        shots.shot.corners[k] = block.corners[k];
    }
    shots.shot.size = vec4(area, length(block.corners[1].xyz - c0) * length(block.corners[3].xyz - c0), 0.0, 0.0);
    shots.shot.state.x = best;
    shots.shot.shots.x += 1u;
    shots.shot.shots.y = block.range.z;
}
