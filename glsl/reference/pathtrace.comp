#version 460
// The ground-truth reference: unidirectional Monte Carlo path tracing with next-event
// estimation, one pixel per invocation, bringing each pixel to `sample_offset + sample_count`
// running mean and sum of squared deviations (Welford) so the host can stop, read progress and
// go on. Lighting and BRDF are those of glsl/common/lights.glsl; see src/reference/mod.rs for
// what the estimator counts.
#include "common/lights.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

struct Shading {
    vec3 n0;
    uint material;
    vec3 n1;
    uint pad0;
    vec3 n2;
    uint pad1;
    vec4 t0;  // xyz: world-space tangent (toward +u); w: bitangent sign
    vec4 t1;
    vec4 t2;
    vec2 uv0;
    vec2 uv1;
    vec2 uv2;
    vec2 pad2;
};

layout(set = 0, binding = 0) uniform Params {
    vec4 eye;          // xyz: camera position
    vec4 right;        // xyz: camera right * tan(fov_y / 2) * aspect
    vec4 up;           // xyz: camera up * tan(fov_y / 2)
    vec4 forward;      // xyz: unit view direction
    vec4 environment;  // rgb: radiance of rays that escape
    uvec4 counts;      // x: lights, y: triangles, z: width, w: height
    uvec4 environment_map;  // x, y: size of the map (0 for the constant environment); z: sampled; w: cube
    uvec4 options;     // x: 1 when a ray past the last interaction can find light (emission, sky);
                       // y: the first area light (punctual lights come before it)
} params;

#define BVH_NODES_BINDING 1
#define BVH_TRIANGLES_BINDING 2
#define BVH_TRIANGLE_COUNT params.counts.y
#define BVH_ORDERED_SKIPS_BINDING 13
#include "common/bvh.glsl"
// Per triangle its Shading (8 texels) and per material its Material (5 texels), as tables.
layout(set = 0, binding = 3, rgba32ui) readonly uniform uimage2D shading_table;
layout(set = 0, binding = 4) readonly buffer Lights { Light items[]; } lights;
// The environment map's texels, and its CDFs four values a texel (environment.glsl).
layout(set = 0, binding = 8, rgba32ui) readonly uniform uimage2D environment_table;
layout(set = 0, binding = 9, rgba32ui) readonly uniform uimage2D environment_cdf_table;
// Texture maps as linear float texels (src/reference/scene_data.rs); per texture
// (first texel, width, height, 0).
layout(set = 0, binding = 10, rgba32ui) readonly uniform uimage2D texture_table;
layout(set = 0, binding = 11, rgba32ui) readonly uniform uimage2D texture_headers;

#include "reference/bsdf.glsl"
#include "reference/environment.glsl"
#include "reference/trace.glsl"

layout(set = 0, binding = 5, rgba32ui) readonly uniform uimage2D material_table;

Shading shading_of(uint triangle) {
    uint k = 8u * triangle;
    uvec4 a = table_texel(shading_table, k);
    vec3 n1 = table_vec4(shading_table, k + 1u).xyz;
    vec3 n2 = table_vec4(shading_table, k + 2u).xyz;
    vec4 uv01 = table_vec4(shading_table, k + 6u);
    vec4 uv2 = table_vec4(shading_table, k + 7u);
    Shading sh;
    sh.n0 = uintBitsToFloat(a.xyz);
    sh.material = a.w;
    sh.n1 = n1;
    sh.pad0 = 0u;
    sh.n2 = n2;
    sh.pad1 = 0u;
    sh.t0 = table_vec4(shading_table, k + 3u);
    sh.t1 = table_vec4(shading_table, k + 4u);
    sh.t2 = table_vec4(shading_table, k + 5u);
    sh.uv0 = uv01.xy;
    sh.uv1 = uv01.zw;
    sh.uv2 = uv2.xy;
    sh.pad2 = vec2(0.0);
    return sh;
}

