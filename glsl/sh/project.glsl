// SH projection of an environment image, first dispatch: every workgroup sums texel value x
// exact texel solid angle x y_i(direction) over its own contiguous run of texels and writes one
// partial sum per coefficient; project_reduce.comp then adds the partial sums in a fixed order.
// Two dispatches rather than float atomics: shader float atomics are optional (lavapipe's may be
// missing), and a fixed summation order makes the result the same from run to run.
//
// Included by project_equirect.comp and project_cube.comp, which define the layout:
//   SH_PROJECT_CUBE undefined: env_image is an equirectangular map (penumbra's mapping, see
//     sh_equirect_texel_dir_world), read texel by texel, solid angle (phi1-phi0)(cos t0 - cos t1).
//   SH_PROJECT_CUBE defined: env_image is a cube map of size x size faces, looked up at each
//     texel's centre direction through a nearest sampler, so the hardware's face selection decides
//     which texel is read (the CPU's cube_texel_dir_world follows the same Vulkan table); solid
//     angle the exact area integral (sh_cube_texel_solid_angle).
// Coefficients are in the SH frame (z up), as everywhere in penumbra.
#include "common/sh.glsl"

layout(local_size_x = 64) in;

#ifdef SH_PROJECT_CUBE
layout(set = 0, binding = 0) uniform samplerCube env_image;
#else
layout(set = 0, binding = 0) uniform sampler2D env_image;
#endif
// partials.v[group * 64 + k]: rgb of coefficient k summed over the group's texels.
layout(set = 0, binding = 1, std430) writeonly buffer Partials { vec4 v[]; } partials;

layout(push_constant) uniform ProjectPush {
    ivec4 dims;  // x: width (cube: face size), y: height (cube: face size), z: bands, w: texels per group
} pc;

shared vec3 partial[64];

void main() {
    int t = int(gl_LocalInvocationIndex);
    int g = int(gl_WorkGroupID.x);
    int nb = clamp(pc.dims.z, 1, SH_MAX_BANDS);
    int nc = nb * nb;
#ifdef SH_PROJECT_CUBE
    int n = max(pc.dims.x, 1);
    int total = 6 * n * n;
#else
    ivec2 size = max(pc.dims.xy, ivec2(1));
    int total = size.x * size.y;
#endif
    int begin = g * pc.dims.w;
    int end = min(begin + pc.dims.w, total);

    vec3 acc[SH_MAX_COEFFS];
    for (int k = 0; k < SH_MAX_COEFFS; ++k) acc[k] = vec3(0.0);
    for (int i = begin + t; i < end; i += 64) {
#ifdef SH_PROJECT_CUBE
        int face = i / (n * n);
        int r = i - face * n * n;
        ivec2 texel = ivec2(r % n, r / n);
        vec3 world = sh_cube_texel_dir_world(face, texel, n);
        vec3 l = textureLod(env_image, world, 0.0).rgb * sh_cube_texel_solid_angle(texel, n);
#else
        ivec2 texel = ivec2(i % size.x, i / size.x);
        vec3 world = sh_equirect_texel_dir_world(texel, size);
        vec3 l = texelFetch(env_image, texel, 0).rgb * sh_equirect_texel_solid_angle(texel.y, size.x, size.y);
#endif
        float y[SH_MAX_COEFFS];
        sh_eval_bands(sh_world_to_sh(world), nb, y);
        for (int k = 0; k < nc; ++k) acc[k] += l * y[k];
    }
    // One tree reduction per coefficient through 64 shared slots (64 coefficients x 64 threads
    // of vec3 at once would exceed the 16 KiB of shared memory every device guarantees).
    for (int k = 0; k < nc; ++k) {
        partial[t] = acc[k];
        barrier();
        for (int s = 32; s > 0; s >>= 1) {
            if (t < s) partial[t] += partial[t + s];
            barrier();
        }
        if (t == 0) partials.v[g * 64 + k] = vec4(partial[0], 0.0);
        barrier();
    }
}
