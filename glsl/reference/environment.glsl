// Radiance from where rays escape: the constant `params.environment`, or an equirectangular or
// cube map (src/reference/environment.rs) taken as constant over each texel and importance-sampled
// in proportion to luminance x texel solid angle. The including shader declares `params`
// (environment_map: x width, y height, both 0 without a map; z: 1 if the map can be sampled;
// w: 1 for a cube map, its faces stacked, height = 6 width) and the tables `environment_table`
// (texels) and `environment_cdf_table` (the CDFs, four values a texel) first.
#ifndef PENUMBRA_REFERENCE_ENVIRONMENT_GLSL
#define PENUMBRA_REFERENCE_ENVIRONMENT_GLSL

#include "common/lights.glsl"
#include "common/cube.glsl"
#include "common/texel_table.glsl"

// Value i of the CDFs.
float environment_cdf(uint i) {
    return uintBitsToFloat(table_packed(environment_cdf_table, i));
}

// Matches Environment::equirect_uv / equirect_dir in src/scene/types.rs.
vec2 equirect_uv(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

vec3 equirect_dir(vec2 uv) {
    float phi = (uv.x - 0.5) * 2.0 * PI;
    float theta = uv.y * PI;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

// Solid-angle density of sampling uniformly within a texel, per unit of the texel's probability:
// equirect dw = 2 pi^2 sin(theta) du dv over a 1/(w h) uv cell; cube dw = ds dt / (1 + s^2 + t^2)^1.5
// over a (2/n)^2 st cell.
float equirect_density(float v) {
    float sin_theta = sin(v * PI);
    float texels = float(params.environment_map.x * params.environment_map.y);
    return sin_theta > 0.0 ? texels / (2.0 * PI * PI * sin_theta) : 0.0;
}

float cube_density(vec2 st) {
    float n = float(params.environment_map.x);
    return 0.25 * n * n * pow(1.0 + dot(st, st), 1.5);
}

// The stored texel (column, row) direction d falls in, and equirect_density / cube_density there.
uvec2 environment_texel(vec3 d, out float density) {
    if (params.environment_map.w != 0u) {
        vec2 st;
        uint face = cube_face(d, st);
        density = cube_density(st);
        return cube_texel(face, st, params.environment_map.x);
    }
    vec2 uv = equirect_uv(d);
    density = equirect_density(uv.y);
    uvec2 size = params.environment_map.xy;
    return min(uvec2(uv * vec2(size)), size - 1u);
}

vec3 environment_radiance(vec3 d) {
    if (!SCENE_HAS_ENVIRONMENT_MAP || params.environment_map.x == 0u) {
        return params.environment.rgb;
    }
    float density;
    uvec2 t = environment_texel(d, density);
    return table_vec4(environment_table, t.y * params.environment_map.x + t.x).rgb;
}

// Probabilities of texel row j and of column i within it, from the CDFs.
float environment_texel_probability(uvec2 t) {
    uint w = params.environment_map.x;
    uint h = params.environment_map.y;
    uint row = h + 1u + t.y * (w + 1u);
    return (environment_cdf(t.y + 1u) - environment_cdf(t.y))
        * (environment_cdf(row + t.x + 1u) - environment_cdf(row + t.x));
}

// Solid-angle density of sample_environment choosing d (0 when the map is not sampled).
float environment_pdf(vec3 d) {
    if (!SCENE_SAMPLES_ENVIRONMENT || params.environment_map.z == 0u) {
        return 0.0;
    }
    float density;
    uvec2 t = environment_texel(d, density);
    return environment_texel_probability(t) * density;
}

// The first k in [0, n) with cdf[offset + k + 1] > u (the CDF ends at 1 > u).
uint cdf_search(uint offset, uint n, float u) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (environment_cdf(offset + mid + 1u) <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// A direction drawn by texel (row, then column) and uniformly within the texel's uv (equirect) or
// st (cube) rectangle.
bool sample_environment(vec2 u, out vec3 dir, out float pdf) {
    uint w = params.environment_map.x;
    uint h = params.environment_map.y;
    uint j = cdf_search(0u, h, u.x);
    float r0 = environment_cdf(j);
    float r1 = environment_cdf(j + 1u);
    uint row = h + 1u + j * (w + 1u);
    uint i = cdf_search(row, w, u.y);
    float c0 = environment_cdf(row + i);
    float c1 = environment_cdf(row + i + 1u);
    vec2 within = vec2((u.y - c0) / (c1 - c0), (u.x - r0) / (r1 - r0));
    float probability = (r1 - r0) * (c1 - c0);
    if (params.environment_map.w != 0u) {
        uint face = j / w;
        vec2 st = 2.0 * (vec2(float(i), float(j - face * w)) + within) / float(w) - 1.0;
        dir = normalize(cube_dir(face, st));
        pdf = probability * cube_density(st);
    } else {
        vec2 uv = (vec2(float(i), float(j)) + within) / vec2(float(w), float(h));
        dir = equirect_dir(uv);
        pdf = probability * equirect_density(uv.y);
    }
    return pdf > 0.0;
}

// Power heuristic (beta = 2) weight of a sample drawn with density `a` against another
// technique's density `b` for the same direction.
float mis_weight(float a, float b) {
    return a * a / (a * a + b * b);
}

#endif
