#version 460
// One decimation step of the smoothing pyramid (the height-field thesis section 5.1, digest section 1.3): level
// k (dst_size^2 texels in the corner of its layer) from level k-1 (src_size^2), reduced by
// q = src_size / dst_size ~ 2^(1/ls). filter 0: tent ("bilinear") of radius q source texels;
// 1: cubic B-spline ("bicubic") scaled by q; 2: plain copy (level 0 from the height image).
// Separable weights, each axis normalised, source indices clamped to the edge.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D src;
layout(set = 0, binding = 1, r32f) uniform writeonly image2D dst;

layout(push_constant) uniform Decimate {
    int src_size;
    int dst_size;
    int filter_kind;
} pc;

float hf_kernel(float x, float q) {
    float a = abs(x) / q;
    if (pc.filter_kind == 0) return max(1.0 - a, 0.0);
    if (a < 1.0) return (4.0 - 6.0 * a * a + 3.0 * a * a * a) / 6.0;
    if (a < 2.0) return (2.0 - a) * (2.0 - a) * (2.0 - a) / 6.0;
    return 0.0;
}

void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    if (t.x >= pc.dst_size || t.y >= pc.dst_size) return;
    if (pc.filter_kind == 2) {
        imageStore(dst, t, vec4(texelFetch(src, t, 0).r, 0.0, 0.0, 0.0));
        return;
    }
    float q = float(pc.src_size) / float(pc.dst_size);
    float radius = pc.filter_kind == 0 ? q : 2.0 * q;
    vec2 u = (vec2(t) + 0.5) * q - 0.5;
    ivec2 lo = ivec2(ceil(u - radius)), hi = ivec2(floor(u + radius));
    float sum = 0.0, wx_sum = 0.0, wy_sum = 0.0;
    for (int x = lo.x; x <= hi.x; ++x) wx_sum += hf_kernel(float(x) - u.x, q);
    for (int y = lo.y; y <= hi.y; ++y) {
        float wy = hf_kernel(float(y) - u.y, q);
        wy_sum += wy;
        if (wy == 0.0) continue;
        float row = 0.0;
        for (int x = lo.x; x <= hi.x; ++x) {
            float wx = hf_kernel(float(x) - u.x, q);
            row += wx * texelFetch(src, clamp(ivec2(x, y), ivec2(0), ivec2(pc.src_size - 1)), 0).r;
        }
        sum += wy * row;
    }
    imageStore(dst, t, vec4(sum / (wx_sum * wy_sum), 0.0, 0.0, 0.0));
}