uint material_index_of(uint triangle) {
    return table_texel(shading_table, 8u * triangle).w;
}

Material material_of(uint index) {
    uint k = 5u * index;
    Material m;
    m.albedo = table_vec4(material_table, k);
    m.specular = table_vec4(material_table, k + 1u);
    m.transmittance = table_vec4(material_table, k + 2u);
    m.emission = table_vec4(material_table, k + 3u);
    m.maps = table_texel(material_table, k + 4u);
    return m;
}
// Stochastic transparency: a surface of opacity a (its material's albedo.w) stops a ray with
// probability a and otherwise lets it through unchanged, so the expected radiance is
// a * surface + (1 - a) * behind, and each layer on a shadow ray blocks it with probability a.
// Random numbers are drawn at translucent surfaces only, so opaque scenes trace as before.
// Beyond MAX_LAYERS crossings the surface reached is kept.
const uint MAX_LAYERS = 64u;

float opacity_of(int triangle) {
    return table_vec4(material_table, 5u * material_index_of(uint(triangle))).w;
}

// A ray origin just past the triangle's point at uv, on the side the ray travels to.
vec3 beyond(int triangle, vec2 uv, vec3 d) {
    Triangle tri = bvh_triangle(uint(triangle));
    vec3 p = tri.p0.xyz + uv.x * tri.e1.xyz + uv.y * tri.e2.xyz;
    vec3 ng = normalize(cross(tri.e1.xyz, tri.e2.xyz));
    return offset_origin(p, dot(ng, d) >= 0.0 ? ng : -ng);
}

// The surface (or area light) a ray stops at.
Hit trace_visible(vec3 o, vec3 d, inout uint rng) {
    Hit h = trace_closest(o, d);
    if (!SCENE_HAS_TRANSLUCENCY) {
        return h;
    }
    for (uint k = 0u; k < MAX_LAYERS && h.triangle >= 0; ++k) {
        float a = opacity_of(h.triangle);
        if (a >= 1.0 || rand(rng) < a) {
            break;
        }
        h = trace_closest(beyond(h.triangle, h.uv, d), d);
    }
    return h;
}

// `occluded` with translucent surfaces stopping the ray stochastically. The any-hit query
// answers first; only when what it found is translucent are the layers walked nearest first.
bool blocked(vec3 o, vec3 d, float t_max, uint skip_light, inout uint rng) {
    for (uint i = params.options.y; i < params.counts.x; ++i) {
        if (i != skip_light && hit_area_light(i, o, d) < t_max) {
            return true;
        }
    }
    int triangle;
    vec2 uv;
    float t = t_max;
    if (!trace_scene(o, d, true, t, triangle, uv)) {
        return false;
    }
    if (!SCENE_HAS_TRANSLUCENCY || opacity_of(triangle) >= 1.0) {
        return true;
    }
    for (uint k = 0u; k < MAX_LAYERS; ++k) {
        t = t_max;
        if (!trace_scene(o, d, false, t, triangle, uv)) {
            return false;
        }
        float a = opacity_of(triangle);
        if (a >= 1.0 || rand(rng) < a) {
            return true;
        }
        vec3 next = beyond(triangle, uv, d);
        t_max -= dot(next - o, d);
        o = next;
    }
    return true;
}

layout(set = 0, binding = 6, rgba32f) uniform image2D mean_radiance;
layout(set = 0, binding = 7, rgba32f) uniform image2D second_moment;
// Pixels whose batch did not run to the end (zeroed by the host before each dispatch).
layout(set = 0, binding = 12) buffer Status { uint short_pixels; } status;
// With the Sobol sampler, per pixel the sum of each replicate's samples (rgb), one layer per
// replicate (sample index modulo SOBOL_REPLICATES, reference/rng.glsl): the scatter of the
// replicates' means is the error of the pixel's mean (src/reference/mod.rs, read_image). An
// image, not a buffer: at 128 bytes a pixel a buffer would pass a device's maxStorageBufferRange
// (lavapipe's 128 MiB) at about a megapixel. Unused otherwise.
layout(set = 0, binding = 14, rgba32f) uniform image2DArray replicate_sums;

