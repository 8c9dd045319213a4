// Check kernel for common/sh.glsl. Compiling it (build.rs does, warnings are errors) checks the
// header; dispatching it (one workgroup of 128 invocations) and comparing with src/sh/ checks
// the GPU numbers. Invocation i uses the centre of texel (i % 16, i / 16) of a 16x8 equirect map
// (world direction, converted to the SH frame) and writes result.values[i * 128 + k]:
//   k 0..63    sh_eval_bands(dir, 8)                       == sh::eval_basis(dir, 8)
//   k 64..79   sh_eval16(dir)                              == sh::eval_basis(dir, 4)
//   k 80..95   sh_eval16(dir), then sh_rotate_z16(0.7)     == sh::rotate_z(.., 0.7)
//   k 96..111  sh_zh_rotate16(sh_cap_zh4(cos 0.45), dir)   == sh::zh_rotate(&cap_zh(0.45, 4), dir)
//   k 112      sh_equirect_texel_solid_angle(i / 16, 16, 8) == sh::equirect_texel_solid_angle
//   k 113      sh_cube_texel_solid_angle((i % 16, i / 16), 16) == sh::cube_texel_solid_angle
//   k 114..116 sh_cube_texel_dir_world(i % 6, (i % 16, i / 16), 16) == sh::cube_texel_dir_world
//   k 117      c = sh_zh_rotate(clamped cosine ZH, 8 bands, dir); sh_rotate_z(c, 8, 0.3);
//              sh_eval_sum(c, 8, +x (SH frame))
//              == sh::eval(&{c = zh_rotate(&clamped_cosine_zh(8), dir); rotate_z(&mut c, 0.3); c}, X)
//   k 118..127 0
// Not used by the renderer.
#version 460
#include "common/sh.glsl"

layout(local_size_x = 128) in;
layout(std430, set = 0, binding = 0) writeonly buffer Result { float values[]; } result;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    int base = i * 128;
    ivec2 texel = ivec2(i % 16, (i / 16) % 8);
    vec3 dir = sh_world_to_sh(sh_equirect_texel_dir_world(texel, ivec2(16, 8)));

    float y[SH_MAX_COEFFS];
    sh_eval_bands(dir, 8, y);
    for (int k = 0; k < 64; ++k) result.values[base + k] = y[k];

    float a[16];
    sh_eval16(dir, a);
    for (int k = 0; k < 16; ++k) result.values[base + 64 + k] = a[k];
    sh_rotate_z16(a, 0.7);
    for (int k = 0; k < 16; ++k) result.values[base + 80 + k] = a[k];

    float b[16];
    sh_zh_rotate16(sh_cap_zh4(cos(0.45)), dir, b);
    for (int k = 0; k < 16; ++k) result.values[base + 96 + k] = b[k];

    result.values[base + 112] = sh_equirect_texel_solid_angle(texel.y, 16, 8);
    result.values[base + 113] = sh_cube_texel_solid_angle(ivec2(i % 16, (i / 16) % 16), 16);
    vec3 cd = sh_cube_texel_dir_world(i % 6, ivec2(i % 16, (i / 16) % 16), 16);
    result.values[base + 114] = cd.x;
    result.values[base + 115] = cd.y;
    result.values[base + 116] = cd.z;

    float zh[SH_MAX_BANDS];
    for (int l = 0; l < SH_MAX_BANDS; ++l) zh[l] = SH_CLAMPED_COS_ZH[l];
    float c[SH_MAX_COEFFS];
    sh_zh_rotate(zh, 8, dir, c);
    sh_rotate_z(c, 8, 0.3);
    result.values[base + 117] = sh_eval_sum(c, 8, vec3(1.0, 0.0, 0.0));
    for (int k = 118; k < 128; ++k) result.values[base + k] = 0.0;
}
