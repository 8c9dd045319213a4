// Shared by the height-field lighting passes (the height-field thesis): parameters, bilinear height fetches,
// normals, wedge-table lookup, z-rotation with per-direction tables, the truncated SH product
// (the SH core's sh_product over this file's term list).
// The CPU mirror is src/heightfield/cpu.rs; conventions are those of common/sh.glsl (SH frame
// z up, world -> SH (x, -z, y)). Texel (i, j) of the field lies at world
// (origin.x + i * spacing, h, origin.z + j * spacing); azimuth phi (SH frame) walks the texel
// grid along (cos phi, -sin phi).
#ifndef PENUMBRA_HF_COMMON_GLSL
#define PENUMBRA_HF_COMMON_GLSL

#include "common/sh.glsl"

const int HF_MAX_LEVELS = 61;
const int HF_MAX_NPHI = 64;
const int HF_MAX_BANDS = 6;
const int HF_MAX_COEFFS = 36;
const float HF_HALF_PI = 1.5707963267948966;

// Matches `PassParams` in src/heightfield/gpu.rs.
layout(set = 0, binding = 0) uniform HfParams {
    ivec4 dims;            // x: samples per side, y: pyramid levels, z: nphi, w: bands
    ivec4 cfg;             // x: table nodes, y: mode (0 faithful, 1 corrected), z: product entries, w: level step
    vec4 grid;             // x: spacing (m), y: world x of texel 0, z: world z of texel 0, w: 1 / spacing
    vec4 horizon;          // x: level offset lo, y: ln(s_r), z: march step (texels), w: march limit (texels, 0 = field)
    vec4 light_pos;        // xyz: sphere centre (world), w: radius (m)
    vec4 light_radiance;   // rgb: sphere radiance, w: world y of height 0 (the field's translation)
    vec4 window[2];        // the transfer window's factor per band, bands 0-7 (1: none)
    vec4 dirs[HF_MAX_NPHI];          // x: cos phi, y: sin phi (SH frame)
    vec4 rot[HF_MAX_NPHI * 3];       // (cos m phi, sin m phi), m = 1..5, packed two per vec4
    vec4 samples[HF_MAX_LEVELS];     // x: distance d_i (texels), y: 1 / d_i, z: pyramid level of sample i
} params;

#ifndef HF_HORIZON_ONLY
// Wedge table: table_nodes^2 entries of bands^2 coefficients, entry (a, b) for left horizon node a
// and right horizon node b.
layout(set = 0, binding = 1, std430) readonly buffer WedgeTable { float v[]; } wedge;
// Non-zero Gamma_ijk (i, j, k < bands^2) of the triple product, x: i | j << 8 | k << 16,
// y: float bits of the value.
layout(set = 0, binding = 2, std430) readonly buffer Product { uvec2 e[]; } product;
#endif
// Level-0 heights (metres), texelFetch only.
layout(set = 0, binding = 3) uniform sampler2D heights;

// Bilinear height fetches through the sampler (one filtered fetch; when the device can filter
// R32_SFLOAT) or as four texel fetches blended in the shader (bit-exact with the CPU mirror).
layout(constant_id = 0) const bool HF_HW_BILINEAR = false;

int hf_res() { return params.dims.x; }

float hf_height_texel(ivec2 p) {
    int r = hf_res() - 1;
    return texelFetch(heights, clamp(p, ivec2(0), ivec2(r)), 0).r;
}

// Bilinear level-0 height at continuous texel coordinates (texel centres at integers), clamped
// to the edge: the surface the brute-force march and the reference see.
float hf_height_bilinear(vec2 q) {
    if (HF_HW_BILINEAR) return texture(heights, (q + 0.5) / float(hf_res())).r;
    vec2 f = floor(q);
    vec2 t = q - f;
    ivec2 p = ivec2(f);
    float a = mix(hf_height_texel(p), hf_height_texel(p + ivec2(1, 0)), t.x);
    float b = mix(hf_height_texel(p + ivec2(0, 1)), hf_height_texel(p + ivec2(1, 1)), t.x);
    return mix(a, b, t.y);
}

// Unit normal in the SH frame from central differences of the level-0 heights (clamped
// neighbours), as the mesh's vertex normals.
vec3 hf_normal_sh(ivec2 p) {
    float dx = (hf_height_texel(p + ivec2(1, 0)) - hf_height_texel(p - ivec2(1, 0))) * 0.5 * params.grid.w;
    float dz = (hf_height_texel(p + ivec2(0, 1)) - hf_height_texel(p - ivec2(0, 1))) * 0.5 * params.grid.w;
    vec3 n_world = normalize(vec3(-dx, 1.0, -dz));
    return sh_world_to_sh(n_world);
}

vec3 hf_world_pos(ivec2 p) {
    return vec3(params.grid.y + float(p.x) * params.grid.x, params.light_radiance.w + hf_height_texel(p), params.grid.z + float(p.y) * params.grid.x);
}

// Texel-space step of azimuth direction j.
vec2 hf_dir(int j) { return vec2(params.dirs[j].x, -params.dirs[j].y); }

