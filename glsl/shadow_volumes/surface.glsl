// Shared by the ambient and light passes of the stencil shadow-volume method: the per-draw push
// constants, the light block and the material record. Matches src/lighting/shadow_volumes/mod.rs.
#ifndef PENUMBRA_SV_SURFACE_GLSL
#define PENUMBRA_SV_SURFACE_GLSL

// One point, spot or directional light per lighting pass. The ambient pass binds zeros (its vertex shader is
// the light pass's, so both write bit-identical depth).
layout(set = 0, binding = 1) uniform LightBlock {
    vec4 position;        // xyz: world position (directional: unit vector toward it); w: radius (0: infinite)
    vec4 colour;          // rgb: faithful light colour L_C, or intensity I in W/sr (physical; W/m^2 directional)
    vec4 spot_direction;  // xyz: a spot light's unit axis; w: the light's kind (light_kind)
    vec4 cone;            // x: cos(inner), y: cos(outer) (spot)
} light;

// The same four vectors as a value, as shade.glsl takes a light and the grouped light pass
// holds its lights.
struct SvLight {
    vec4 position;
    vec4 colour;
    vec4 spot_direction;
    vec4 cone;
};

#include "common/lights.glsl"
#include "common/scene.glsl"

// LIGHT_POINT, LIGHT_SPOT or LIGHT_DIRECTIONAL (common/lights.glsl), as the block's w holds it.
uint light_kind() {
    return uint(light.spot_direction.w + 0.5);
}

#endif
