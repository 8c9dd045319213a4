// Spherical harmonics for penumbra's GPU passes. The CPU twin is src/sh/ (its mod.rs documents
// the conventions in full); src/sh/tests/glsl.rs checks the constants below against it and
// tests/sh_gpu.rs every function on the device. Contents: basis evaluation (loop to 8 bands,
// unrolled 4), z-rotation, ZH rotation, general rotation by a 3x3 matrix (Ivanic-Ruedenberg, up
// to SH_ROTATE_MAX_BANDS = 8 bands), clamped-cosine / Lambert / cap ZH, Hanning and Lanczos
// windows, the triple product over the CPU's term list (sh::product_terms), texel solid angles
// and directions of equirect and cube maps.
//
// * Real SH, orthonormal over the sphere, Condon-Shortley phase included:
//   y_1^{-1} = -0.488603 y, y_1^0 = +0.488603 z, y_1^1 = -0.488603 x.
// * Flat index l(l+1)+m; "n bands" = l < n = n*n coefficients. Loop-based helpers take up to
//   SH_MAX_BANDS = 8 bands (64 coefficients); the *16 helpers are unrolled for 4 bands.
// * SH frame z up (theta from +z, phi from +x toward +y). penumbra's world is y up:
//   sh = (x, -z, y) (sh_world_to_sh), world = (x, z, -y) (sh_sh_to_world).
// * Rotations rotate the function: a lobe about +z rotated to `axis` peaks at `axis`;
//   z-rotation by a maps phi -> phi + a.
// * Coefficients are plain projections c_i = integral f y_i; irradiance E_lm = A_l L_lm with
//   SH_LAMBERT_A; Lambertian exit radiance is rho/pi * E.
#ifndef PENUMBRA_SH_GLSL
#define PENUMBRA_SH_GLSL

const float SH_PI = 3.14159265358979323846;
const int SH_MAX_BANDS = 8;
const int SH_MAX_COEFFS = 64;

// Cartesian constants of the unrolled 4-band basis (exact values in the comments).
const float SH_Y00 = 0.28209479177387814;     // 1/(2 sqrt(pi))
const float SH_C1 = 0.4886025119029199;       // sqrt(3/(4 pi))
const float SH_C2_XY = 1.0925484305920792;    // sqrt(15/pi)/2
const float SH_C2_ZZ = 0.31539156525252005;   // sqrt(5/pi)/4, times (3z^2 - 1)
const float SH_C2_XXYY = 0.5462742152960396;  // sqrt(15/pi)/4
const float SH_C3_3 = 0.5900435899266435;     // sqrt(35/(2 pi))/4
const float SH_C3_XYZ = 2.890611442640554;    // sqrt(105/pi)/2
const float SH_C3_1 = 0.4570457994644658;     // sqrt(21/(2 pi))/4
const float SH_C3_0 = 0.3731763325901154;     // sqrt(7/pi)/4
const float SH_C3_2 = 1.445305721320277;      // sqrt(105/pi)/4

// sqrt(4 pi / (2l+1)): the ZH-rotation and convolution factor per band.
const float SH_ZH_ROT_K[8] = float[8](3.5449077018110318, 2.046653415892977, 1.5853309190424043,
    1.3398491713813576, 1.1816359006036774, 1.0688298875771143, 0.9831804988974527, 0.9152912328637689);
// Clamped cosine max(cos theta, 0) about +z, ZH z_l: sqrt(pi)/2, sqrt(pi/3), sqrt(5 pi)/8, 0, ...
const float SH_CLAMPED_COS_ZH[8] = float[8](0.8862269254527579, 1.0233267079464885, 0.4954159122007514,
    0.0, -0.11077836568159474, 0.0, 0.04992713470963627, 0.0);
// Lambert kernel A_l = SH_ZH_ROT_K[l] * SH_CLAMPED_COS_ZH[l]: pi, 2pi/3, pi/4, 0, -pi/24, 0, pi/64, 0.
const float SH_LAMBERT_A[8] = float[8](3.141592653589793, 2.0943951023931953, 0.7853981633974483,
    0.0, -0.1308996938995747, 0.0, 0.04908738521234052, 0.0);

