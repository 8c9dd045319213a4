#version 460
// HDR radiance to the window: exposure and the ACES fit; the sRGB swapchain format encodes.
#include "common/tonemap.glsl"

layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(push_constant) uniform Display {
    float exposure;
} display;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

void main() {
    vec3 radiance = texture(hdr, in_uv).rgb;
    out_color = vec4(aces_fit(radiance * display.exposure), 1.0);
}