layout(push_constant) uniform Batch {
    uint sample_offset;  // index of this dispatch's first sample (0: start afresh)
    uint sample_count;   // samples each pixel adds in this dispatch
    uint seed;
    uint bounces;        // surface interactions followed after the first hit
    uint flags;
    uint roulette_after; // first interaction subject to Russian roulette (0xffffffff: none)
    uint first_row;      // the dispatch covers rows first_row.. (a band of the image, or all of it)
} batch;

// Leave out light that reaches the camera after fewer than two surface interactions.
const uint FLAG_INDIRECT_ONLY = 1u;
// Next-event estimation draws one light per vertex and colour channel instead of visiting every one.
const uint FLAG_ONE_LIGHT = 2u;
// Seed difference of the next-event estimation stream.
const uint LIGHT_STREAM = 0x9e3779b9u;

// Texture `index` at uv as the raster sampler (LINEAR, REPEAT, one mip level) filters it: texel
// centres at half-integers, the four nearest texels wrapped and blended bilinearly.
// `i` within one texel of [0, size): GLSL leaves % of negative numbers undefined.
vec4 texel_at(uvec4 header, ivec2 i) {
    ivec2 size = ivec2(header.yz);
    i += size * ivec2(lessThan(i, ivec2(0))) - size * ivec2(greaterThanEqual(i, size));
    return table_vec4(texture_table, header.x + uint(i.y * size.x + i.x));
}

vec4 sample_texture(uint index, vec2 uv) {
    uvec4 header = table_texel(texture_headers, index);
    vec2 s = fract(uv) * vec2(header.yz) - 0.5;
    vec2 base = floor(s);
    vec2 f = s - base;
    ivec2 i = ivec2(base);
    vec4 top = mix(texel_at(header, i), texel_at(header, i + ivec2(1, 0)), f.x);
    vec4 bottom = mix(texel_at(header, i + ivec2(0, 1)), texel_at(header, i + ivec2(1, 1)), f.x);
    return mix(top, bottom, f.y);
}

// The surface hit by the ray along d, normals turned toward where the ray came from: a one-sided
// thin surface seen from behind reflects like its front, as in the forward method. The shading
// normal is turned with the geometric one, to its side: a ray arriving between the two planes
// (at grazing incidence where interpolated normals lean away from the face) would otherwise turn
// them to opposite sides, where bsdf_times_cos, which wants l on the viewer's side of both, is
// zero almost everywhere, and the point would go black. The material
// comes back with its maps applied as the raster methods apply them (glsl/forward/forward.frag,
// glsl/shadow_volumes/light.frag): albedo and specular multiplied by their maps, and the shading
// normal bent by the normal map in the frame (t, b, n) built after the flip, so that seen from
// behind the frame is (t, -b, -n).
Surface surface_at(Hit h, vec3 d, out Material m) {
    Triangle tri = bvh_triangle(uint(h.triangle));
    Shading sh = shading_of(uint(h.triangle));
    m = material_of(sh.material);
    Surface s;
    s.p = tri.p0.xyz + h.uv.x * tri.e1.xyz + h.uv.y * tri.e2.xyz;
    vec3 ng = normalize(cross(tri.e1.xyz, tri.e2.xyz));
    vec3 bary = vec3(1.0 - h.uv.x - h.uv.y, h.uv.x, h.uv.y);
    vec3 ns = bary.x * sh.n0 + bary.y * sh.n1 + bary.z * sh.n2;
    float len = length(ns);
    ns = len > 0.0 ? ns / len : ng;
    s.geometric_normal = dot(ng, d) > 0.0 ? -ng : ng;
    s.shading_normal = dot(ns, s.geometric_normal) < 0.0 ? -ns : ns;
    if (!SCENE_HAS_MAPS || all(equal(m.maps.xyz, uvec3(0u)))) {
        return s;
    }
    vec2 uv = bary.x * sh.uv0 + bary.y * sh.uv1 + bary.z * sh.uv2;
    if (m.maps.x != 0u) {
        m.albedo.rgb *= sample_texture(m.maps.x - 1u, uv).rgb;
    }
    if (m.maps.z != 0u) {
        m.specular.rgb *= sample_texture(m.maps.z - 1u, uv).rgb;
    }
    if (m.maps.y != 0u) {
        vec4 tangent = bary.x * sh.t0 + bary.y * sh.t1 + bary.z * sh.t2;
        vec3 n = s.shading_normal;
        vec3 t = tangent.xyz - n * dot(n, tangent.xyz);
        // A tangent along the normal has no frame; the raster methods would shade NaN there.
        if (dot(t, t) > 1e-20) {
            t = normalize(t);
            vec3 b = cross(n, t) * tangent.w;
            vec3 tn = normalize(sample_texture(m.maps.y - 1u, uv).xyz * 2.0 - 1.0);
            s.shading_normal = normalize(t * tn.x + b * tn.y + n * tn.z);
        }
    }
    return s;
}