// Spherical-cap ZH factors (sh_cap_zh4): sqrt(pi), sqrt(3 pi)/2, sqrt(5 pi)/2, sqrt(7 pi)/8.
const float SH_CAP_K[4] = float[4](1.7724538509055159, 1.5349900619197328, 1.9816636488030055, 0.5861840124793439);

vec3 sh_world_to_sh(vec3 d) { return vec3(d.x, -d.z, d.y); }
vec3 sh_sh_to_world(vec3 d) { return vec3(d.x, d.z, -d.y); }

// Unit direction; zero or non-finite input becomes +z (as on the CPU).
vec3 sh_unit(vec3 d) {
    float len2 = dot(d, d);
    return (len2 > 1e-30 && len2 < 1e30) ? d * inversesqrt(len2) : vec3(0.0, 0.0, 1.0);
}

// All basis functions of `bands` (clamped to 1..8) bands at `dir`; y[i] = 0 beyond bands^2.
// Normalised associated-Legendre recurrence (stable, no factorials) with the azimuthal
// factors from (x + iy)^m, exactly as src/sh/basis.rs.
void sh_eval_bands(vec3 dir, int bands, out float y[SH_MAX_COEFFS]) {
    for (int i = 0; i < SH_MAX_COEFFS; ++i) y[i] = 0.0;
    vec3 d = sh_unit(dir);
    int nb = clamp(bands, 1, SH_MAX_BANDS);
    float pmm = SH_Y00;
    vec2 cs = vec2(1.0, 0.0);  // (cos m phi, sin m phi) * sin^m theta
    for (int m = 0; m < nb; ++m) {
        if (m > 0) {
            pmm *= -sqrt(float(2 * m + 1) / float(2 * m));
            cs = vec2(d.x * cs.x - d.y * cs.y, d.x * cs.y + d.y * cs.x);
        }
        float p_prev = 0.0;
        float p = pmm;
        for (int l = m; l < nb; ++l) {
            if (l == m + 1) {
                p_prev = p;
                p = sqrt(float(2 * m + 3)) * d.z * p_prev;
            } else if (l > m + 1) {
                float lf = float(l), mf = float(m);
                float a = sqrt((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf));
                float b = sqrt(((lf - 1.0) * (lf - 1.0) - mf * mf) / (4.0 * (lf - 1.0) * (lf - 1.0) - 1.0));
                float next = a * (d.z * p - b * p_prev);
                p_prev = p;
                p = next;
            }
            int centre = l * (l + 1);
            if (m == 0) {
                y[centre] = p;
            } else {
                y[centre + m] = 1.4142135623730951 * p * cs.x;
                y[centre - m] = 1.4142135623730951 * p * cs.y;
            }
        }
    }
}

// The 16 basis functions of 4 bands (l <= 3), unrolled Cartesian polynomials.
void sh_eval16(vec3 dir, out float y[16]) {
    vec3 d = sh_unit(dir);
    float x = d.x, yy = d.y, z = d.z;
    y[0] = SH_Y00;
    y[1] = -SH_C1 * yy;
    y[2] = SH_C1 * z;
    y[3] = -SH_C1 * x;
    y[4] = SH_C2_XY * x * yy;
    y[5] = -SH_C2_XY * yy * z;
    y[6] = SH_C2_ZZ * (3.0 * z * z - 1.0);
    y[7] = -SH_C2_XY * x * z;
    y[8] = SH_C2_XXYY * (x * x - yy * yy);
    y[9] = -SH_C3_3 * yy * (3.0 * x * x - yy * yy);
    y[10] = SH_C3_XYZ * x * yy * z;
    y[11] = -SH_C3_1 * yy * (5.0 * z * z - 1.0);
    y[12] = SH_C3_0 * z * (5.0 * z * z - 3.0);
    y[13] = -SH_C3_1 * x * (5.0 * z * z - 1.0);
    y[14] = SH_C3_2 * z * (x * x - yy * yy);
    y[15] = -SH_C3_3 * x * (x * x - 3.0 * yy * yy);
}

