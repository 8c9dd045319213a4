// Body of the check kernels for the general rotation, windows and triple product of
// common/sh.glsl (sh_ops_check.comp: SH_ROTATE_MAX_BANDS 8; sh_ops_check4.comp: 4). One
// workgroup of 64 invocations; invocation i reads its case at cases.v[i * 48 ..]:
//   +0..2   R1 (SH frame, columns)   +3..5 R2 (SH frame)   +6..8 Rw (world frame)
//   +9      x: window width w
//   +10..25 a (64 coefficients)      +26..41 b (64 coefficients)
// and writes result.values[i * 512 + k]:
//   k 0..63    sh_rotate(R1, 8, a)
//   k 64..127  sh_rotate(R2, 8, sh_rotate(R1, 8, a))
//   k 128..191 sh_rotate(identity, 8, a)
//   k 192..255 sh_rotate(R1, 4, a)  (coefficients from 16 on are a's, untouched)
//   k 256..319 sh_rotate(sh_rotation_from_world(Rw), 8, a)
//   k 320..383 sh_product(a, b) over the push constant's term count
//   k 384..391 sh_hanning(l, w), k 392..399 sh_lanczos(l, w), l = 0..7
//   k 400..463 a after sh_apply_window(a, 8, Lanczos of width w)
//   k 464..511 0
// Not used by the renderer.
#include "common/sh.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Cases { vec4 v[]; } cases;
layout(std430, set = 0, binding = 1) readonly buffer Terms { uvec2 e[]; } terms;
layout(std430, set = 0, binding = 2) writeonly buffer Result { float values[]; } result;
layout(push_constant) uniform Push { int term_count; } push;

uvec2 sh_product_term(int e) { return terms.e[e]; }

mat3 case_matrix(int base) { return mat3(cases.v[base].xyz, cases.v[base + 1].xyz, cases.v[base + 2].xyz); }

void load(int base, out float c[SH_MAX_COEFFS]) {
    for (int k = 0; k < SH_MAX_COEFFS; ++k) c[k] = cases.v[base + k / 4][k % 4];
}

void store(int base, float c[SH_MAX_COEFFS]) {
    for (int k = 0; k < SH_MAX_COEFFS; ++k) result.values[base + k] = c[k];
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    int cb = i * 48, ob = i * 512;
    float a[SH_MAX_COEFFS], b[SH_MAX_COEFFS], c[SH_MAX_COEFFS];
    load(cb + 10, a);
    load(cb + 26, b);
    mat3 r1 = case_matrix(cb), r2 = case_matrix(cb + 3), rw = case_matrix(cb + 6);
    float width = cases.v[cb + 9].x;

    c = a;
    sh_rotate(r1, 8, c);
    store(ob, c);
    sh_rotate(r2, 8, c);
    store(ob + 64, c);
    c = a;
    sh_rotate(mat3(1.0), 8, c);
    store(ob + 128, c);
    c = a;
    sh_rotate(r1, 4, c);
    store(ob + 192, c);
    c = a;
    sh_rotate(sh_rotation_from_world(rw), 8, c);
    store(ob + 256, c);

    sh_product(a, b, push.term_count, c);
    store(ob + 320, c);

    float window[SH_MAX_BANDS];
    for (int l = 0; l < SH_MAX_BANDS; ++l) {
        result.values[ob + 384 + l] = sh_hanning(l, width);
        window[l] = sh_lanczos(l, width);
        result.values[ob + 392 + l] = window[l];
    }
    c = a;
    sh_apply_window(c, 8, window);
    store(ob + 400, c);
    for (int k = 464; k < 512; ++k) result.values[ob + k] = 0.0;
}