vec3 spawn_origin(Surface s, vec3 dir) {
    return offset_origin(s.p, dot(s.geometric_normal, dir) >= 0.0 ? s.geometric_normal : -s.geometric_normal);
}

// Radiance an area light sends back along -d (quads emit from their front side only).
vec3 light_seen(uint i, vec3 d) {
    Light light = lights.items[i];
    if (SCENE_HAS_QUAD_LIGHTS && uint(light.position.w) == LIGHT_QUAD && dot(d, cross(light.direction.xyz, light.cone.xyz)) >= 0.0) {
        return vec3(0.0);
    }
    return light.intensity.rgb;
}

// A direction toward a point light, its distance and what arrives along it divided by the
// solid-angle pdf of the direction (for delta lights, the irradiance at normal incidence).
bool sample_light(uint i, vec3 p, uint depth, inout uint rng, out vec3 l, out vec3 arriving, out float dist) {
    Light light = lights.items[i];
    uint type = uint(light.position.w);
    l = vec3(0.0, 1.0, 0.0);
    arriving = vec3(0.0);
    dist = NO_HIT;
    if (SCENE_HAS_PUNCTUAL_LIGHTS && type <= LIGHT_DIRECTIONAL) {
        light_incidence(light, p, l, arriving);
        if (type != LIGHT_DIRECTIONAL) {
            dist = distance(light.position.xyz, p);
        }
        return true;
    }
    vec2 u = sample2(DRAW_LIGHT, depth, i, rng);
    if (SCENE_HAS_SPHERE_LIGHTS && type == LIGHT_SPHERE) {
        // Uniform directions in the cone of the sphere's visible cap: pdf 1 / (2 pi (1 - cos_max)).
        vec3 to_center = light.position.xyz - p;
        float d2 = dot(to_center, to_center);
        float r2 = light.direction.x * light.direction.x;
        if (d2 <= r2) {
            return false;
        }
        float sin2_max = r2 / d2;
        float cap = sin2_max / (1.0 + sqrt(1.0 - sin2_max));  // 1 - cos_max without cancellation
        float one_minus_cos = u.x * cap;
        float sin2 = one_minus_cos * (2.0 - one_minus_cos);
        float dc = sqrt(d2);
        l = around(to_center / dc, 1.0 - one_minus_cos, sqrt(sin2), 2.0 * PI * u.y);
        dist = dc * (1.0 - one_minus_cos) - sqrt(max(0.0, r2 - d2 * sin2));
        arriving = light.intensity.rgb * (2.0 * PI * cap);
        return true;
    }
    if (SCENE_HAS_QUAD_LIGHTS && type == LIGHT_QUAD) {
        // Uniform on the area: pdf dist^2 / (cos_light * area) per solid angle.
        vec3 q = light.position.xyz + u.x * light.direction.xyz + u.y * light.cone.xyz;
        vec3 n = cross(light.direction.xyz, light.cone.xyz);
        float area = length(n);
        vec3 to_q = q - p;
        float d2 = dot(to_q, to_q);
        dist = sqrt(d2);
        l = to_q / dist;
        float cos_light = -dot(l, n) / area;
        if (cos_light <= 0.0 || d2 <= 0.0) {
            return false;
        }
        arriving = light.intensity.rgb * (cos_light * area / d2);
        return true;
    }
    return false;
}