// Reconstruction sum c_i y_i(dir).
float sh_eval_sum(float c[SH_MAX_COEFFS], int bands, vec3 dir) {
    float y[SH_MAX_COEFFS];
    sh_eval_bands(dir, bands, y);
    int n = clamp(bands, 1, SH_MAX_BANDS);
    float s = 0.0;
    for (int i = 0; i < n * n; ++i) s += c[i] * y[i];
    return s;
}

float sh_eval_sum16(float c[16], vec3 dir) {
    float y[16];
    sh_eval16(dir, y);
    float s = 0.0;
    for (int i = 0; i < 16; ++i) s += c[i] * y[i];
    return s;
}

// Integral of the product of two 4-band functions.
float sh_dot16(float a[16], float b[16]) {
    float s = 0.0;
    for (int i = 0; i < 16; ++i) s += a[i] * b[i];
    return s;
}

// z-rotation by `angle` (phi -> phi + angle): c'_m = c_m cos ma - c_-m sin ma,
// c'_-m = c_m sin ma + c_-m cos ma (the height-field thesis section 1.6). cos/sin of m*angle by angle addition.
void sh_rotate_z(inout float c[SH_MAX_COEFFS], int bands, float angle) {
    int nb = clamp(bands, 1, SH_MAX_BANDS);
    vec2 e1 = vec2(cos(angle), sin(angle));
    vec2 e = e1;
    for (int m = 1; m < nb; ++m) {
        for (int l = m; l < nb; ++l) {
            int ip = l * (l + 1) + m, im = l * (l + 1) - m;
            float a = c[ip], b = c[im];
            c[ip] = a * e.x - b * e.y;
            c[im] = a * e.y + b * e.x;
        }
        e = vec2(e.x * e1.x - e.y * e1.y, e.x * e1.y + e.y * e1.x);
    }
}

// 4-band z-rotation with precomputed (cos m a, sin m a) for m = 1, 2, 3 (the height-field thesis precomputes
// them per azimuth direction).
void sh_rotate_z16_cs(inout float c[16], vec2 e1, vec2 e2, vec2 e3) {
    float a, b;
    // m = 1: pairs (3,1), (7,5), (13,11)
    a = c[3];  b = c[1];  c[3] = a * e1.x - b * e1.y;  c[1] = a * e1.y + b * e1.x;
    a = c[7];  b = c[5];  c[7] = a * e1.x - b * e1.y;  c[5] = a * e1.y + b * e1.x;
    a = c[13]; b = c[11]; c[13] = a * e1.x - b * e1.y; c[11] = a * e1.y + b * e1.x;
    // m = 2: pairs (8,4), (14,10)
    a = c[8];  b = c[4];  c[8] = a * e2.x - b * e2.y;  c[4] = a * e2.y + b * e2.x;
    a = c[14]; b = c[10]; c[14] = a * e2.x - b * e2.y; c[10] = a * e2.y + b * e2.x;
    // m = 3: pair (15,9)
    a = c[15]; b = c[9];  c[15] = a * e3.x - b * e3.y; c[9] = a * e3.y + b * e3.x;
}

void sh_rotate_z16(inout float c[16], float angle) {
    vec2 e1 = vec2(cos(angle), sin(angle));
    vec2 e2 = vec2(e1.x * e1.x - e1.y * e1.y, 2.0 * e1.x * e1.y);
    vec2 e3 = vec2(e2.x * e1.x - e2.y * e1.y, e2.x * e1.y + e2.y * e1.x);
    sh_rotate_z16_cs(c, e1, e2, e3);
}

// Zonal function with ZH coefficients zh[l] about +z, rotated to `axis`:
// c_lm = sqrt(4 pi/(2l+1)) z_l y_lm(axis).
void sh_zh_rotate(float zh[SH_MAX_BANDS], int bands, vec3 axis, out float c[SH_MAX_COEFFS]) {
    sh_eval_bands(axis, bands, c);
    int nb = clamp(bands, 1, SH_MAX_BANDS);
    for (int l = 0; l < nb; ++l) {
        float k = SH_ZH_ROT_K[l] * zh[l];
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) c[i] *= k;
    }
}

