#version 460
// Largest and smallest height of the field this frame, for the brute-force march's early exit.
layout(local_size_x = 256) in;

layout(set = 0, binding = 0) uniform sampler2D heights;
layout(set = 0, binding = 1, std430) writeonly buffer Bounds { vec4 b; } bounds;

shared float hi_s[256];
shared float lo_s[256];

void main() {
    int t = int(gl_LocalInvocationIndex);
    ivec2 size = textureSize(heights, 0);
    float hi = -3.4e38, lo = 3.4e38;
    for (int i = t; i < size.x * size.y; i += 256) {
        float h = texelFetch(heights, ivec2(i % size.x, i / size.x), 0).r;
        hi = max(hi, h);
        lo = min(lo, h);
    }
    hi_s[t] = hi;
    lo_s[t] = lo;
    barrier();
    for (int s = 128; s > 0; s >>= 1) {
        if (t < s) {
            hi_s[t] = max(hi_s[t], hi_s[t + s]);
            lo_s[t] = min(lo_s[t], lo_s[t + s]);
        }
        barrier();
    }
    if (t == 0) bounds.b = vec4(hi_s[0], lo_s[0], 0.0, 0.0);
}
