#version 460
// One receiver patch per invocation gathers its share of the shot (solve.rs's inner loop): the
// form factor from the receiver to the shooting block times the block's unshot power, if a ray
// from the receiver reaches the block's centre. The shooter's own patches give their unshot
// power away. Each invocation writes only its own patch, so no two race.
#include "radiosity/shooting.glsl"

layout(local_size_x = 64) in;

layout(set = 0, binding = 0) readonly buffer Patches { Patch items[]; } patches;
layout(set = 0, binding = 1) buffer State { Radiosity items[]; } radiosity;
layout(set = 0, binding = 4) readonly buffer Shots { Shot shot; } shots;

// The surface-visibility matrix (src/lighting/radiosity/visibility.rs): 2 bits per ordered
// chart pair, NONE 0 (nothing passes), PARTIAL 1 (a ray decides), FULL 2 (no occluder: no ray).
layout(set = 0, binding = 12) readonly buffer Visibility { uint items[]; } visibility;

uint chart_visibility(uint i, uint j) {
    if (push.visibility_matrix == 0u) {
        return 1u;
    }
    uint k = i * push.chart_count + j;
    return (visibility.items[k >> 4u] >> (2u * (k & 15u))) & 3u;
}

// Visibility rays cut short by the device, counted for the host (which refuses the result).
layout(set = 0, binding = 10) buffer Status { uint cut_rays; } status;

#define BVH_NODES_BINDING 8
#define BVH_TRIANGLES_BINDING 9
#define BVH_SKIPS_BINDING 11
#define BVH_TRIANGLE_COUNT push.triangle_count
#include "common/bvh.glsl"

const float PI = 3.14159265358979;

// CaLight's point-sampled form factor with its near-field clamp (form_factor::point_sampled).
float point_sampled(vec3 x, vec3 nx, vec3 y, vec3 ny, float area) {
    vec3 d = y - x;
    float r2 = dot(d, d);
    if (r2 <= 0.0) {
        return 0.0;
    }
    vec3 dir = d * inversesqrt(r2);
    float ci = dot(nx, dir);
    float cj = -dot(ny, dir);
    if (ci <= 0.0 || cj <= 0.0) {
        return 0.0;
    }
    return area * ci * cj / (PI * max(r2, push.patch_size * push.patch_size));
}

// One edge's term of the contour integral: the angle it subtends, atan2(|a x b|, a.b), which
// keeps its precision in fp32 for the small angles of distant shooters (acos does not), times
// the cosine between its plane and the receiver's normal.
float edge_term(vec3 x, vec3 n, vec3 p, vec3 q) {
    vec3 a = normalize(p - x);
    vec3 b = normalize(q - x);
    vec3 c = cross(a, b);
    float len = length(c);
    return len < 1e-12 ? 0.0 : atan(len, dot(a, b)) * dot(n, c / len);
}

// The exact form factor from a differential area to a quadrilateral clipped to the receiver's
// front half-space (form_factor::point_to_polygon). The clipped polygon's vertices are streamed
// into the sum as Sutherland-Hodgman emits them, so no array is indexed at run time.
float point_to_polygon(vec3 x, vec3 n, vec3 corners[4]) {
    float sum = 0.0;
    uint count = 0u;
    vec3 first = vec3(0.0);
    vec3 previous = vec3(0.0);
    for (uint k = 0u; k < 4u; ++k) {
        vec3 p = corners[k];
        vec3 q = corners[(k + 1u) & 3u];
        float sp = dot(n, p - x);
        float sq = dot(n, q - x);
        for (uint e = 0u; e < 2u; ++e) {
            bool emit = e == 0u ? sp > 0.0 : ((sp > 0.0) != (sq > 0.0) && sp != sq);
            if (!emit) {
                continue;
            }
            vec3 v = e == 0u ? p : p + (q - p) * (sp / (sp - sq));
            if (count == 0u) {
                first = v;
            } else {
                sum += edge_term(x, n, previous, v);
            }
            previous = v;
            ++count;
        }
    }
    if (count < 3u) {
        return 0.0;
    }
    sum += edge_term(x, n, previous, first);
    return abs(sum / (2.0 * PI));
}

// Whether the receiver at x is near enough to the shooting square that its centre's form
// factor misjudges the patch (solve.rs near_field).
bool near_field(vec3 x, vec3 corners[4]) {
    vec3 centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
    float radius = 0.5 * max(length(corners[2] - corners[0]), length(corners[3] - corners[1]));
    return length(x - centre) < push.near_field * (radius + push.patch_size * 0.70710678);
}

