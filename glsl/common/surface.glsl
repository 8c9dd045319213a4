// The shading inputs of a scene surface as the raster direct-lighting methods read them: the
// material and its maps, the normal flipped toward the viewer and normal-mapped, and the
// unshadowed environment irradiance (common/environment.glsl). Include after common/frame.glsl,
// common/sh.glsl and common/scene.glsl.
#ifndef PENUMBRA_SURFACE_GLSL
#define PENUMBRA_SURFACE_GLSL

#include "common/environment.glsl"

struct SurfacePoint {
    vec3 n;         // shading normal, toward the viewer
    vec3 v;         // unit vector toward the eye
    vec3 emission;
    vec3 albedo;
    vec3 specular;
    float exponent;
};

SurfacePoint surface_point(Material m, vec3 world, vec3 normal, vec2 uv, vec4 tangent, sampler2D albedo_map, sampler2D normal_map, sampler2D specular_map) {
    SurfacePoint s;
    s.v = normalize(frame.camera_pos.xyz - world);
    vec3 n = normalize(normal);
    s.emission = m.emission.rgb;
    // Surfaces seen from behind: one-sided emitters don't emit there; other surfaces are thin
    // and lit from the viewer's side, so the shading frame is flipped before normal mapping
    // (deciding on the mapped normal would flip texels that merely lean away).
    if (dot(n, s.v) < 0.0) {
        n = -n;
        if (m.maps.y != 0u) {
            s.emission = vec3(0.0);
        }
    }
    if (m.maps.x != 0u) {
        // Tangent-space normal map; Gram-Schmidt keeps the frame orthonormal after interpolation.
        vec3 t = normalize(tangent.xyz - n * dot(n, tangent.xyz));
        vec3 b = cross(n, t) * tangent.w;
        vec3 tn = texture(normal_map, uv).xyz * 2.0 - 1.0;
        n = normalize(t * tn.x + b * tn.y + n * tn.z);
    }
    s.n = n;
    s.albedo = m.albedo.rgb * texture(albedo_map, uv).rgb;
    s.specular = m.specular.rgb * texture(specular_map, uv).rgb;
    s.exponent = m.specular.w;
    return s;
}

#endif
