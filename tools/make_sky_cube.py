#!/usr/bin/env python3
"""Writes scenes/terrain/sky_cube/{px,nx,py,ny,pz,nz}.hdr, the cube-map sky of
scenes/terrain_sky_cube.toml: the sky of tools/make_sky.py (the same radiance function) as six
32x32 Radiance HDR faces (flat RGBE scanlines) in Vulkan's layer order, oriented as
scenes/README.md documents: on face k the texel in column x, row y (row 0 at the top) looks along
cube_dir(k, s, t) with s = 2(x + 0.5)/32 - 1, t = 2(y + 0.5)/32 - 1. So terrain_sky_cube.toml and
terrain_sky.toml light the mountains with one sky in two layouts.
Deterministic; rerun to regenerate: python3 tools/make_sky_cube.py"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_sky import radiance, rgbe  # noqa: E402

N = 32
FACES = ["px", "nx", "py", "ny", "pz", "nz"]


def cube_dir(face, s, t):
    """Matches Environment::cube_dir in src/scene/types.rs (Vulkan's face selection table)."""
    return [
        (1.0, -t, -s),
        (-1.0, -t, s),
        (s, 1.0, t),
        (s, -1.0, -t),
        (s, -t, 1.0),
        (-s, -t, -1.0),
    ][face]


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "terrain", "sky_cube")
    os.makedirs(out, exist_ok=True)
    for face, name in enumerate(FACES):
        data = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {N} +X {N}\n".encode())
        for y in range(N):
            for x in range(N):
                d = cube_dir(face, 2.0 * (x + 0.5) / N - 1.0, 2.0 * (y + 0.5) / N - 1.0)
                r = math.sqrt(sum(c * c for c in d))
                data += rgbe(radiance(tuple(c / r for c in d)))
        with open(os.path.join(out, name + ".hdr"), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