#ifndef HF_HORIZON_ONLY
// Per-invocation work arrays at module scope: GLSL copies array arguments in and out of every
// call, which on a CPU driver costs more than the arithmetic, so the helpers below work on these.
float hf_v[HF_MAX_COEFFS];    // one wedge
float hf_vis[HF_MAX_COEFFS];  // the visibility V
float hf_c[HF_MAX_COEFFS];    // the clamped cosine C about the normal
float hf_t[HF_MAX_COEFFS];    // the transfer T = V * C
float hf_hz[HF_MAX_NPHI];     // horizon angle per direction

// hf_v = the wedge-table coefficients for horizons (wl, wr) over the table's range [lo, hi]:
// the nearest node pair in faithful mode, bilinear between the four around them otherwise.
void hf_wedge(float wl, float wr, float lo, float hi) {
    int n = params.cfg.x;
    int nc = params.dims.w * params.dims.w;
    float scale = float(n - 1) / (hi - lo);
    float xl = clamp((wl - lo) * scale, 0.0, float(n - 1));
    float xr = clamp((wr - lo) * scale, 0.0, float(n - 1));
    if (params.cfg.y == 0) {
        int base = (int(floor(xl + 0.5)) * n + int(floor(xr + 0.5))) * nc;
        for (int k = 0; k < nc; ++k) hf_v[k] = wedge.v[base + k];
    } else {
        int a0 = clamp(int(floor(xl)), 0, n - 2), b0 = clamp(int(floor(xr)), 0, n - 2);
        float ta = xl - float(a0), tb = xr - float(b0);
        float w00 = (1.0 - ta) * (1.0 - tb), w01 = (1.0 - ta) * tb, w10 = ta * (1.0 - tb), w11 = ta * tb;
        int e00 = (a0 * n + b0) * nc, e01 = e00 + nc, e10 = e00 + n * nc, e11 = e10 + nc;
        for (int k = 0; k < nc; ++k) {
            hf_v[k] = w00 * wedge.v[e00 + k] + w01 * wedge.v[e01 + k] + w10 * wedge.v[e10 + k] + w11 * wedge.v[e11 + k];
        }
    }
}

// hf_vis += hf_v rotated about z by phi_j (phi -> phi + phi_j), with the precomputed
// cos/sin m phi_j (the height-field thesis section 1.6).
void hf_accumulate_rotated(int j) {
    int bands = params.dims.w;
    hf_vis[0] += hf_v[0];
    for (int l = 1; l < bands; ++l) hf_vis[l * (l + 1)] += hf_v[l * (l + 1)];
    for (int m = 1; m < bands; ++m) {
        vec4 packed = params.rot[j * 3 + (m - 1) / 2];
        vec2 e = ((m - 1) % 2 == 0) ? packed.xy : packed.zw;
        for (int l = m; l < bands; ++l) {
            int ip = l * (l + 1) + m, im = l * (l + 1) - m;
            float a = hf_v[ip], b = hf_v[im];
            hf_vis[ip] += a * e.x - b * e.y;
            hf_vis[im] += a * e.y + b * e.x;
        }
    }
}

// hf_vis = sum_j R_{phi_j} v(hz_j, hz_{j+1}) (Eq. 4.19).
void hf_visibility(float lo, float hi) {
    int nphi = params.dims.z;
    for (int k = 0; k < HF_MAX_COEFFS; ++k) hf_vis[k] = 0.0;
    for (int j = 0; j < nphi; ++j) {
        hf_wedge(hf_hz[j], hf_hz[(j + 1) % nphi], lo, hi);
        hf_accumulate_rotated(j);
    }
}

// `out_c` = the zonal function zh (bands values) rotated to `axis` (SH frame).
void hf_zh_rotate_into_c(float zh[SH_MAX_BANDS], vec3 axis) {
    float full[SH_MAX_COEFFS];
    sh_zh_rotate(zh, params.dims.w, axis, full);
    for (int k = 0; k < HF_MAX_COEFFS; ++k) hf_c[k] = full[k];
}

// hf_c = the clamped cosine about the normal divided by pi (the Lambert BRDF's 1/pi; the albedo
// is applied when the mesh is drawn): the height-field thesis section 5.2's (1/pi)[0.886227, 1.02333, 0.495416, 0].
void hf_transfer_cosine(vec3 n_sh) {
    float zh[SH_MAX_BANDS];
    for (int l = 0; l < SH_MAX_BANDS; ++l) zh[l] = SH_CLAMPED_COS_ZH[l] / SH_PI;
    hf_zh_rotate_into_c(zh, n_sh);
}

// The term list for the SH core's sh_product (built by sh::product_terms).
uvec2 sh_product_term(int e) { return product.e[e]; }

// hf_t = hf_vis * hf_c, the truncated SH product (sh_product: the same terms in the same order
// as before it moved to the core). Its arrays are SH_MAX_COEFFS long, so the operands are
// copied across once per texel: negligible next to the product's thousands of terms.
void hf_product() {
    float a[SH_MAX_COEFFS], b[SH_MAX_COEFFS], t[SH_MAX_COEFFS];
    for (int k = 0; k < SH_MAX_COEFFS; ++k) {
        a[k] = k < HF_MAX_COEFFS ? hf_vis[k] : 0.0;
        b[k] = k < HF_MAX_COEFFS ? hf_c[k] : 0.0;
    }
    sh_product(a, b, params.cfg.z, t);
    for (int k = 0; k < HF_MAX_COEFFS; ++k) hf_t[k] = t[k];
}
#endif  // HF_HORIZON_ONLY

#endif