// What light `i` sends through the surface toward v, unshadowed, with the direction and distance
// of the shadow ray that decides whether it arrives: exact for a punctual light, one sampled point
// (divided by its pdf) of an area light; zero where it cannot reach the surface.
vec3 light_contribution(uint i, Surface s, Material m, vec3 v, uint depth, inout uint rng, out vec3 l, out float dist) {
    vec3 arriving;
    if (!sample_light(i, s.p, depth, rng, l, arriving, dist) || all(equal(arriving, vec3(0.0)))) {
        return vec3(0.0);
    }
    return bsdf_times_cos(s, m, v, l) * arriving;
}

bool unblocked_toward(Surface s, vec3 l, float dist, uint skip_light, inout uint rng) {
    float t_max = dist == NO_HIT ? NO_HIT : dist * (1.0 - 1e-4);
    return !blocked(spawn_origin(s, l), l, t_max, skip_light, rng);
}

// Next-event estimation. Lights: a shadow ray to each (one sampled point of an area light), or
// (FLAG_ONE_LIGHT) per colour channel one light drawn with probability c_i / C, its unshadowed
// contribution c_i to that channel (for an area light, at the point sampled on it) over all
// lights' C, and counted as C times its visibility. Given the sampled points the expected value
// is the sum over lights of c_i times visibility, so the estimate is unbiased; it is exact where
// nothing is shadowed and punctual, and never exceeds C, so coloured lights leave no rare large
// values for the standard error to miss. The draw is one pass of weighted reservoir sampling
// with one random number per light for all three channels, so lights of one colour pick the same
// light and take one shadow ray. The environment map: one ray, weighted against the BSDF
// sampling that can also find it.
vec3 direct_light(Surface s, Material m, vec3 v, uint depth, inout uint rng) {
    vec3 sum = vec3(0.0);
    if (NEE_MODE == 1u || (NEE_MODE == 2u && (batch.flags & FLAG_ONE_LIGHT) != 0u)) {
        vec3 total = vec3(0.0);
        uvec3 chosen = uvec3(NO_LIGHT);
        vec3 chosen_l[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
        vec3 chosen_dist = vec3(0.0);
        for (uint i = 0u; i < params.counts.x; ++i) {
            vec3 l;
            float dist;
            vec3 c = max(light_contribution(i, s, m, v, depth, rng, l, dist), vec3(0.0));
            if (all(equal(c, vec3(0.0)))) {
                continue;
            }
            total += c;
            // Where c is 0 the comparison fails, so a channel only ever picks a light it gets.
            bvec3 take = lessThan(vec3(rand(rng)) * total, c);
            chosen = mix(chosen, uvec3(i), take);
            chosen_dist = mix(chosen_dist, vec3(dist), take);
            chosen_l[0] = take.x ? l : chosen_l[0];
            chosen_l[1] = take.y ? l : chosen_l[1];
            chosen_l[2] = take.z ? l : chosen_l[2];
        }
        // A light drawn by two channels is the same sample: one shadow ray serves both.
        float seen[3];
        for (int k = 0; k < 3; ++k) {
            uint i = chosen[k];
            if (i == NO_LIGHT) {
                seen[k] = 0.0;
            } else if (k > 0 && i == chosen[0]) {
                seen[k] = seen[0];
            } else if (k > 1 && i == chosen[1]) {
                seen[k] = seen[1];
            } else {
                seen[k] = unblocked_toward(s, chosen_l[k], chosen_dist[k], i, rng) ? 1.0 : 0.0;
            }
        }
        sum += total * vec3(seen[0], seen[1], seen[2]);
    } else {
        for (uint i = 0u; i < params.counts.x; ++i) {
            vec3 l;
            float dist;
            vec3 c = light_contribution(i, s, m, v, depth, rng, l, dist);
            if (any(notEqual(c, vec3(0.0))) && unblocked_toward(s, l, dist, i, rng)) {
                sum += c;
            }
        }
    }
    if (!SCENE_SAMPLES_ENVIRONMENT || params.environment_map.z == 0u) {
        return sum;
    }
    vec2 u = sample2(DRAW_ENVIRONMENT, depth, 0u, rng);
    vec3 l;
    float pdf;
    if (sample_environment(u, l, pdf)) {
        vec3 f = bsdf_times_cos(s, m, v, l);
        if (any(greaterThan(f, vec3(0.0))) && !blocked(spawn_origin(s, l), l, NO_HIT, NO_LIGHT, rng)) {
            float weight = mis_weight(pdf, bsdf_pdf(s, m, lobe_choice(m), v, l));
            sum += f * environment_radiance(l) * (weight / pdf);
        }
    }
    return sum;
}

vec3 camera_ray(vec2 film) {
    vec2 ndc = film / vec2(params.counts.zw) * 2.0 - 1.0;
    return normalize(params.forward.xyz + params.right.xyz * ndc.x - params.up.xyz * ndc.y);
}

// One sample of the radiance through film position `film` (pixels). Next-event estimation at
// each vertex draws from a stream of its own, keyed by `light_key` and the depth, so the path and
// every other vertex's light samples are the same whichever terms the flags leave out.
vec3 path_radiance(vec2 film, inout uint rng, uint light_key) {
    bool skip_direct = (batch.flags & FLAG_INDIRECT_ONLY) != 0u;
    vec3 d = camera_ray(film);
    Hit h = trace_visible(params.eye.xyz, d, rng);
    if (h.triangle < 0) {
        if (skip_direct) {
            return vec3(0.0);
        }
        return h.light >= 0 ? light_seen(uint(h.light), d) : environment_radiance(d);
    }
    vec3 radiance = vec3(0.0);
    vec3 throughput = vec3(1.0);
    for (uint depth = 0u;; ++depth) {
        // Light gathered at this vertex (by NEE, or hit by the sampled ray) has made depth + 1
        // surface interactions; primary emission has made none.
        bool counted = !skip_direct || depth >= 1u;
        Material m;
        Surface s = surface_at(h, d, m);
        vec3 v = -d;
        if (depth == 0u && counted) {
            radiance += m.emission.rgb;
        }
        if (counted) {
            uint light_rng = pcg_hash(light_key ^ pcg_hash(depth));
            radiance += throughput * direct_light(s, m, v, depth, light_rng);
        }
        // Past the last vertex a ray can only add emission or the environment: where the scene
        // has neither, the path ends here with the same estimate and one ray fewer.
        if (depth >= batch.bounces && params.options.x == 0u) {
            break;
        }
        vec3 l;
        vec3 weight;
        float pdf;
        if (!sample_bsdf(s, m, v, depth, rng, l, weight, pdf)) {
            break;
        }
        throughput *= weight;
        d = l;
        h = trace_visible(spawn_origin(s, l), d, rng);
        if (h.light >= 0) {
            break;  // area lights were sampled by next-event estimation
        }
        if (h.triangle < 0) {
            if (counted) {
                radiance += throughput * environment_radiance(d) * mis_weight(pdf, environment_pdf(d));
            }
            break;
        }
        if (counted) {
            radiance += throughput * table_vec4(material_table, 5u * material_index_of(uint(h.triangle)) + 3u).rgb;
        }
        if (depth >= batch.bounces) {
            break;
        }
        // Russian roulette: where bounce `roulette_after` or a later one hits, the path goes on with
        // probability q (its throughput's largest channel, at most 0.95) and its throughput is
        // divided by q, so the expected value is that of the path without roulette.
        if (depth + 1u >= batch.roulette_after) {
            float q = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95);
            if (sample1(DRAW_ROULETTE, depth, rng) >= q) {
                break;
            }
            throughput /= q;
        }
    }
    return radiance;
}

