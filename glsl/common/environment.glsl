// Unshadowed irradiance from the environment's 3-band SH fit, for the raster methods' base term.
// Include after common/frame.glsl and common/sh.glsl.
#ifndef PENUMBRA_ENVIRONMENT_GLSL
#define PENUMBRA_ENVIRONMENT_GLSL

// Clamped: a 3-band fit can dip below zero.
vec3 environment_irradiance(vec3 n) {
    // The unrolled 4-band evaluation; only the first 3 bands (9 coefficients) are used.
    float y[16];
    sh_eval16(sh_world_to_sh(n), y);
    vec3 e = vec3(0.0);
    for (int i = 0; i < 9; ++i) {
        e += frame.env_irradiance[i].rgb * y[i];
    }
    return max(e, vec3(0.0));
}

#endif