// The receiver's form factor averaged over the sub-samples it keeps (solve.rs
// near_form_factor): once per quarter of the patch, at the centroid of its kept sub-samples in
// front of the shooter's plane, weighted by their count. `at` becomes the centroid of all of
// those, where the visibility ray starts. 0 when none is in front.
float near_form_factor(Patch p, vec3 shooter_normal, vec3 corners[4], out vec3 at) {
    vec3 sums[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    uint counts[4] = uint[4](0u, 0u, 0u, 0u);
    uint count = 0u;
    for (uint b = 0u; b < 16u; ++b) {
        if ((p.ids.z & (1u << b)) == 0u) {
            continue;
        }
        uint si = b & 3u;
        uint sj = b >> 2u;
        vec3 y = p.first_sample.xyz + p.step_u.xyz * float(si) + p.step_v.xyz * float(sj);
        ++count;
        if (dot(shooter_normal, y - corners[0]) > 0.0) {
            uint q = 2u * (sj >> 1u) + (si >> 1u);
            sums[q] += y;
            counts[q] += 1u;
        }
    }
    if (count == 0u) {
        at = p.centre.xyz;
        return dot(shooter_normal, at - corners[0]) > 0.0 ? point_to_polygon(at, p.normal.xyz, corners) : 0.0;
    }
    float sum = 0.0;
    uint front = 0u;
    vec3 total = vec3(0.0);
    for (uint q = 0u; q < 4u; ++q) {
        if (counts[q] == 0u) {
            continue;
        }
        sum += float(counts[q]) * point_to_polygon(sums[q] / float(counts[q]), p.normal.xyz, corners);
        front += counts[q];
        total += sums[q];
    }
    at = front > 0u ? total / float(front) : p.centre.xyz;
    return front > 0u ? sum / float(count) : 0.0;
}

void main() {
    uint r = gl_GlobalInvocationID.x;
    if (r >= push.patch_count || shots.shot.state.y != 0u) {
        return;
    }
    Patch receiver = patches.items[r];
    if (receiver.ids.y == NO_BLOCK) {
        return;
    }
    Shot shot = shots.shot;
    if (receiver.ids.y == shot.state.x) {
        radiosity.items[r].unshot = vec4(0.0);
        return;
    }
    uint vis = chart_visibility(shot.shots.y, receiver.ids.x);
    if (vis == 0u) {
        return;
    }
    vec3 normal = shot.normal.xyz;
    vec3 x = receiver.centre.xyz;
    vec3 corners[4] = vec3[4](shot.corners[0].xyz, shot.corners[1].xyz, shot.corners[2].xyz, shot.corners[3].xyz);
    // A receiver near the shooter is judged by its sub-samples, which may straddle the
    // shooter's plane.
    bool near = push.mode == MODE_CORRECTED && near_field(x, corners);
    // Shooters emit toward their normal only; a chart never lights itself (it is planar).
    if (receiver.ids.x == shot.shots.y || (!near && dot(normal, x - corners[0]) <= 0.0) || all(equal(receiver.albedo.rgb, vec3(0.0)))) {
        return;
    }
    float f;
    if (near) {
        f = near_form_factor(receiver, normal, corners, x) / shot.size.y;
    } else if (push.mode == MODE_CORRECTED) {
        f = point_to_polygon(x, receiver.normal.xyz, corners) / shot.size.y;
    } else {
        f = point_sampled(x, receiver.normal.xyz, shot.centre.xyz, normal, shot.size.x) / shot.size.x;
    }
    if (f <= 0.0) {
        return;
    }
    // A curved chart's patch takes the normal of the surface under it, which is not its
    // chart's plane: both ends must then also face each other's planes, and the ray leaves
    // along the plane, as the CPU solve does (solve.rs receiver_share). On a planar chart the
    // two normals are one.
    vec3 plane = receiver.ids.w == 1u ? normalize(cross(receiver.step_u.xyz, receiver.step_v.xyz)) : receiver.normal.xyz;
    vec3 shooter_plane = normalize(cross(corners[1] - corners[0], corners[3] - corners[0]));
    if (dot(plane, shot.centre.xyz - x) <= 0.0 || dot(shooter_plane, x - shot.centre.xyz) <= 0.0) {
        return;
    }
    vec3 from = x + plane * push.epsilon;
    vec3 to = shot.centre.xyz + shooter_plane * push.epsilon;
    vec3 d = to - from;
    float len = length(d);
    if (len > 0.0 && vis != 2u) {
        float t_max = len * (1.0 - 1e-4) - 1e-5;
        bool complete;
        bool blocked = t_max > 0.0 && occluded(from, d / len, t_max, complete);
        if (!complete) {
            atomicAdd(status.cut_rays, 1u);
        }
        if (blocked) {
            return;
        }
    }
    vec3 delta = receiver.albedo.rgb * shot.flux.rgb * f;
    radiosity.items[r].total.rgb += delta;
    radiosity.items[r].unshot.rgb += delta;
}
