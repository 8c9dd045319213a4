// Ray queries against the scene: the BVH over triangles (common/bvh.glsl) and the area lights,
// which are opaque to every ray.
// The including shader declares `params` (counts.x: lights; options.y: the first area light,
// the punctual ones coming before it) and `lights`, and includes common/bvh.glsl, before
// including this file.
#ifndef PENUMBRA_REFERENCE_TRACE_GLSL
#define PENUMBRA_REFERENCE_TRACE_GLSL

#include "common/bvh.glsl"
#include "reference/features.glsl"

const uint LIGHT_SPHERE = 3u;
const uint LIGHT_QUAD = 4u;
// A light index no light has: occlusion tests that skip none.
const uint NO_LIGHT = 0xffffffffu;

struct Hit {
    float t;
    int triangle;  // slot in `triangles`, or -1
    int light;     // index of the area light hit, or -1
    vec2 uv;       // barycentrics of p1 and p2 on the triangle
};

// Nearest positive distance to a sphere, NO_HIT if none.
float hit_sphere(vec3 o, vec3 d, vec3 center, float radius) {
    vec3 oc = o - center;
    float b = dot(oc, d);
    float disc = b * b - (dot(oc, oc) - radius * radius);
    if (disc < 0.0) {
        return NO_HIT;
    }
    float s = sqrt(disc);
    float t = -b - s > 0.0 ? -b - s : -b + s;
    return t > 0.0 ? t : NO_HIT;
}

// Distance to area light `i` (either side of a quad), NO_HIT if missed or not an area light.
float hit_area_light(uint i, vec3 o, vec3 d) {
    Light light = lights.items[i];
    uint type = uint(light.position.w);
    if (SCENE_HAS_SPHERE_LIGHTS && type == LIGHT_SPHERE) {
        return hit_sphere(o, d, light.position.xyz, light.direction.x);
    }
    if (SCENE_HAS_QUAD_LIGHTS && type == LIGHT_QUAD) {
        // A parallelogram is a triangle test without the u + v <= 1 bound.
        vec3 e1 = light.direction.xyz;
        vec3 e2 = light.cone.xyz;
        vec3 pv = cross(d, e2);
        float det = dot(e1, pv);
        if (det == 0.0) {
            return NO_HIT;
        }
        float inv = 1.0 / det;
        vec3 tv = o - light.position.xyz;
        float u = dot(tv, pv) * inv;
        vec3 qv = cross(tv, e1);
        float v = dot(d, qv) * inv;
        float t = dot(e2, qv) * inv;
        return (u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0 && t > 0.0) ? t : NO_HIT;
    }
    return NO_HIT;
}

// The BVH query through the walk the host chose (features.glsl).
bool trace_scene(vec3 o, vec3 d, bool any_hit, inout float t_max, out int triangle, out vec2 uv) {
    if (BVH_WALK_ORDERED) {
        return trace_triangles_ordered(o, d, any_hit, t_max, triangle, uv);
    }
    return trace_triangles(o, d, any_hit, t_max, triangle, uv);
}

Hit trace_closest(vec3 o, vec3 d) {
    Hit h;
    h.t = NO_HIT;
    h.light = -1;
    trace_scene(o, d, false, h.t, h.triangle, h.uv);
    for (uint i = params.options.y; i < params.counts.x; ++i) {
        float t = hit_area_light(i, o, d);
        if (t < h.t) {
            h.t = t;
            h.light = int(i);
            h.triangle = -1;
        }
    }
    return h;
}

// Whether anything lies on the ray closer than t_max; `skip_light` is the light being sampled.
bool occluded(vec3 o, vec3 d, float t_max, uint skip_light) {
    for (uint i = params.options.y; i < params.counts.x; ++i) {
        if (i != skip_light && hit_area_light(i, o, d) < t_max) {
            return true;
        }
    }
    int triangle;
    vec2 uv;
    return trace_scene(o, d, true, t_max, triangle, uv);
}

// A ray origin just off the surface at p on the side of unit `n`, offset in units of the float
// spacing at p (Waechter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection",
// Ray Tracing Gems, 2019), so it works at any distance from the origin.
vec3 offset_origin(vec3 p, vec3 n) {
    const float ORIGIN = 1.0 / 32.0;
    const float FLOAT_SCALE = 1.0 / 65536.0;
    const float INT_SCALE = 256.0;
    ivec3 of_i = ivec3(INT_SCALE * n);
    ivec3 bits = floatBitsToInt(p);
    vec3 p_i = intBitsToFloat(ivec3(
        bits.x + (p.x < 0.0 ? -of_i.x : of_i.x),
        bits.y + (p.y < 0.0 ? -of_i.y : of_i.y),
        bits.z + (p.z < 0.0 ? -of_i.z : of_i.z)));
    return vec3(
        abs(p.x) < ORIGIN ? p.x + FLOAT_SCALE * n.x : p_i.x,
        abs(p.y) < ORIGIN ? p.y + FLOAT_SCALE * n.y : p_i.y,
        abs(p.z) < ORIGIN ? p.z + FLOAT_SCALE * n.z : p_i.z);
}

#endif
