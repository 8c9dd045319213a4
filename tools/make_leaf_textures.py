#!/usr/bin/env python3
"""Writes scenes/textures/leaf_albedo.png and scenes/textures/leaf_normal.png, the leaf maps of
the generated `bush` mesh (scenes/lpv_bush.toml), as 128x128 RGBA8 PNGs. Seed 004's channel
packing (its digest, section 2.9): the albedo map's alpha is the wind weight ("floppiness"),
the normal map's alpha the leaf's translucency (thin = 1). Penumbra's methods read only RGB.

The leaf fills the map with its tip at the top (v = 0, row 0) and its stem at the bottom (v = 1);
the mesh's leaves are diamonds with the tip at (0.5, 0), the stem at (0.5, 1) and the widest
points at (0, 0.6) and (1, 0.6). Texels outside the diamond carry the same lamina, so filtering
at a leaf's edge stays green, except the bark patch in the lower-left corner (u < 0.2,
v > 0.85, well outside the diamond) where the bush's trunk and branches take their uvs.

 - leaf_albedo.png: RGB an sRGB-encoded pale leaf green (the material's albedo gives the hue:
   scenes/lpv_bush.toml multiplies it by (0.45, 0.6, 0.25)) with lighter veins, a midrib and
   six secondary veins a side running toward the tip, slight mottling and a darker margin;
   brown bark in the corner patch. A = wind weight t^2, t going linearly from 0 on the stem's
   row (the last) to 1 on the tip's (the first); 0 on the bark.
 - leaf_normal.png: an OpenGL-convention tangent-space normal map (red toward +u, green toward
   -v, "up" in the image) of a height field whose veins are ridges:
   n = normalize(-s dh/dx, s dh/dy, 1), per texel, y down the rows. A = translucency, 0.85 on
   the lamina, lower on the veins and midrib (thicker), 0 on the bark (flat there).

Only the Python 3 standard library (zlib + struct write the PNGs), deterministic; rerun to
regenerate: python3 tools/make_leaf_textures.py"""
import math
import os
import struct
import zlib

N = 128
TIP_V, WIDE_V = 0.0, 0.6
BARK = (0.2, 0.85)  # the bark patch: u < 0.2 and v > 0.85


def hash01(x, y, seed):
    h = (x * 0x8DA6B343 ^ y * 0xD8163841 ^ seed * 0xCB1AB31F) & 0xFFFFFFFF
    h ^= h >> 13
    h = (h * 0x5BD1E995) & 0xFFFFFFFF
    h ^= h >> 15
    return (h & 0xFFFFFF) / 16777216.0


def noise(u, v, cells, seed):
    """Smooth value noise in [0, 1) with `cells` cells across the map."""
    fx, fy = u * cells, v * cells
    ix, iy = math.floor(fx), math.floor(fy)
    tx, ty = fx - ix, fy - iy
    sx, sy = tx * tx * (3 - 2 * tx), ty * ty * (3 - 2 * ty)
    a = hash01(ix, iy, seed) + (hash01(ix + 1, iy, seed) - hash01(ix, iy, seed)) * sx
    b = hash01(ix, iy + 1, seed) + (hash01(ix + 1, iy + 1, seed) - hash01(ix, iy + 1, seed)) * sx
    return a + (b - a) * sy


def half_width(v):
    """Half the diamond's width at v (0 at the tip and the stem, 0.5 at v = 0.6)."""
    return 0.5 * v / WIDE_V if v < WIDE_V else 0.5 * (1.0 - v) / (1.0 - WIDE_V)


def segment_distance(p, a, b):
    ax, ay = b[0] - a[0], b[1] - a[1]
    t = max(0.0, min(1.0, ((p[0] - a[0]) * ax + (p[1] - a[1]) * ay) / (ax * ax + ay * ay)))
    return math.hypot(p[0] - a[0] - t * ax, p[1] - a[1] - t * ay)


def secondary_veins():
    """Six veins a side: from the midrib toward the margin and the tip, ending at the outline."""
    veins = []
    for k in range(6):
        v0 = 0.2 + 0.13 * k
        for side in (-1.0, 1.0):
            # March along (side, -0.8) until the diamond's edge.
            end = (0.5, v0)
            for i in range(1, 200):
                u, v = 0.5 + side * 0.005 * i, v0 - 0.004 * i
                if v <= 0.0 or abs(u - 0.5) >= half_width(v):
                    break
                end = (u, v)
            veins.append(((0.5, v0), end))
    return veins


