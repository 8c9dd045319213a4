// Horizon angles per azimuth direction: from the smoothing pyramid (HF_PYRAMID; the height-field thesis section
// 4.2.1 with the digest's nearest-first reading, section 5.1) or ray-marched on the bilinear
// level-0 field (HF_BRUTE). The CPU mirror is src/heightfield/cpu.rs.
#ifndef PENUMBRA_HF_HORIZON_GLSL
#define PENUMBRA_HF_HORIZON_GLSL

#include "heightfield/common.glsl"

// Planar distance (texels) from texel p to the light's centre.
float hf_light_planar_texels(ivec2 p) {
    vec2 c = (params.light_pos.xz - vec2(params.grid.y, params.grid.z)) * params.grid.w;
    return length(c - vec2(p));
}

#ifdef HF_PYRAMID
// Full-resolution smoothed levels (B-spline reconstructions), one per layer.
layout(set = 0, binding = 4) uniform sampler2DArray pyramid;

// The receiver's height in every level (module scope: see common.glsl).
float hf_h0[HF_MAX_LEVELS];

float hf_level_texel(ivec2 p, int layer) {
    int r = hf_res() - 1;
    return texelFetch(pyramid, ivec3(clamp(p, ivec2(0), ivec2(r)), layer), 0).r;
}

float hf_level_bilinear(vec2 q, int layer) {
    if (HF_HW_BILINEAR) return texture(pyramid, vec3((q + 0.5) / float(hf_res()), float(layer))).r;
    vec2 f = floor(q);
    vec2 t = q - f;
    ivec2 p = ivec2(f);
    float a = mix(hf_level_texel(p, layer), hf_level_texel(p + ivec2(1, 0), layer), t.x);
    float b = mix(hf_level_texel(p + ivec2(0, 1), layer), hf_level_texel(p + ivec2(1, 1), layer), t.x);
    return mix(a, b, t.y);
}

// Faithful (Eq. 4.5): the receiver's height from each sample's own level. Corrected: never below
// its true height (level 0), since a level that has smoothed a ridge or plateau edge away puts
// the receiver under the surface around it, and it would see a horizon above the true one (up
// to 4.6 degrees on the digest's wall field); in valleys, where smoothing raises the receiver, the
// level's height still cancels the raised samples.
void hf_load_receiver(ivec2 p) {
    float h = hf_level_texel(p, 0);
    for (int l = 0; l < params.dims.y; ++l) {
        float hl = hf_level_texel(p, l);
        hf_h0[l] = params.cfg.y != 0 ? max(hl, h) : hl;
    }
}

// Elevation angle of sample i along texel direction d (Eq. 4.5-4.6): at distance d_i, from
// level L_i, the receiver's height from the same level.
float hf_sample(ivec2 p, vec2 d, int i) {
    vec4 s = params.samples[i];
    int layer = int(s.z);
    float hq = hf_level_bilinear(vec2(p) + s.x * d, layer);
    return atan((hq - hf_h0[layer]) * s.y * params.grid.w);
}

// The B-spline maximum over the sample index (Eq. 4.8-4.13), streamed over a window of four
// samples W(m-3..m) with the end values replicated: samples 0..last are taken, the knots
// i <= t_end and midpoints i + 1/2 <= t_end evaluated (weights {1,4,1}/6 and {1,23,23,1}/48),
// and with `at_end` the spline exactly at t_end too. Returns -pi/2 if nothing was evaluated.
float hf_spline_max(ivec2 p, vec2 d, int last, float t_end, bool at_end) {
    float best = -HF_HALF_PI;
    float w0 = hf_sample(p, d, 0);
    float p3 = w0, p2 = w0, p1 = w0;
    int f = int(floor(t_end));
    float u = t_end - float(f);
    for (int m = 0; m <= last + 2; ++m) {
        float cur = m == 0 ? w0 : (m <= last ? hf_sample(p, d, m) : p1);
        int k = m - 1;
        if (k >= 0 && float(k) <= t_end) best = max(best, (p2 + 4.0 * p1 + cur) / 6.0);
        int h = m - 2;
        if (h >= 0 && float(h) + 0.5 <= t_end) best = max(best, (p3 + 23.0 * (p2 + p1) + cur) / 48.0);
        if (at_end && m == f + 2) {
            float u2 = u * u, u3 = u2 * u;
            float b0 = (1.0 - u) * (1.0 - u) * (1.0 - u), b1 = 3.0 * u3 - 6.0 * u2 + 4.0;
            float b2 = -3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0, b3 = u3;
            best = max(best, (b0 * p3 + b1 * p2 + b2 * p1 + b3 * cur) / 6.0);
        }
        p3 = p2;
        p2 = p1;
        p1 = cur;
    }
    return best;
}

