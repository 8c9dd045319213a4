// Display transform for the window: exposure, Narkowicz's ACES fit, then the swapchain's sRGB
// format encodes. Matches `tonemap` in src/util/image_io.rs (used for PNG captures).
#ifndef PENUMBRA_TONEMAP_GLSL
#define PENUMBRA_TONEMAP_GLSL

vec3 aces_fit(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

#endif
