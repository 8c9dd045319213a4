#version 460
// Reconstruction of every decimated level back to full resolution with the uniform cubic
// B-spline (the height-field thesis section 5.1): layer k of `levels` holds sizes[k]^2 texels in its corner;
// full-resolution texel x maps to u = (x + 0.5) sizes[k] / res - 0.5, and 4x4 taps with the
// B-spline weights of frac(u) give layer k of `pyramid_out`. Source indices clamp to the level.
// With `exact_level0` (the corrected mode) level 0, already at full resolution, is copied: the
// approximating B-spline would smooth it by (1, 4, 1)/6 per axis, so even the finest samples
// would not see the field the brute force marches.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0) uniform sampler2DArray levels;
layout(set = 0, binding = 1, r32f) uniform writeonly image2DArray pyramid_out;
layout(set = 0, binding = 2) uniform Sizes { ivec4 size[61]; } sizes;

layout(push_constant) uniform Reconstruct { int res; int count; int exact_level0; } pc;

vec4 hf_bspline_weights(float u) {
    float u2 = u * u, u3 = u2 * u;
    return vec4((1.0 - u) * (1.0 - u) * (1.0 - u), 3.0 * u3 - 6.0 * u2 + 4.0, -3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0, u3) / 6.0;
}

void main() {
    ivec3 g = ivec3(gl_GlobalInvocationID);
    if (g.x >= pc.res || g.y >= pc.res || g.z >= pc.count) return;
    int n = sizes.size[g.z].x;
    if (g.z == 0 && pc.exact_level0 != 0) {
        imageStore(pyramid_out, g, vec4(texelFetch(levels, ivec3(g.xy, 0), 0).r, 0.0, 0.0, 0.0));
        return;
    }
    vec2 u = (vec2(g.xy) + 0.5) * float(n) / float(pc.res) - 0.5;
    vec2 f = floor(u);
    vec4 wx = hf_bspline_weights(u.x - f.x), wy = hf_bspline_weights(u.y - f.y);
    ivec2 b = ivec2(f) - 1;
    float sum = 0.0;
    for (int y = 0; y < 4; ++y) {
        float row = 0.0;
        for (int x = 0; x < 4; ++x) {
            ivec2 s = clamp(b + ivec2(x, y), ivec2(0), ivec2(n - 1));
            row += wx[x] * texelFetch(levels, ivec3(s, g.z), 0).r;
        }
        sum += wy[y] * row;
    }
    imageStore(pyramid_out, g, vec4(sum, 0.0, 0.0, 0.0));
}
