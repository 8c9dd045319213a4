// The material model of glsl/common/lights.glsl as a sampled BSDF: Lambert rho/pi plus the
// energy-normalised Blinn-Phong lobe (reflection, evaluated by `brdf_times_cos` itself), plus
// thin-surface diffuse transmission tau/pi into the other hemisphere.
//
// Directions are sampled from a mixture of a cosine lobe, the Blinn-Phong half-vector lobe and a
// cosine lobe on the back side, each chosen with probability proportional to its colour's
// luminance; the weight is f cos / (mixture pdf), so every lobe can produce every direction the
// BSDF is non-zero for.
#ifndef PENUMBRA_REFERENCE_BSDF_GLSL
#define PENUMBRA_REFERENCE_BSDF_GLSL

#include "common/lights.glsl"
#include "reference/features.glsl"
#include "reference/rng.glsl"

struct Material {
    vec4 albedo;         // rgb: diffuse albedo
    vec4 specular;       // rgb: Blinn-Phong colour; w: exponent
    vec4 transmittance;  // rgb: diffuse transmittance of a thin surface
    vec4 emission;       // rgb: emitted radiance (both sides)
    uvec4 maps;          // x: albedo, y: normal, z: specular map, each a texture index + 1 (0: none)
};

// A point on a surface, normals turned toward the side the path arrived from.
struct Surface {
    vec3 p;
    vec3 shading_normal;
    vec3 geometric_normal;
};

struct LobeChoice {
    float diffuse;
    float specular;
    float transmit;
};

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

LobeChoice lobe_choice(Material m) {
    float d = luminance(m.albedo.rgb);
    float s = luminance(m.specular.rgb);
    float t = luminance(m.transmittance.rgb);
    float total = d + s + t;
    if (total <= 0.0) {
        return LobeChoice(0.0, 0.0, 0.0);
    }
    return LobeChoice(d / total, s / total, t / total);
}

// Orthonormal tangents of unit `n` (Duff et al., "Building an Orthonormal Basis, Revisited").
void tangent_basis(vec3 n, out vec3 t, out vec3 b) {
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + sgn * n.x * n.x * a, sgn * c, -sgn * n.x);
    b = vec3(c, sgn + n.y * n.y * a, -n.y);
}

vec3 around(vec3 n, float cos_theta, float sin_theta, float phi) {
    vec3 t;
    vec3 b;
    tangent_basis(n, t, b);
    return normalize(t * (sin_theta * cos(phi)) + b * (sin_theta * sin(phi)) + n * cos_theta);
}

// pdf cos(theta) / pi.
vec3 sample_cosine(vec3 n, vec2 u) {
    return around(n, sqrt(max(0.0, 1.0 - u.x)), sqrt(u.x), 2.0 * PI * u.y);
}

// Half vectors with pdf (e + 1) / (2 pi) (n.h)^e.
vec3 sample_blinn_half(vec3 n, float exponent, vec2 u) {
    float cos_theta = pow(u.x, 1.0 / (exponent + 1.0));
    return around(n, cos_theta, sqrt(max(0.0, 1.0 - cos_theta * cos_theta)), 2.0 * PI * u.y);
}

// Solid-angle pdf of `l` under the Blinn half-vector lobe reflected about v.
float blinn_pdf(vec3 n, vec3 v, vec3 l, float exponent) {
    vec3 h = normalize(v + l);
    float v_dot_h = dot(v, h);
    float n_dot_h = dot(n, h);
    if (v_dot_h <= 0.0 || n_dot_h <= 0.0) {
        return 0.0;
    }
    return (exponent + 1.0) / (2.0 * PI) * pow(n_dot_h, exponent) / (4.0 * v_dot_h);
}

// f(v, l) |n.l|. Reflection needs l on the viewer's side of both normals, transmission on the
// other side of both: where interpolated normals and the true surface disagree the BSDF is zero
// rather than letting a path slip through the mesh.
vec3 bsdf_times_cos(Surface s, Material m, vec3 v, vec3 l) {
    float g = dot(s.geometric_normal, l);
    float c = dot(s.shading_normal, l);
    if (g > 0.0 && c > 0.0) {
        if (!SCENE_HAS_SPECULAR) {
            // brdf_times_cos with no specular colour: the same arithmetic, less the zero lobe.
            return m.albedo.rgb / PI * c;
        }
        return brdf_times_cos(s.shading_normal, v, l, m.albedo.rgb, m.specular.rgb, m.specular.w);
    }
    if (SCENE_HAS_TRANSMISSION && g < 0.0 && c < 0.0) {
        return m.transmittance.rgb / PI * -c;
    }
    return vec3(0.0);
}

// Density of `sample_bsdf` producing l. The Blinn lobe also reflects some directions below the
// surface, into the transmission hemisphere, so its density counts on both sides.
float bsdf_pdf(Surface s, Material m, LobeChoice p, vec3 v, vec3 l) {
    float c = dot(s.shading_normal, l);
    float pdf = c > 0.0 ? p.diffuse * c / PI : (SCENE_HAS_TRANSMISSION ? p.transmit * -c / PI : 0.0);
    if (SCENE_HAS_SPECULAR && p.specular > 0.0) {
        pdf += p.specular * blinn_pdf(s.shading_normal, v, l, m.specular.w);
    }
    return pdf;
}

// Samples the next direction at path depth `depth`; `weight` = f |cos| / pdf. False when the
// path ends here.
bool sample_bsdf(Surface s, Material m, vec3 v, uint depth, inout uint rng, out vec3 l, out vec3 weight, out float pdf) {
    weight = vec3(0.0);
    pdf = 0.0;
    LobeChoice p = lobe_choice(m);
    float choice = sample1(DRAW_LOBE, depth, rng);
    vec2 u = sample2(DRAW_BSDF, depth, 0u, rng);
    if (choice < p.diffuse) {
        l = sample_cosine(s.shading_normal, u);
    } else if (SCENE_HAS_SPECULAR && choice < p.diffuse + p.specular) {
        vec3 h = sample_blinn_half(s.shading_normal, m.specular.w, u);
        float v_dot_h = dot(v, h);
        if (v_dot_h <= 0.0) {
            return false;
        }
        l = 2.0 * v_dot_h * h - v;
    } else if (SCENE_HAS_TRANSMISSION && p.transmit > 0.0) {
        l = sample_cosine(-s.shading_normal, u);
    } else {
        l = vec3(0.0);
        return false;
    }
    vec3 f = bsdf_times_cos(s, m, v, l);
    pdf = bsdf_pdf(s, m, p, v, l);
    if (pdf <= 0.0 || all(equal(f, vec3(0.0)))) {
        return false;
    }
    weight = f / pdf;
    return true;
}

#endif
