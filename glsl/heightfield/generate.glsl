// Height-field generators, the GPU twin of HeightfieldSource::height_at (src/scene/heightfield.rs):
// same formulas, same integer hash, same order of operations.
#ifndef PENUMBRA_HF_GENERATE_GLSL
#define PENUMBRA_HF_GENERATE_GLSL

// Matches `GenParams` in src/heightfield/gpu.rs.
struct HfGen {
    uvec4 kind;      // x: shape code (HeightShape::code), y: count/octaves, z: seed, w: image present
    vec4 shape;      // x: wavelength / slope tan / step position, y: radius, z: ring radius, w: size variation / street
    vec4 placement;  // x: height, y: taper, z: offset x, w: offset z
    vec4 motion;     // x: cos(pattern rotation), y: sin(pattern rotation), z: speed, w: time
    vec4 field;      // x: size (m), y: samples per side, z: image width, w: image height
};

uint hf_hash_u(int ix, int iz, uint seed) {
    uint h = (uint(ix) * 0x8da6b343u) ^ (uint(iz) * 0xd8163841u) ^ (seed * 0xcb1ab31fu);
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

float hf_hash(int ix, int iz, uint seed) {
    return float(hf_hash_u(ix, iz, seed) >> 8) / 16777216.0;
}

float hf_smooth(float t) { return t * t * (3.0 - 2.0 * t); }

float hf_value_noise(float x, float z, uint seed) {
    float fx = floor(x), fz = floor(z);
    int ix = int(fx), iz = int(fz);
    float tx = hf_smooth(x - fx), tz = hf_smooth(z - fz);
    float a = hf_hash(ix, iz, seed);
    float b = hf_hash(ix + 1, iz, seed);
    float c = hf_hash(ix, iz + 1, seed);
    float d = hf_hash(ix + 1, iz + 1, seed);
    float ab = a + (b - a) * tx;
    float cd = c + (d - c) * tx;
    return ab + (cd - ab) * tz;
}

// Bilinear value of the source image at continuous pixel coordinates, clamped to the edge.
float hf_image_bilinear(sampler2D img, vec2 px) {
    ivec2 size = textureSize(img, 0);
    vec2 f = floor(px);
    vec2 t = px - f;
    ivec2 p0 = ivec2(f);
    float a00 = texelFetch(img, clamp(p0, ivec2(0), size - 1), 0).r;
    float a10 = texelFetch(img, clamp(p0 + ivec2(1, 0), ivec2(0), size - 1), 0).r;
    float a01 = texelFetch(img, clamp(p0 + ivec2(0, 1), ivec2(0), size - 1), 0).r;
    float a11 = texelFetch(img, clamp(p0 + ivec2(1, 1), ivec2(0), size - 1), 0).r;
    float a = a00 + (a10 - a00) * t.x;
    float b = a01 + (a11 - a01) * t.x;
    return a + (b - a) * t.y;
}

float hf_taper(HfGen g, float x, float z) {
    float taper = g.placement.y;
    if (taper <= 0.0) return 1.0;
    float half_size = 0.5 * g.field.x;
    float band = taper * half_size;
    float wx = hf_smooth(clamp((half_size - abs(x)) / band, 0.0, 1.0));
    float wz = hf_smooth(clamp((half_size - abs(z)) / band, 0.0, 1.0));
    return wx * wz;
}

// Height (object space, metres) at (x, z) at the generator's time.
float hf_height(HfGen g, float x, float z, sampler2D img) {
    float c = g.motion.x, s = g.motion.y;
    float dx = x - g.placement.z, dz = z - g.placement.w;
    float qx = c * dx + s * dz;
    float qz = -s * dx + c * dz;
    uint kind = g.kind.x;
    float t = g.motion.w;
    if (kind != 4u) qx -= g.motion.z * t;
    float a = g.placement.x;
    const float TAU = 6.283185307179586;
    float h = 0.0;
    if (kind == 0u) {
        h = a;
    } else if (kind == 1u) {
        h = g.shape.x * qx;
    } else if (kind == 2u) {
        h = qx > g.shape.x ? a : 0.0;
    } else if (kind == 3u) {
        h = a * (0.5 + 0.5 * sin(TAU * qx / g.shape.x));
    } else if (kind == 4u) {
        uint count = g.kind.y;
        for (uint k = 0u; k < count; ++k) {
            float ang = TAU * float(k) / float(count) + g.motion.z * t;
            float cx = g.shape.z * cos(ang), cz = g.shape.z * sin(ang);
            float sk = 1.0 - g.shape.w * float(k) / float(count);
            float r = sqrt((qx - cx) * (qx - cx) + (qz - cz) * (qz - cz));
            h = max(h, a * sk * max(1.0 - r / (g.shape.y * sk), 0.0));
        }
    } else if (kind == 5u) {
        float sum = 0.0, norm = 0.0, amp = 1.0, freq = 1.0 / g.shape.x;
        for (uint o = 0u; o < g.kind.y; ++o) {
            sum += amp * hf_value_noise(qx * freq, qz * freq, g.kind.z + o);
            norm += amp;
            amp *= 0.5;
            freq *= 2.0;
        }
        float peak = max(sum / max(norm, 1e-6) - 0.4, 0.0) / 0.6;
        h = a * peak * peak;
    } else if (kind == 6u) {
        h = a * (0.5 + 0.5 * sin(TAU * qx / g.shape.x) * sin(TAU * qz / g.shape.x));
    } else if (kind == 7u) {
        float u = qx / g.shape.x, v = qz / g.shape.x;
        float cu = floor(u), cv = floor(v);
        float fu = u - cu, fv = v - cv;
        float half_width = 0.5 * (1.0 - g.shape.w);
        bool inside = abs(fu - 0.5) < half_width && abs(fv - 0.5) < half_width;
        bool empty = hf_hash(int(cu), int(cv), g.kind.z + 7919u) < 0.15;
        h = (inside && !empty) ? a * (0.25 + 0.75 * hf_hash(int(cu), int(cv), g.kind.z)) : 0.0;
    } else if (kind == 8u && g.kind.w != 0u) {
        vec2 px = vec2((qx / g.field.x + 0.5) * g.field.z - 0.5, (qz / g.field.x + 0.5) * g.field.w - 0.5);
        h = a * hf_image_bilinear(img, px);
    }
    return h * hf_taper(g, x, z);
}

#endif
