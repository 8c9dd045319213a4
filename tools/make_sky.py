#!/usr/bin/env python3
"""Writes scenes/terrain/sky.hdr, the generated sky of scenes/terrain_sky.toml: a 128x64
equirectangular Radiance HDR (flat RGBE scanlines) in penumbra's mapping (v = 0 straight up,
u = 0.5 toward -z, u = 0.75 toward +x). Radiance in W/(m^2 sr): a blue zenith fading to a pale
horizon, a broad warm glow about a low sun 25 degrees up toward -x, -z, and a dark ground.
Smooth on purpose: the height-field methods see it through 4-6 SH bands and the reference
samples it texel by texel, so a pin-point sun would only measure ringing and noise.
Deterministic; rerun to regenerate: python3 tools/make_sky.py"""
import math
import os

W, H = 128, 64
SUN = (-math.cos(math.radians(25)) * math.sqrt(0.5), math.sin(math.radians(25)), -math.cos(math.radians(25)) * math.sqrt(0.5))


def radiance(d):
    x, y, z = d
    if y < 0.0:
        g = 0.06 + 0.04 * math.exp(8.0 * y)  # ground, brightening toward the horizon
        return (g, 0.9 * g, 0.75 * g)
    t = 1.0 - y
    sky = (0.25 + 0.45 * t ** 3, 0.38 + 0.42 * t ** 3, 0.75 + 0.15 * t ** 3)
    c = max(0.0, x * SUN[0] + y * SUN[1] + z * SUN[2])
    glow = 6.0 * c ** 24 + 0.6 * c ** 4
    return (sky[0] + glow, sky[1] + 0.8 * glow, sky[2] + 0.55 * glow)


def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes(4)
    mant, exp = math.frexp(m)
    scale = mant * 256.0 / m
    return bytes([int(c[0] * scale), int(c[1] * scale), int(c[2] * scale), exp + 128])


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "terrain", "sky.hdr")
    data = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {H} +X {W}\n".encode())
    for j in range(H):
        theta = (j + 0.5) / H * math.pi
        for i in range(W):
            phi = ((i + 0.5) / W - 0.5) * 2.0 * math.pi
            d = (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))
            data += rgbe(radiance(d))
    with open(out, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
