#version 460
// Ambient and light passes: world position, frame, texture coordinates, and the light and eye
// vectors in tangent space (the seed's per-vertex tangent-space vectors; the fragment shader
// keeps the world-space light vector for attenuation, as Listing 1 does).
#include "common/frame.glsl"
#define PENUMBRA_SCENE_VERTEX
#include "surface.glsl"

layout(location = 0) out vec3 out_world;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) out vec4 out_tangent;
layout(location = 4) out vec3 out_light_ts;
layout(location = 5) out vec3 out_eye_ts;
// For the grouped light pass, which takes many lights at once: the bitangent and the position in
// the tangent frame, from which light_group.frag forms each light's tangent-space vector as the
// interpolation of out_light_ts would (it is linear in the light's position).
layout(location = 6) out vec3 out_bitangent;
layout(location = 7) out vec3 out_world_ts;

// The light passes test depth with LESS_OR_EQUAL against the ambient pass's depth: both run
// this same shader on the same vertices, so the depths are identical. (`invariant` would say so
// too, but lavapipe warns about the decoration glslang puts on the gl_PerVertex member.)

void main() {
    vec4 world = draw.model * vec4(in_position, 1.0);
    mat3 normal_matrix = transpose(inverse(mat3(draw.model)));
    vec3 n = normalize(normal_matrix * in_normal);
    vec3 t = mat3(draw.model) * in_tangent.xyz;
    t = normalize(t - n * dot(n, t));
    vec3 b = cross(n, t) * in_tangent.w;
    // A directional light's position.xyz is the unit vector toward it (light.frag).
    vec3 to_light = light_kind() == LIGHT_DIRECTIONAL ? light.position.xyz : light.position.xyz - world.xyz;
    vec3 to_eye = frame.camera_pos.xyz - world.xyz;
    out_world = world.xyz;
    out_normal = n;
    out_uv = in_uv;
    out_tangent = vec4(t, in_tangent.w);
    out_light_ts = vec3(dot(to_light, t), dot(to_light, b), dot(to_light, n));
    out_eye_ts = vec3(dot(to_eye, t), dot(to_eye, b), dot(to_eye, n));
    out_bitangent = b;
    out_world_ts = vec3(dot(world.xyz, t), dot(world.xyz, b), dot(world.xyz, n));
    gl_Position = frame.view_proj * world;
}
