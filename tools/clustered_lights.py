#!/usr/bin/env python3
"""Frame time against light count, clustered and forward (README, "Clustered shading").

Writes one scene per light count: a 32 m floor with a 4 x 4 block of boxes, and N point lights
on a square grid 0.5 m above it (every other one a spot light aimed down). The grid's pitch
shrinks as N grows, and each light's radius is 2.5 pitches, so every surface point is within
range of about the same number of lights (~20) whatever N: the many-lights setting clustered
shading is for. Intensities scale with the radius squared, so the image stays as bright.

Then runs `penumbra profile` on each scene with each method and prints the medians (ms) of the
frame and of each pass. Usage: tools/clustered_lights.py [--size WxH] [--frames N] [--counts 64,1024]
[--methods clustered,forward] [--penumbra target/debug/penumbra] [--device llvmpipe]
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile


def scene(n: int) -> str:
    side = 32.0
    per_row = max(1, round(math.sqrt(n)))
    pitch = side / per_row
    radius = 2.5 * pitch
    intensity = 0.05 * radius * radius
    out = [
        'methods = ["clustered", "forward"]',
        "[camera]\nposition = [0, 9, 18]\ntarget = [0, 0, -2]\nfov_y_deg = 60\n",
        '[[materials]]\nname = "floor"\nalbedo = [0.7, 0.6, 0.5]\nspecular = 0.2\nexponent = 16\n',
        '[[objects]]\nmesh = "plane"\nsize = [32, 32]\nmaterial = "floor"\n',
    ]
    for i in range(4):
        for j in range(4):
            x, z = -9.0 + 6.0 * i, -9.0 + 6.0 * j
            out.append(f'[[objects]]\nmesh = "box"\nsize = [1.5, 2, 1.5]\ntranslate = [{x}, 1, {z}]\nmaterial = "floor"\n')
    k = 0
    for i in range(per_row):
        for j in range(per_row):
            if k == n:
                break
            x, z = -side / 2 + pitch * (i + 0.5), -side / 2 + pitch * (j + 0.5)
            c = [0.6 + 0.4 * ((k * 7) % 5) / 4, 0.6 + 0.4 * ((k * 3) % 5) / 4, 0.6 + 0.4 * ((k * 11) % 5) / 4]
            col = f"[{c[0] * intensity:.4f}, {c[1] * intensity:.4f}, {c[2] * intensity:.4f}]"
            if k % 2:
                out.append(f'[[lights]]\ntype = "spot"\nposition = [{x:.3f}, 1.5, {z:.3f}]\ndirection = [0, -1, 0]\nouter_deg = 50\nintensity = {col}\nradius = {radius:.3f}\n')
            else:
                out.append(f'[[lights]]\ntype = "point"\nposition = [{x:.3f}, 0.5, {z:.3f}]\nintensity = {col}\nradius = {radius:.3f}\n')
            k += 1
    return "\n".join(out)


def profile(exe, path, method, size, frames, device):
    cmd = [exe, "profile", path, "--method", method, "--size", size, "--frames", str(frames)]
    if device:
        cmd += ["--device", device]
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    # A cluster out of slots drops light: a faster frame of a wrong image. Say so.
    for line in text.splitlines():
        if line.startswith("warning: "):
            print(f"{method} ({os.path.basename(path)}): {line}", flush=True)
    medians = {}
    for line in text.splitlines():
        parts = line.rsplit(None, 3)
        if len(parts) == 4:
            try:
                medians[parts[0].strip()] = float(parts[1])
            except ValueError:
                pass
    return text.splitlines()[0], medians


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", default="640x360")
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--counts", default="64,1024")
    ap.add_argument("--methods", default="clustered,forward")
    ap.add_argument("--penumbra", default="target/debug/penumbra")
    ap.add_argument("--device", default="llvmpipe")
    a = ap.parse_args()
    counts = [int(c) for c in a.counts.split(",")]
    methods = a.methods.split(",")
    results = {}
    with tempfile.TemporaryDirectory() as d:
        for n in counts:
            path = os.path.join(d, f"lights_{n}.toml")
            with open(path, "w") as f:
                f.write(scene(n))
            for m in methods:
                header, medians = profile(a.penumbra, path, m, a.size, a.frames, a.device)
                results[(m, n)] = medians
                passes = ", ".join(f"{k} {v:.1f}" for k, v in medians.items() if k != "frame")
                print(f"{m:10s} {n:5d} lights: frame {medians.get('frame', float('nan')):.1f} ms ({passes})", flush=True)
    print(header.split(", " + a.size)[0] + f", {a.size}, {a.frames} frames, medians")
    for m in methods:
        if (m, counts[0]) in results and (m, counts[-1]) in results:
            lo, hi = results[(m, counts[0])]["frame"], results[(m, counts[-1])]["frame"]
            print(f"{m}: {counts[-1]} lights cost {hi / lo:.2f}x what {counts[0]} cost")


if __name__ == "__main__":
    sys.exit(main())
