// The light propagation volume as every LPV pass sees it: 2-band SH (Y00, x, y, z) per colour
// channel per cell, intensity in W/sr, and the volume's placement. Matches
// src/lighting/lpv/volume.rs (`VolumeBlock`, the set layout) and src/lighting/lpv/sh.rs.
#ifndef PENUMBRA_LPV_VOLUME_GLSL
#define PENUMBRA_LPV_VOLUME_GLSL

// The basis constants (SH_Y00, SH_C1, SH_PI) are the SH core's; the LPV orders band 1 as
// (x, y, z) in world space, its own convention (digest section 2.2).
#include "common/sh.glsl"

// The clamped cosine's 2-band projection: sqrt(pi)/2 and sqrt(pi/3).
const float LPV_COS0 = 0.886226925452758;
const float LPV_COS1 = 1.0233267079464885;

// A set stores fp16 (2 words per channel and cell, as the document's RGBA16F) or fp32 (4).
layout(constant_id = 10) const uint HALF = 1u;

#ifndef LPV_VOLUME_BINDING
#define LPV_VOLUME_BINDING 0
#endif
layout(set = 0, binding = LPV_VOLUME_BINDING) uniform VolumeBlock {
    ivec4 size;     // cells per axis; w: cell count
    vec4 origin;    // world position of the volume's corner; w: cell size (metres)
    vec4 units;     // x: fixed-point units per W/sr, y: its inverse, z: per blocking unit, w: its inverse
    ivec4 rsm;      // x: RSM texels per side; y: gather samples; z: the document's transform bug;
                    // w: 1 where the surfels add light but no blocking (a later light's RSM)
    mat4 light_view_proj;  // world -> the RSM's clip space
    vec4 light;     // xyz: direction the light travels (unit); w: 1 for a spot light
    vec4 light_pos; // xyz: spot light position; w: the RSM's clip depth per metre along the light
    vec4 light_intensity;  // rgb: irradiance (directional) or intensity (spot); w: RSM texel area
                           // (directional, m^2) or tan of the half field of view (spot)
    vec4 light_cone;       // x: cos inner, y: cos outer (spot); z: 1 in the document's mode
    vec4 scale;     // x: stored per W/sr (corrected: 1/cell^2, so the fp16 sets hold
                    // irradiance-sized values at any scale of the scene), y: its inverse
} volume;

vec4 sh_basis(vec3 d) {
    return vec4(SH_Y00, SH_C1 * d);
}

vec4 cosine_lobe(vec3 n) {
    return vec4(LPV_COS0, LPV_COS1 * n);
}

uint cell_index(ivec3 c) {
    return uint(c.x + volume.size.x * (c.y + volume.size.y * c.z));
}

bool inside(ivec3 c) {
    return all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, volume.size.xyz));
}

uint set_words() {
    return HALF != 0u ? 2u : 4u;
}

// Word offset of (cell, channel) in a set.
uint slot(uint cell, uint channel) {
    return (cell * 3u + channel) * set_words();
}

// A set is a `uint w[]` buffer; these expand where it is named.
#define SET_LOAD(buf, s) (HALF != 0u ? vec4(unpackHalf2x16(buf.w[(s)]), unpackHalf2x16(buf.w[(s) + 1u])) : uintBitsToFloat(uvec4(buf.w[(s)], buf.w[(s) + 1u], buf.w[(s) + 2u], buf.w[(s) + 3u])))
#define SET_STORE(buf, s, v) \
    if (HALF != 0u) { \
        buf.w[(s)] = packHalf2x16((v).xy); \
        buf.w[(s) + 1u] = packHalf2x16((v).zw); \
    } else { \
        uvec4 bits_ = floatBitsToUint(v); \
        buf.w[(s)] = bits_.x; \
        buf.w[(s) + 1u] = bits_.y; \
        buf.w[(s) + 2u] = bits_.z; \
        buf.w[(s) + 3u] = bits_.w; \
    }

#endif
