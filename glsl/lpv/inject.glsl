// The scatter injection, shared by inject.comp (the RSM's surfels) and inject_gbuffer.comp (the
// camera's G-buffer's, with SKIP_HELD_BY_RSM defined).
// Scatter injection (corrected): every valid RSM texel is a VPL added, as a cosine lobe of its
// reflected flux Phi/pi * coslobe(n) (and of its transmitted flux along -n), into the cell that
// holds p + cell/2 * n; and, as blocking potential (A_s / cell^2) * coslobe(n) * (1 - tau) (peak
// normalised to 1; a thin surface's from both sides), into the geometry volume's corner nearest p. Sums are fixed-point integer atomics (no float
// atomics needed), made floats again by resolve.comp.
#ifndef PENUMBRA_LPV_INJECT_GLSL
#define PENUMBRA_LPV_INJECT_GLSL
#include "lpv/volume.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 1) uniform sampler2D rsm_flux;         // rgb reflected flux (W), a: surfel area (m^2)
layout(set = 0, binding = 2) uniform sampler2D rsm_transmitted;  // rgb transmitted flux (W), a: 1 - mean transmittance
layout(set = 0, binding = 3) uniform sampler2D rsm_position;     // xyz world position, a: 1 where a surface was drawn
layout(set = 0, binding = 4) uniform sampler2D rsm_normal;       // xyz normal facing the light
layout(set = 0, binding = 5) buffer FixedLight { int v[]; } fixed_light;
layout(set = 0, binding = 6) buffer FixedBlocking { int v[]; } fixed_blocking;

#ifdef SKIP_HELD_BY_RSM
// The RSM's own layers (volume.rsm.y texels per side; the block is the light's, so
// light_view_proj projects into the RSM).
layout(set = 0, binding = 7) uniform sampler2D held_position;
layout(set = 0, binding = 8) uniform sampler2D held_normal;

// Whether the RSM already holds the surface at p (normal n): the RSM texel p projects to saw a
// surface whose plane passes within one RSM texel's footprint of p, with a normal along n's line
// (either side: surfaces are two-sided). Such a surfel is skipped, so that a surface both views
// see blocks once. A plane test rather than a depth test along the light: a surface tilted
// away from the light changes depth across a texel by up to the footprint over its cosine,
// while its plane stays put.
bool held_by_rsm(vec3 p, vec3 n) {
    vec4 c = volume.light_view_proj * vec4(p, 1.0);
    if (c.w <= 0.0) {
        return false;
    }
    vec3 ndc = c.xyz / c.w;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThanEqual(uv, vec2(1.0))) || ndc.z < 0.0 || ndc.z > 1.0) {
        return false;
    }
    float size = float(volume.rsm.y);
    ivec2 t = ivec2(uv * size);
    vec4 q = texelFetch(held_position, t, 0);
    if (q.w < 0.5) {
        return false;
    }
    vec3 m = normalize(texelFetch(held_normal, t, 0).xyz);
    // The width of an RSM texel where q lies: the sun's is fixed (sqrt of its area); a spot
    // light's grows with the distance along its axis (2 tan(half angle) z / size).
    float footprint = volume.light.w > 0.5
        ? 2.0 * volume.light_intensity.w * max(dot(q.xyz - volume.light_pos.xyz, volume.light.xyz), 0.0) / size
        : sqrt(volume.light_intensity.w);
    return abs(dot(p - q.xyz, m)) <= footprint && abs(dot(n, m)) >= 0.5;
}
#endif

void add_lobe(uint cell, uint ch, vec4 c) {
    for (uint k = 0u; k < 4u; ++k) {
        int q = int(round(c[k] * volume.units.x));
        if (q != 0) {
            atomicAdd(fixed_light.v[(cell * 3u + ch) * 4u + k], q);
        }
    }
}

void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(t, ivec2(volume.rsm.x)))) {
        return;
    }
    vec4 position = texelFetch(rsm_position, t, 0);
    if (position.w < 0.5) {
        return;
    }
    vec4 flux = texelFetch(rsm_flux, t, 0);
    vec4 transmitted = texelFetch(rsm_transmitted, t, 0);
    vec3 n = normalize(texelFetch(rsm_normal, t, 0).xyz);
#ifdef SKIP_HELD_BY_RSM
    if (held_by_rsm(position.xyz, n)) {
        return;
    }
#endif
    float cell_size = volume.origin.w;
    vec3 p = (position.xyz - volume.origin.xyz) / cell_size;
    // Reflected light leaves on the lit side, transmitted light on the back: each half a cell
    // off the surface along its own direction, so neither lights its own surfel.
    ivec3 front = ivec3(floor(p + 0.5 * n));
    ivec3 back = ivec3(floor(p - 0.5 * n));
    vec4 lobe = cosine_lobe(n) / SH_PI;
    vec4 back_lobe = cosine_lobe(-n) / SH_PI;
    for (uint ch = 0u; ch < 3u; ++ch) {
        if (inside(front) && flux[ch] > 0.0) {
            add_lobe(cell_index(front), ch, flux[ch] * lobe);
        }
        if (inside(back) && transmitted[ch] > 0.0) {
            add_lobe(cell_index(back), ch, transmitted[ch] * back_lobe);
        }
    }
    ivec3 corner = ivec3(floor(p + 0.5));
    // rsm.w = 1: a second or later light's RSM, whose surfels the first light's already block.
    if (inside(corner) && volume.rsm.w == 0) {
        // The 2-band lobe of max(0, n.w) peaks at 0.75 (LPV_COS0 * SH_Y00 + LPV_COS1 * SH_C1):
        // scaled by 4/3 so that a surface filling the cell blocks light meeting it head-on
        // completely, as max(0, n.w) itself would.
        // A thin surface (one that transmits, transmitted.w < 1) blocks light meeting either of
        // its sides: a leaf lit from above still stops light coming up from the ground. A
        // solid's back is the front of another of its surfaces, which blocks in its turn.
        float peak = LPV_COS0 * SH_Y00 + LPV_COS1 * SH_C1;
        vec4 sides = transmitted.w < 1.0 ? cosine_lobe(n) + cosine_lobe(-n) : cosine_lobe(n);
        vec4 b = sides * (flux.w / (cell_size * cell_size) * transmitted.w / peak);
        for (uint k = 0u; k < 4u; ++k) {
            int q = int(round(b[k] * volume.units.z));
            if (q != 0) {
                atomicAdd(fixed_blocking.v[cell_index(corner) * 4u + k], q);
            }
        }
    }
}

#endif
