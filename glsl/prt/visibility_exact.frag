#version 460
// The corrected raster baker's coverage test (src/lighting/prt/raster.rs): the ray from the
// vertex along this pixel's direction against the triangle (Moller-Trumbore), kept when the
// hit lies between near and far (radial: distance; planar: depth along the normal). Depth is
// that metric, so the nearest occluder wins; the value is 0, or the distance gradient.

#include "prt/mapping.glsl"

layout(constant_id = 0) const int MAPPING = 0;
layout(constant_id = 1) const int RADIAL = 0;
layout(constant_id = 2) const int TILE = 32;
layout(constant_id = 7) const float NEAR = 0.001;
layout(constant_id = 8) const float FAR = 1000.0;
layout(constant_id = 9) const int GRADIENT = 0;

layout(location = 0) flat in vec3 in_a;
layout(location = 1) flat in vec3 in_b;
layout(location = 2) flat in vec3 in_c;
layout(location = 3) flat in ivec2 in_tile;

// The atlas is RGBA: the pipeline writes only B (R and G are the colour-coded sphere's).
layout(location = 0) out vec4 out_atlas;

void main() {
    ivec2 q = ivec2(gl_FragCoord.xy) - in_tile;
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(TILE)))) {
        discard;
    }
    // A rim pixel whose centre lies outside the disk still holds part of it (its weight is the
    // part's integral): its direction is the horizon's there.
    vec2 st = -1.0 + (2.0 * vec2(q) + 1.0) / float(TILE);
    vec3 d = prt_unproject_clamped(MAPPING, st);
    vec3 e1 = in_b - in_a;
    vec3 e2 = in_c - in_a;
    vec3 pv = cross(d, e2);
    float det = dot(e1, pv);
    if (det == 0.0) {
        discard;
    }
    float inv = 1.0 / det;
    vec3 tv = -in_a;
    float u = dot(tv, pv) * inv;
    vec3 qv = cross(tv, e1);
    float v = dot(d, qv) * inv;
    float t = dot(e2, qv) * inv;
    if (u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 0.0) {
        discard;
    }
    float metric = RADIAL == 1 ? t : t * d.z;
    if (metric <= NEAR || metric >= FAR) {
        discard;
    }
    float depth = (metric - NEAR) / (FAR - NEAR);
    gl_FragDepth = depth;
    out_atlas = vec4(0.0, 0.0, GRADIENT == 1 ? depth : 0.0, 0.0);
}