// Environment horizon: the maximum over the whole spline, clamped at 0 (Eq. 4.13).
float hf_horizon_env(ivec2 p, int j) {
    int n = params.dims.y;
    return max(hf_spline_max(p, hf_dir(j), n - 1, float(n - 1), false), 0.0);
}

// Local-light horizon (Eq. 4.24-4.25): samples up to the first beyond the light's planar
// distance d_li, the maximum of the spline for d <= d_li (and, corrected, at d_li), signed. A
// light within one texel keeps the first sample (the height-field thesis section 3.2.4c), continuous with the
// receivers around it.
float hf_horizon_light(ivec2 p, int j, float d_li) {
    int n = params.dims.y;
    float t_li = d_li > 0.0 ? log(d_li) / params.horizon.y : -1.0;
    if (t_li < 0.0) return hf_sample(p, hf_dir(j), 0);
    int k = min(int(floor(t_li)) + 1, n - 1);
    return hf_spline_max(p, hf_dir(j), k, min(t_li, float(n - 1)), params.cfg.y != 0);
}
#endif  // HF_PYRAMID

#ifdef HF_BRUTE
// x: largest height of the field this frame (from the bounds pass).
layout(set = 0, binding = 4, std430) readonly buffer Bounds { vec4 b; } bounds;

float hf_h0;

void hf_load_receiver(ivec2 p) {
    hf_h0 = hf_height_texel(p);
}

// One march position: stops at the end or once even the field's highest point could not beat
// `best`.
#define HF_MARCH_AT(k)                                                              \
    if (!stop) {                                                                    \
        int m = base + k;                                                           \
        float dist = float(m) * step;                                               \
        if (m > count || rise <= best * dist) {                                     \
            stop = true;                                                            \
        } else {                                                                    \
            float hq = hf_height_bilinear(vec2(p) + dist * d);                      \
            best = max(best, (hq - hf_h0) * params.grid.w / dist);                  \
        }                                                                           \
    }

// Largest slope (h(q) - h0) / dist over the march positions dist = step, 2 step, ... <= limit
// (at least one step, so a light straight above still sees the receiver's surroundings, as the
// pyramid's first sample does), starting from `best`. Stops early once even the field's highest
// point could not beat it. Eight positions per loop iteration: llvmpipe ends every loop of an
// invocation after 65535 iterations in total (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS, shared by
// all loops), which a one-position loop over 32 directions reaches at 2048 positions each.
float hf_march(ivec2 p, int j, float limit, float best) {
    vec2 d = hf_dir(j);
    float step = params.horizon.z;
    float rise = (bounds.b.x - hf_h0) * params.grid.w;
    int count = max(int(floor(limit / step)), 1);
    bool stop = false;
    for (int base = 1; base <= count && !stop; base += 8) {
        HF_MARCH_AT(0) HF_MARCH_AT(1) HF_MARCH_AT(2) HF_MARCH_AT(3)
        HF_MARCH_AT(4) HF_MARCH_AT(5) HF_MARCH_AT(6) HF_MARCH_AT(7)
    }
    return best;
}

// The same field as the pyramid's: clamped to the edge beyond the border (the thesis's terrain
// "extending to infinity"), searched as far as the pyramid's farthest sample, res texels.
float hf_horizon_env(ivec2 p, int j) {
    float limit = params.horizon.w > 0.0 ? params.horizon.w : float(hf_res());
    return atan(hf_march(p, j, limit, 0.0));
}

// Marched to the light's planar distance, at most twice the field's width (beyond that the
// edge-clamped field adds nothing the march has not seen).
float hf_horizon_light(ivec2 p, int j, float d_li) {
    float limit = min(d_li, params.horizon.w > 0.0 ? params.horizon.w : 2.0 * float(hf_res()));
    return atan(hf_march(p, j, limit, -1e30));
}
#endif  // HF_BRUTE

#endif
