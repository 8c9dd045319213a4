// The per-texel lighting pass of the height-field thesis (sections 4.2-4.3, 5.2-5.3): horizons in nphi
// directions -> SH visibility from the wedge tables -> transfer V * C with the clamped cosine
// about the normal -> dot with the light. Included by env_*.comp (HF_LIGHT undefined: the
// environment, hemisphere table, horizons clamped at 0) and light_*.comp (HF_LIGHT: one sphere
// light, full-sphere table, horizons truncated at the light and signed), with HF_PYRAMID or
// HF_BRUTE choosing the horizon. With HF_HORIZON_ONLY it writes the horizons instead (tests,
// debug views): horizons[j * res^2 + y * res + x], radians.
#include "heightfield/horizon.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef HF_HORIZON_ONLY
layout(set = 0, binding = 5, std430) writeonly buffer Horizons { float h[]; } horizons;
#else
layout(set = 0, binding = 5, rgba32f) uniform writeonly image2D out_radiance;
#ifndef HF_LIGHT
// Environment radiance in SH (rgb per coefficient), from the environment-projection pass.
layout(set = 0, binding = 6, std430) readonly buffer EnvSh { vec4 c[]; } env_sh;
#endif
#endif

#ifdef HF_HORIZON_ONLY
layout(push_constant) uniform HorizonPush { int light; } horizon_push;
#endif

// ZH of a spherical cap (unit radiance) with cos(half-angle) = c, bands l < SH_MAX_BANDS:
// z_0 = sqrt(pi)(1 - c), z_l = sqrt(pi/(2l+1)) (P_{l-1}(c) - P_{l+1}(c)) (src/sh/zonal.rs).
void hf_cap_zh(float c, out float zh[SH_MAX_BANDS]) {
    float p[SH_MAX_BANDS + 1];
    p[0] = 1.0;
    p[1] = c;
    for (int k = 2; k <= SH_MAX_BANDS; ++k) p[k] = (float(2 * k - 1) * c * p[k - 1] - float(k - 1) * p[k - 2]) / float(k);
    zh[0] = sqrt(SH_PI) * (1.0 - c);
    for (int l = 1; l < SH_MAX_BANDS; ++l) zh[l] = sqrt(SH_PI / float(2 * l + 1)) * (p[l - 1] - p[l + 1]);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    int res = hf_res();
    if (p.x >= res || p.y >= res) return;
    int nphi = params.dims.z;
    hf_load_receiver(p);

#if defined(HF_HORIZON_ONLY)
    bool light = horizon_push.light != 0;
    float d_li = hf_light_planar_texels(p);
    for (int j = 0; j < nphi; ++j) {
        float w = light ? hf_horizon_light(p, j, d_li) : hf_horizon_env(p, j);
        horizons.h[j * res * res + p.y * res + p.x] = w;
    }
#else
#ifdef HF_LIGHT
    float d_li = hf_light_planar_texels(p);
    for (int j = 0; j < nphi; ++j) hf_hz[j] = hf_horizon_light(p, j, d_li);
    hf_visibility(-HF_HALF_PI, HF_HALF_PI);
#else
    for (int j = 0; j < nphi; ++j) hf_hz[j] = hf_horizon_env(p, j);
    hf_visibility(0.0, HF_HALF_PI);
#endif
    hf_transfer_cosine(hf_normal_sh(p));
    hf_product();
    int nc = params.dims.w * params.dims.w;
    // The optional window on the transfer's bands (factors of 1 without one).
    for (int l = 0; l < params.dims.w; ++l) {
        float f = params.window[l / 4][l % 4];
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) hf_t[k] *= f;
    }
    vec3 rgb = vec3(0.0);
#ifdef HF_LIGHT
    // The sphere seen from the receiver: a cap of half-angle asin(r / d), d the 3D distance to
    // the centre (corrected) or the planar one (faithful, the height-field thesis section 5.9); a receiver
    // inside the sphere sees a hemisphere toward the centre.
    vec3 pw = hf_world_pos(p);
    vec3 to = params.light_pos.xyz - pw;
    float dist3 = length(to);
    float dist = params.cfg.y != 0 ? dist3 : length(to.xz);
    float r = params.light_pos.w;
    float sin_a = dist > r ? r / dist : 1.0;
    float cos_a = sqrt(max(1.0 - sin_a * sin_a, 0.0));
    float zh[SH_MAX_BANDS];
    hf_cap_zh(cos_a, zh);
    hf_zh_rotate_into_c(zh, dist3 > 1e-12 ? sh_world_to_sh(to / dist3) : vec3(0.0, 0.0, 1.0));
    float s = 0.0;
    for (int k = 0; k < nc; ++k) s += hf_t[k] * hf_c[k];
    rgb = s * params.light_radiance.rgb;
#else
    for (int k = 0; k < nc; ++k) rgb += hf_t[k] * env_sh.c[k].rgb;
#endif
    imageStore(out_radiance, p, vec4(rgb, 1.0));
#endif
}
