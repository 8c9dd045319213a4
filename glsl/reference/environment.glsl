// Radiance from where rays escape: the constant `params.environment`, or an equirectangular map
// (src/reference/environment.rs) taken as constant over each texel and importance-sampled in
// proportion to luminance x sin(theta). The including shader declares `params`
// (environment_map: x width, y height, both 0 without a map; z: 1 if the map can be sampled),
// `environment_map` and `environment_cdf` first.
#ifndef PENUMBRA_REFERENCE_ENVIRONMENT_GLSL
#define PENUMBRA_REFERENCE_ENVIRONMENT_GLSL

#include "common/lights.glsl"

// Matches Environment::equirect_uv / equirect_dir in src/scene/types.rs.
vec2 equirect_uv(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

vec3 equirect_dir(vec2 uv) {
    float phi = (uv.x - 0.5) * 2.0 * PI;
    float theta = uv.y * PI;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

uvec2 environment_texel(vec2 uv) {
    uvec2 size = params.environment_map.xy;
    return min(uvec2(uv * vec2(size)), size - 1u);
}

vec3 environment_radiance(vec3 d) {
    if (params.environment_map.x == 0u) {
        return params.environment.rgb;
    }
    uvec2 t = environment_texel(equirect_uv(d));
    return environment_map.items[t.y * params.environment_map.x + t.x].rgb;
}

// dw = 2 pi^2 sin(theta) du dv.
float environment_solid_angle_pdf(float uv_pdf, float v) {
    float sin_theta = sin(v * PI);
    return sin_theta > 0.0 ? uv_pdf / (2.0 * PI * PI * sin_theta) : 0.0;
}

// Probabilities of texel row j and of column i within it, from the CDFs.
float environment_texel_probability(uvec2 t) {
    uint w = params.environment_map.x;
    uint h = params.environment_map.y;
    uint row = h + 1u + t.y * (w + 1u);
    return (environment_cdf.items[t.y + 1u] - environment_cdf.items[t.y])
        * (environment_cdf.items[row + t.x + 1u] - environment_cdf.items[row + t.x]);
}

// Solid-angle density of sample_environment choosing d (0 when the map is not sampled).
float environment_pdf(vec3 d) {
    if (params.environment_map.z == 0u) {
        return 0.0;
    }
    vec2 uv = equirect_uv(d);
    float texels = float(params.environment_map.x * params.environment_map.y);
    return environment_solid_angle_pdf(environment_texel_probability(environment_texel(uv)) * texels, uv.y);
}

// The first k in [0, n) with cdf[offset + k + 1] > u (the CDF ends at 1 > u).
uint cdf_search(uint offset, uint n, float u) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (environment_cdf.items[offset + mid + 1u] <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// A direction drawn by texel (row, then column) and uniformly within the texel's uv rectangle.
bool sample_environment(vec2 u, out vec3 dir, out float pdf) {
    uint w = params.environment_map.x;
    uint h = params.environment_map.y;
    uint j = cdf_search(0u, h, u.x);
    float r0 = environment_cdf.items[j];
    float r1 = environment_cdf.items[j + 1u];
    uint row = h + 1u + j * (w + 1u);
    uint i = cdf_search(row, w, u.y);
    float c0 = environment_cdf.items[row + i];
    float c1 = environment_cdf.items[row + i + 1u];
    vec2 uv = vec2((float(i) + (u.y - c0) / (c1 - c0)) / float(w), (float(j) + (u.x - r0) / (r1 - r0)) / float(h));
    dir = equirect_dir(uv);
    pdf = environment_solid_angle_pdf((r1 - r0) * (c1 - c0) * float(w * h), uv.y);
    return pdf > 0.0;
}

// Power heuristic (beta = 2) weight of a sample drawn with density `a` against another
// technique's density `b` for the same direction.
float mis_weight(float a, float b) {
    return a * a / (a * a + b * b);
}

#endif