void sh_zh_rotate16(vec4 zh, vec3 axis, out float c[16]) {
    sh_eval16(axis, c);
    c[0] *= SH_ZH_ROT_K[0] * zh.x;
    for (int i = 1; i < 4; ++i) c[i] *= SH_ZH_ROT_K[1] * zh.y;
    for (int i = 4; i < 9; ++i) c[i] *= SH_ZH_ROT_K[2] * zh.z;
    for (int i = 9; i < 16; ++i) c[i] *= SH_ZH_ROT_K[3] * zh.w;
}

// Clamped cosine about `normal` (4 bands): the Lambert transfer of an unoccluded receiver.
void sh_clamped_cosine16(vec3 normal, out float c[16]) {
    sh_zh_rotate16(vec4(SH_CLAMPED_COS_ZH[0], SH_CLAMPED_COS_ZH[1], SH_CLAMPED_COS_ZH[2], SH_CLAMPED_COS_ZH[3]),
                   normal, c);
}

// ZH of a spherical cap (unit radiance) with cos(half-angle) = cos_alpha, 4 bands
// (the height-field thesis Appendix A.1): sqrt(pi)(1-c), sqrt(3pi)/2 s^2, sqrt(5pi)/2 c s^2,
// sqrt(7pi)/8 s^2 (5c^2 - 1). cos_alpha is clamped to [-1, 1].
vec4 sh_cap_zh4(float cos_alpha) {
    float c = clamp(cos_alpha, -1.0, 1.0);
    float s2 = max(1.0 - c * c, 0.0);
    return vec4(SH_CAP_K[0] * (1.0 - c), SH_CAP_K[1] * s2, SH_CAP_K[2] * c * s2,
                SH_CAP_K[3] * s2 * (5.0 * c * c - 1.0));
}

// Exact solid angle of any texel in row `y` of a width x height equirectangular map:
// (2 pi / width)(cos t0 - cos t1) = (2 pi / width) 2 sin((t0+t1)/2) sin((t1-t0)/2)
// (the product form has no cancellation in float at the poles).
float sh_equirect_texel_solid_angle(int y, int width, int height) {
    float h = float(max(height, 1));
    float dt = SH_PI / h;
    return 2.0 * SH_PI / float(max(width, 1)) * 2.0 * sin((float(y) + 0.5) * dt) * sin(0.5 * dt);
}