void main() {
    uvec2 size = params.counts.zw;
    uvec2 pixel = gl_GlobalInvocationID.xy + uvec2(0u, batch.first_row);
    if (any(greaterThanEqual(pixel, size))) {
        return;
    }
    vec4 mean = vec4(0.0);
    vec4 m2 = vec4(0.0);
    if (batch.sample_offset > 0u) {
        mean = imageLoad(mean_radiance, ivec2(pixel));
        m2 = imageLoad(second_moment, ivec2(pixel));
    }
    uint pixel_index = pixel.y * size.x + pixel.x;
    // Each pixel goes on from the samples it holds to the batch's end: after a batch cut short
    // for some pixels only, those that finished it already hold its samples and add nothing
    // when it is run again with fewer, instead of counting samples twice.
    uint have = batch.sample_offset > 0u ? uint(m2.a) : 0u;
    uint end = max(batch.sample_offset + batch.sample_count, have);
    uint done = 0u;
    vec3 replicate_sum[SOBOL_REPLICATES];
    for (uint r = 0u; r < SOBOL_REPLICATES; ++r) {
        replicate_sum[r] = SAMPLER_SOBOL && have > 0u ? imageLoad(replicate_sums, ivec3(pixel, r)).rgb : vec3(0.0);
    }
    for (uint index = have; index < end; ++index) {
        uint rng = rng_start(pixel_index, index, batch.seed);
        uint light_key = rng_start(pixel_index, index, batch.seed ^ LIGHT_STREAM);
        sampler_start(pixel_index, index, batch.seed);
        // Box filter: uniform over the pixel's square.
        vec2 film = vec2(pixel) + sample2(DRAW_PIXEL, 0u, 0u, rng);
        vec3 x = path_radiance(film, rng, light_key);
        vec3 delta = x - mean.rgb;
        mean.rgb += delta / float(index + 1u);
        m2.rgb += delta * (x - mean.rgb);
        if (SAMPLER_SOBOL) {
            replicate_sum[index % SOBOL_REPLICATES] += x;
        }
        done += 1u;
    }
    // llvmpipe stops every loop of an invocation once all of them together have run 65,535
    // iterations: a sample's ray traversal would end early and the batch would lose samples,
    // silently. Once that budget is spent a loop runs its body once more and exits, so this one
    // counts to lights + 2 only while budget remains (its bound comes from a buffer, so no
    // compiler can unroll it). A batch cut short is not stored: the host sees the count in
    // `status`, and runs it again with fewer samples per invocation.
    uint canary = 0u;
    for (uint i = 0u; i < params.counts.x + 2u; ++i) {
        canary += 1u;
    }
    if (have + done != end || canary != params.counts.x + 2u) {
        atomicAdd(status.short_pixels, 1u);
        return;
    }
    mean.a = 1.0;
    // The samples this pixel holds: the host checks that every pixel holds all it asked for.
    m2.a = float(end);
    imageStore(mean_radiance, ivec2(pixel), mean);
    imageStore(second_moment, ivec2(pixel), m2);
    if (SAMPLER_SOBOL) {
        for (uint r = 0u; r < SOBOL_REPLICATES; ++r) {
            imageStore(replicate_sums, ivec3(pixel, r), vec4(replicate_sum[r], 0.0));
        }
    }
}
