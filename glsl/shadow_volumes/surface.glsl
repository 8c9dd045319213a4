// Shared by the ambient and light passes of the stencil shadow-volume method: the per-draw push
// constants, the light block and the material record. Matches src/lighting/shadow_volumes/mod.rs.
#ifndef PENUMBRA_SV_SURFACE_GLSL
#define PENUMBRA_SV_SURFACE_GLSL

// One point, spot or directional light per lighting pass. The ambient pass binds zeros (its vertex shader is
// the light pass's, so both write bit-identical depth).
layout(set = 0, binding = 1) uniform PointLightBlock {
    vec4 position;        // xyz: world position (directional: unit vector toward it); w: radius (0: infinite)
    vec4 colour;          // rgb: faithful light colour L_C, or intensity I in W/sr (physical; W/m^2 directional)
    vec4 spot_direction;  // xyz: a spot light's unit axis; w: 1 spot, 0 point, 2 directional
    vec4 cone;            // x: cos(inner), y: cos(outer) (spot)
} light;

#include "common/scene.glsl"

#endif