// World direction of the centre of texel (x, y), penumbra's equirect mapping
// (v = 0 is +y, u = 0.5 is -z, u = 0.75 is +x).
vec3 sh_equirect_texel_dir_world(ivec2 texel, ivec2 size) {
    vec2 uv = (vec2(texel) + 0.5) / vec2(max(size, ivec2(1)));
    float phi = (uv.x - 0.5) * 2.0 * SH_PI;
    float theta = uv.y * SH_PI;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

// Un-normalised world direction of the centre of texel (x, y) of cube face `face` (Vulkan
// layer order +X, -X, +Y, -Y, +Z, -Z and the spec's face-selection table).
vec3 sh_cube_texel_dir_world(int face, ivec2 texel, int size) {
    vec2 st = 2.0 * (vec2(texel) + 0.5) / float(max(size, 1)) - 1.0;
    float sc = st.x, tc = st.y;
    switch (clamp(face, 0, 5)) {
        case 0: return vec3(1.0, -tc, -sc);
        case 1: return vec3(-1.0, -tc, sc);
        case 2: return vec3(sc, 1.0, tc);
        case 3: return vec3(sc, -1.0, -tc);
        case 4: return vec3(sc, -tc, 1.0);
        default: return vec3(-sc, -tc, -1.0);
    }
}

// Solid angle of the triangle a, b, c (Van Oosterom-Strackee): tan(omega/2) =
// a.(b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|). `triple` is a.(b x c), passed in
// so the caller can compute it exactly from edge vectors.
float sh_triangle_solid_angle(vec3 a, vec3 b, vec3 c, float triple) {
    float la = length(a), lb = length(b), lc = length(c);
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    // Small triangles (every texel of a face 8 texels or more wide) by the odd series of atan,
    // whose truncation (r^9/9 < 2e-9 relative at r = 1/8) is below float rounding: built-in
    // atan need only be good to a few ulp of pi, and lavapipe's is 2e-5 relative here.
    float r = triple / den;
    if (den > 0.0 && abs(r) < 0.125) {
        float r2 = r * r;
        return 2.0 * r * (1.0 - r2 * (1.0 / 3.0 - r2 * (0.2 - r2 * (1.0 / 7.0))));
    }
    return 2.0 * atan(triple, den);
}

// Exact solid angle of texel (x, y) of a size^2 cube face (the same on every face). Equal to the
// atan-area formula of the CPU (cube_texel_solid_angle); evaluated as two triangles on the
// z = 1 face plane, whose triple products are exactly the edge products h^2, because the
// four-term atan formula cancels catastrophically in float for large maps (~1% at 1024^2).
// Measured: 2e-6 relative in a float port; 2e-5 on lavapipe before the small-angle series.
float sh_cube_texel_solid_angle(ivec2 texel, int size) {
    float n = float(max(size, 1));
    float x0 = 2.0 * float(texel.x) / n - 1.0, x1 = 2.0 * float(texel.x + 1) / n - 1.0;
    float y0 = 2.0 * float(texel.y) / n - 1.0, y1 = 2.0 * float(texel.y + 1) / n - 1.0;
    vec3 p00 = vec3(x0, y0, 1.0), p10 = vec3(x1, y0, 1.0), p11 = vec3(x1, y1, 1.0), p01 = vec3(x0, y1, 1.0);
    float h = 2.0 / n;
    float area2 = h * h;  // exact, unlike (x1 - x0)(y1 - y0) in float
    return sh_triangle_solid_angle(p00, p10, p11, area2) + sh_triangle_solid_angle(p00, p11, p01, area2);
}

// ---- Windowing against ringing (src/sh/window.rs; Sloan, "Stupid SH Tricks"). Width w in bands,
// usually w = the number of bands used. A NaN or non-positive width (an error on the CPU) gives 0
// for every band, so a bad width blanks the result instead of passing it through unwindowed.

// Hanning: (1 + cos(pi l / w)) / 2 for l < w, else 0.
float sh_hanning(int l, float width) {
    if (!(width > 0.0) || float(l) >= width) return 0.0;
    return 0.5 * (1.0 + cos(SH_PI * float(l) / width));
}

// Lanczos sigma factor: sinc(l / w) = sin(pi l / w) / (pi l / w) for l < w (1 at l = 0), else 0.
float sh_lanczos(int l, float width) {
    if (!(width > 0.0) || float(l) >= width) return 0.0;
    if (l == 0) return 1.0;
    float x = SH_PI * float(l) / width;
    return sin(x) / x;
}

// Scales band l (< bands, clamped to 1..8) of c by window[l].
void sh_apply_window(inout float c[SH_MAX_COEFFS], int bands, float window[SH_MAX_BANDS]) {
    int nb = clamp(bands, 1, SH_MAX_BANDS);
    for (int l = 0; l < nb; ++l) {
        for (int i = l * l; i < (l + 1) * (l + 1); ++i) c[i] *= window[l];
    }
}

// ---- Triple product (a * b)_k = sum_ij a_i b_j Gamma_ijk (src/sh/product.rs) over the sparse
// term list that sh::product_terms builds on the CPU: one uvec2 per ordered (i, j, k) with
// Gamma_ijk != 0, x = i | j << 8 | k << 16, y = the float bits of Gamma_ijk. The list's band
// count sets the bands of all three vectors (everything else in c is 0).
//
// A storage buffer cannot be passed to a function, so a shader that calls sh_product defines
//     uvec2 sh_product_term(int e) { return my_list.e[e]; }
// (shaders that do not call it need not). Terms with an index beyond SH_MAX_COEFFS (a list built
// for more than 8 bands) are skipped rather than read out of bounds.
uvec2 sh_product_term(int e);

void sh_product(float a[SH_MAX_COEFFS], float b[SH_MAX_COEFFS], int count, out float c[SH_MAX_COEFFS]) {
    for (int k = 0; k < SH_MAX_COEFFS; ++k) c[k] = 0.0;
    for (int e = 0; e < count; ++e) {
        uvec2 g = sh_product_term(e);
        if ((g.x & 0xffc0c0c0u) != 0u) continue;
        int i = int(g.x & 0xffu), j = int((g.x >> 8) & 0xffu), k = int(g.x >> 16);
        c[k] += uintBitsToFloat(g.y) * a[i] * b[j];
    }
}

// ---- General rotation by a 3x3 rotation matrix: the Ivanic-Ruedenberg recurrence of
// src/sh/rotation.rs (ShRotation), the same algorithm in float. Band l's (2l+1)^2 block comes from
// band 1 (R itself, rows/columns in (y, z, x) order) and band l - 1; the recurrence is for the
// basis without the Condon-Shortley phase, so each band is conjugated by diag((-1)^m).
//
// Only two blocks are alive at a time (band l - 1 and band l), in module-scope arrays: function
// arguments are copied in and out, which would cost more than the recurrence. Their size is set
// by SH_ROTATE_MAX_BANDS (default 8, the library's max; define it as 2..8 before the first include
// to shrink them): 2 * (2 * max - 1)^2 floats, 450 at 8 bands, 98 at 4 bands. On a discrete GPU
// that much per-invocation memory spills to scratch; a pass rotating many vectors by one R should
// build the blocks once (per workgroup, or on the CPU with ShRotation) and multiply.
#ifndef SH_ROTATE_MAX_BANDS
#define SH_ROTATE_MAX_BANDS 8
#endif
#if SH_ROTATE_MAX_BANDS < 2 || SH_ROTATE_MAX_BANDS > 8
#error SH_ROTATE_MAX_BANDS must be in 2..8
#endif
#define SH_ROT_W (2 * SH_ROTATE_MAX_BANDS - 1)  // width of the widest block
float sh_rot_r1[9];                       // band 1, (m + 1) * 3 + (n + 1), no CS phase
float sh_rot_prev[SH_ROT_W * SH_ROT_W];   // band l - 1, width 2l - 1
float sh_rot_cur[SH_ROT_W * SH_ROT_W];    // band l, width 2l + 1

float sh_rot_r1_at(int m, int n) { return sh_rot_r1[(m + 1) * 3 + n + 1]; }
float sh_rot_prev_at(int l, int a, int b) { return sh_rot_prev[(a + l - 1) * (2 * l - 1) + b + l - 1]; }

// Ivanic-Ruedenberg's P (their Table 2) for band l.
float sh_rot_p(int l, int i, int a, int b) {
    if (b == l) return sh_rot_r1_at(i, 1) * sh_rot_prev_at(l, a, l - 1) - sh_rot_r1_at(i, -1) * sh_rot_prev_at(l, a, 1 - l);
    if (b == -l) return sh_rot_r1_at(i, 1) * sh_rot_prev_at(l, a, 1 - l) + sh_rot_r1_at(i, -1) * sh_rot_prev_at(l, a, l - 1);
    return sh_rot_r1_at(i, 0) * sh_rot_prev_at(l, a, b);
}

// sh_rot_cur = the block of band l >= 2 from sh_rot_prev. u, v, w as on the CPU (with the 1998
// corrections); a term is skipped exactly where its coefficient is zero, which is also where
// its P would index outside band l - 1.
void sh_rot_band(int l) {
    int w = 2 * l + 1;
    for (int m = -l; m <= l; ++m) {
        int am = abs(m);
        float d0 = m == 0 ? 1.0 : 0.0;
        for (int n = -l; n <= l; ++n) {
            float denom = abs(n) == l ? float(2 * l * (2 * l - 1)) : float((l + n) * (l - n));
            float val = 0.0;
            if (am < l) val += sqrt(float((l + m) * (l - m)) / denom) * sh_rot_p(l, 0, m, n);
            float v = 0.5 * sqrt((1.0 + d0) * float((l + am - 1) * (l + am)) / denom) * (1.0 - 2.0 * d0);
            float vv;
            if (m == 0) {
                vv = sh_rot_p(l, 1, 1, n) + sh_rot_p(l, -1, -1, n);
            } else if (m == 1) {
                vv = sh_rot_p(l, 1, 0, n) * 1.4142135623730951;
            } else if (m > 1) {
                vv = sh_rot_p(l, 1, m - 1, n) - sh_rot_p(l, -1, 1 - m, n);
            } else if (m == -1) {
                vv = sh_rot_p(l, -1, 0, n) * 1.4142135623730951;
            } else {
                vv = sh_rot_p(l, 1, m + 1, n) + sh_rot_p(l, -1, -m - 1, n);
            }
            val += v * vv;
            if (m != 0 && am < l - 1) {
                float ww = -0.5 * sqrt(float((l - am - 1) * (l - am)) / denom);
                float wv = m > 0 ? sh_rot_p(l, 1, m + 1, n) + sh_rot_p(l, -1, -m - 1, n)
                                 : sh_rot_p(l, 1, m - 1, n) - sh_rot_p(l, -1, 1 - m, n);
                val += ww * wv;
            }
            sh_rot_cur[(m + l) * w + n + l] = val;
        }
    }
}

// Rotates the function c (bands clamped to 1..8) by the rotation r (SH frame): afterwards
// c(w) holds the old c(r^T w), so a lobe about axis a ends up about r a (mod.rs's convention).
// r is re-orthonormalised as on the CPU (Gram-Schmidt on the columns); a matrix far from a
// rotation gives a meaningless result (the CPU refuses it). Bands from SH_ROTATE_MAX_BANDS up to
// `bands` are set to 0 (a missing band is visible, a silently unrotated one is not); coefficients
// beyond bands^2 are untouched.
void sh_rotate(mat3 r, int bands, inout float c[SH_MAX_COEFFS]) {
    int nb = clamp(bands, 1, SH_MAX_BANDS);
    int nr = min(nb, SH_ROTATE_MAX_BANDS);
    for (int i = nr * nr; i < nb * nb; ++i) c[i] = 0.0;
    if (nr < 2) return;
    vec3 c0 = normalize(r[0]);
    vec3 c1 = normalize(r[1] - c0 * dot(c0, r[1]));
    mat3 q = mat3(c0, c1, cross(c0, c1));
    // Band 1 in (y, z, x) order; q[col][row].
    int perm[3] = int[3](1, 2, 0);
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) sh_rot_r1[i * 3 + j] = q[perm[j]][perm[i]];
    }
    for (int k = 0; k < 9; ++k) sh_rot_prev[k] = sh_rot_r1[k];
    float t[SH_ROT_W];
    for (int l = 1; l < nr; ++l) {
        int w = 2 * l + 1, base = l * l;
        if (l >= 2) sh_rot_band(l);
        else for (int k = 0; k < 9; ++k) sh_rot_cur[k] = sh_rot_r1[k];
        // c_band = D M D c_band, D = diag((-1)^m); (-1)^m = (-1)^(i + l) for row i = m + l.
        for (int i = 0; i < w; ++i) {
            float acc = 0.0;
            for (int j = 0; j < w; ++j) {
                float s = ((i + j) & 1) == 0 ? 1.0 : -1.0;
                acc += s * sh_rot_cur[i * w + j] * c[base + j];
            }
            t[i] = acc;
        }
        for (int i = 0; i < w; ++i) c[base + i] = t[i];
        for (int k = 0; k < w * w; ++k) sh_rot_prev[k] = sh_rot_cur[k];
    }
}

// A rotation given in penumbra's world frame (y up) as the same rotation in the SH frame:
// WORLD_TO_SH * r_world * SH_TO_WORLD, as ShRotation::from_world.
mat3 sh_rotation_from_world(mat3 r_world) {
    const mat3 world_to_sh = mat3(vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0), vec3(0.0, -1.0, 0.0));
    return world_to_sh * r_world * transpose(world_to_sh);
}

#endif  // PENUMBRA_SH_GLSL