VEINS = secondary_veins()


def ridge(d, w):
    return math.exp(-(d / w) ** 2)


def fields(u, v):
    """(midrib, veins, margin) at (u, v): the two vein profiles in [0, 1], and how far toward the
    outline the point lies (0 on the midrib, 1 on and beyond the outline)."""
    hw = half_width(v)
    margin = min(1.0, abs(u - 0.5) / hw) if hw > 1e-6 else 1.0
    mid_w = 0.004 + 0.012 * v  # the midrib thickens toward the stem
    midrib = ridge(abs(u - 0.5), mid_w) if v > 0.01 else 0.0
    veins = 0.0
    for a, b in VEINS:
        veins = max(veins, ridge(segment_distance((u, v), a, b), 0.0075))
    return midrib, veins * (1.0 - 0.6 * margin), margin


def in_bark(u, v):
    return u < BARK[0] and v > BARK[1]


def height(u, v):
    midrib, veins, margin = fields(u, v)
    return 1.0 * midrib + 0.5 * veins + 0.05 * noise(u, v, 16, 3) - 0.15 * margin * margin


def srgb(c):
    c = max(0.0, min(1.0, c))
    s = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
    return int(s * 255 + 0.5)


def unorm(c):
    return int(max(0.0, min(1.0, c)) * 255 + 0.5)


def albedo_texel(x, y):
    u, v = (x + 0.5) / N, (y + 0.5) / N
    if in_bark(u, v):
        streak = 0.6 * noise(u * 4.0, v * 0.25, 32, 17) + 0.4 * noise(u, v, 64, 19)
        c = [k * (0.75 + 0.5 * streak) for k in (0.32, 0.22, 0.13)]
        return [srgb(k) for k in c] + [0]
    midrib, veins, margin = fields(u, v)
    mottle = 0.9 + 0.2 * (0.6 * noise(u, v, 8, 5) + 0.4 * noise(u, v, 32, 7))
    lamina = [k * mottle for k in (0.55, 0.72, 0.36)]
    edge = [0.5, 0.62, 0.26]  # a darker, yellower margin
    w = margin ** 4
    lamina = [l * (1 - w) + e * w for l, e in zip(lamina, edge)]
    vein = max(midrib, veins)
    c = [l * (1 - vein) + h * vein for l, h in zip(lamina, (0.78, 0.86, 0.5))]
    # Wind weight: 0 on the stem's row, 1 on the tip's, quadratic in between.
    t = (N - 1 - y) / (N - 1)
    return [srgb(k) for k in c] + [unorm(t * t)]


def normal_texel(x, y, h):
    u, v = (x + 0.5) / N, (y + 0.5) / N
    if in_bark(u, v):
        return [128, 128, 255, 0]

    def at(i, j):
        return h[min(max(j, 0), N - 1)][min(max(i, 0), N - 1)]

    s = 1.5
    dx = 0.5 * (at(x + 1, y) - at(x - 1, y))
    dy = 0.5 * (at(x, y + 1) - at(x, y - 1))
    n = (-s * dx, s * dy, 1.0)
    length = math.sqrt(sum(c * c for c in n))
    midrib, veins, _ = fields(u, v)
    translucency = 0.85 - 0.45 * veins - 0.55 * midrib
    return [unorm(c / length * 0.5 + 0.5) for c in n] + [unorm(translucency)]


def write_png(path, rows):
    raw = b"".join(b"\x00" + bytes(row) for row in rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", N, N, 8, 6, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "textures")
    albedo = [[c for x in range(N) for c in albedo_texel(x, y)] for y in range(N)]
    h = [[height((x + 0.5) / N, (y + 0.5) / N) for x in range(N)] for y in range(N)]
    normal = [[c for x in range(N) for c in normal_texel(x, y, h)] for y in range(N)]
    for name, rows in (("leaf_albedo.png", albedo), ("leaf_normal.png", normal)):
        path = os.path.normpath(os.path.join(out, name))
        write_png(path, rows)
        print(f"{path}: {os.path.getsize(path)} bytes")


if __name__ == "__main__":
    main()
