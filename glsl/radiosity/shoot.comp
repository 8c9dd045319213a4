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
    // Shooters emit toward their normal only; a chart never lights itself (it is planar).
    if (receiver.ids.x == shot.shots.y || dot(normal, x - shot.corners[0].xyz) <= 0.0 || all(equal(receiver.albedo.rgb, vec3(0.0)))) {
        return;
    }
    float f;
    if (push.mode == MODE_CORRECTED) {
        vec3 corners[4] = vec3[4](shot.corners[0].xyz, shot.corners[1].xyz, shot.corners[2].xyz, shot.corners[3].xyz);
        f = point_to_polygon(x, receiver.normal.xyz, corners) / shot.size.y;
    } else {
        f = point_sampled(x, receiver.normal.xyz, shot.centre.xyz, normal, shot.size.x) / shot.size.x;
    }
    if (f <= 0.0) {
        return;
    }
    vec3 from = x + receiver.normal.xyz * push.epsilon;
    vec3 to = shot.centre.xyz + normal * push.epsilon;
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
