#version 460
// One level of a mip pyramid: each texel of `dst` (mip N) is the mean or the maximum of the 2x2
// texels of `src` (mip N-1) it covers. Shared by pyramid-building passes.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D dst;

// Scales the result; 1 for a plain pyramid (a specialization constant, folded by the driver).
layout(constant_id = 0) const float SCALE = 1.0;

layout(push_constant) uniform Params {
    uint use_max;  // 0: mean, 1: maximum
} params;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(dst)))) {
        return;
    }
    ivec2 s = textureSize(src, 0) - 1;
    vec4 a = texelFetch(src, min(2 * p, s), 0);
    vec4 b = texelFetch(src, min(2 * p + ivec2(1, 0), s), 0);
    vec4 c = texelFetch(src, min(2 * p + ivec2(0, 1), s), 0);
    vec4 d = texelFetch(src, min(2 * p + ivec2(1, 1), s), 0);
    vec4 r = params.use_max != 0u ? max(max(a, b), max(c, d)) : 0.25 * (a + b + c + d);
    imageStore(dst, p, r * SCALE);
}
