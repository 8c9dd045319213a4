#!/usr/bin/env python3
"""`penumbra reference` side by side with Mitsuba 3 on the same scenes, size and samples per pixel.

For each case the scene is exported exactly as the path tracer sees it
(`penumbra reference SCENE --export-scene DIR`: world-space triangles per material as PLY, the
camera, materials, lights and environment as JSON) and rebuilt as a Mitsuba scene dict: the
same camera (perspective, vertical field of view, box pixel filter), Lambertian materials
(two-sided, as penumbra's surfaces are), quad and sphere lights as area emitters on a rectangle
or sphere with a black BSDF (penumbra's area lights are opaque and reflect nothing), the constant
environment as a `constant` emitter. Bounces: penumbra's `--bounces K` counts light after at most
K + 1 surface interactions, Mitsuba's `max_depth` = K + 2; `--direct-only` is `max_depth` = 2.
Mitsuba keeps its own Russian roulette (`rr_depth` 5), penumbra its default.

Prints one table: samples per second of each renderer (in brackets penumbra's rate over
Mitsuba's), the image means (luminance) and the agreement check: the largest |z| over the RGB
channels and the variants, z being the difference of the two image means over their combined
standard error (each renderer's from the scatter of the means of its CHUNKS renders, each of the
full spp with its own seed). Timing: penumbra's from its first dispatch to the
read-back image (the scene and pipeline are built before); Mitsuba's of `mi.render` and the
copy to numpy, after the scene is loaded (and, for the LLVM and CUDA variants, after a 1-spp
render that compiles their kernels).

Samples per second alone favour the renderer with the noisier samples, so the table also gives
each renderer's variance of one sample, per pixel and channel relative as the chart's relative
MSE weighs errors (over r^2 + 0.01, r being penumbra's image for both, so that both weigh the
pixels alike), averaged over the image: for both, the scatter of its CHUNKS renders pixel by
pixel times their spp (the error a render of that spp has, whatever the sampler; a stratified
sampler's samples are not independent, so neither a standard-error image nor renders of fewer
samples would give it). A renderer reaches a given relative MSE in a time proportional to that
variance over its samples per second, so the last column, penumbra's samples/s over its variance
divided by Mitsuba's, is penumbra's speed at equal error. `--penumbra-args '--sampler NAME'`
(penumbra's default is `sobol`) and `--mitsuba-sampler NAME` (Mitsuba's `independent`, `stratified`, `multijitter`, `orthogonal` or
`ldsampler`) choose the samplers.

Needs `python3 -m venv tools/.venv && tools/.venv/bin/pip install mitsuba numpy` (the mitsuba
wheel does not pull numpy in). The `llvm_ad_rgb` variant needs an LLVM newer than Debian 12's
system LLVM 15 (Dr.Jit's kernels fail to compile there); put one at tools/.venv/llvm19 (`apt-get download libllvm19 && dpkg -x libllvm19_*.deb tools/.venv/llvm19`)
or name it with --libllvm / DRJIT_LIBLLVM_PATH.

Usage:
    tools/.venv/bin/python tools/reference_vs_mitsuba.py [--size 64x64] [--cases cornell32,direct,furnace,terrain]
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# name: (scene, penumbra arguments, Mitsuba max_depth, spp, flip normals of emissive meshes)
CASES = {
    "cornell32": ("scenes/cornell.toml", ["--bounces", "32"], 34, 64, False),
    "direct": ("scenes/cornell.toml", ["--direct-only"], 2, 256, False),
    # The furnace is seen from inside a sphere whose normals face out; Mitsuba's area emitters
    # emit on the normals' side only, penumbra's emission is two-sided.
    "furnace": ("scenes/furnace.toml", [], 18, 16, True),
    "terrain": ("scenes/terrain_mountains.toml", [], 18, 64, False),
}


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--penumbra", default=str(ROOT / "target/release/penumbra"), help="penumbra binary (release build)")
    p.add_argument("--size", default="64x64")
    p.add_argument("--cases", default=",".join(CASES))
    p.add_argument("--variants", default="scalar_rgb,llvm_ad_rgb")
    p.add_argument("--spp-scale", type=float, default=1.0, help="multiply every case's spp")
    p.add_argument("--chunks", type=int, default=4, help="renders per case and renderer (different seeds, each of the full spp) for the error of one")
    p.add_argument("--mitsuba-sampler", default="independent", help="Mitsuba's sampler plugin (independent, stratified, multijitter, orthogonal, ldsampler)")
    p.add_argument("--libllvm", default=None, help="libLLVM for Dr.Jit's LLVM backend")
    p.add_argument("--penumbra-args", default="", help="extra arguments for penumbra reference (e.g. '--roulette-after off')")
    return p.parse_args()


def setup_llvm(path):
    if path is None and "DRJIT_LIBLLVM_PATH" not in os.environ:
        found = sorted(ROOT.glob("tools/.venv/llvm*/usr/lib/x86_64-linux-gnu/libLLVM.so.*"))
        path = str(found[-1]) if found else None
    if path:
        os.environ["DRJIT_LIBLLVM_PATH"] = path


def jit_variants_that_run(variants):
    """The variants left after dropping each LLVM or CUDA one that cannot render a 1-spp scene
    here, with one line saying why. Tried in a child process: Dr.Jit compiling its kernels with
    too old an LLVM (Debian 12's 15) aborts the process, which no exception handler would see."""
    kept = []
    for v in variants:
        if not v.startswith(("llvm", "cuda")):
            kept.append(v)
            continue
        probe = f"import mitsuba as mi; mi.set_variant({v!r}); mi.render(mi.load_dict(mi.cornell_box()), spp=1)"
        try:
            r = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
            ok, why = r.returncode == 0, (r.stderr.strip().splitlines() or ["exit status %d" % r.returncode])[0][:120]
        except subprocess.TimeoutExpired:
            ok, why = False, "a 1-spp render took over 300 s"
        if ok:
            kept.append(v)
        else:
            print(f"skipping Mitsuba variant {v}: {why} (for llvm_ad_rgb see --libllvm in this script's docstring)", file=sys.stderr)
    return kept


# Every file the run writes goes under one folder, removed when the run ends (however it ends).
WORK = None


def work_dir(prefix):
    return Path(tempfile.mkdtemp(prefix=prefix, dir=WORK))


def run_penumbra(binary, scene, args, size, spp, seed, extra):
    out = work_dir("penumbra-") / "ref.exr"
    cmd = [binary, "reference", str(ROOT / scene), "--size", size, "--spp", str(spp), "--seed", str(seed), "-o", str(out)] + args + extra
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr}")
    rate = float(re.search(r"([0-9.]+) samples/s", r.stdout).group(1))
    m = re.search(r"average radiance \(RGB\): (\S+) (\S+) (\S+), standard error (\S+) (\S+) (\S+)", r.stdout)
    vals = [float(x) for x in m.groups()]
    return rate, vals[:3], vals[3:], out


def export_scene(binary, scene, dest):
    r = subprocess.run([binary, "reference", str(ROOT / scene), "--export-scene", str(dest)], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"export of {scene} failed:\n{r.stderr}")
    return json.loads((dest / "scene.json").read_text())


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def mitsuba_scene(mi, exported, folder, size, max_depth, flip_emissive, sampler):
    T = mi.ScalarTransform4f
    cam = exported["camera"]
    w, h = size
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": cam["fov_y_deg"],
            "to_world": T().look_at(origin=cam["position"], target=cam["target"], up=cam["up"]),
            "film": {"type": "hdrfilm", "width": w, "height": h, "pixel_format": "rgb", "rfilter": {"type": "box"}},
            "sampler": {"type": sampler},
        },
    }
    black = {"type": "diffuse", "reflectance": rgb([0, 0, 0])}
    for k, m in enumerate(exported["materials"]):
        if m["mesh"] is None:
            continue
        plain = not any(m["specular"]) and not any(m["transmittance"]) and m["opacity"] >= 1.0 and not m["texture_maps"]
        if not plain:
            sys.exit(f"material {m['name']!r}: only Lambertian materials without maps are converted")
        shape = {
            "type": "ply",
            "filename": str(folder / m["mesh"]),
            "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb(m["albedo"])}},
        }
        if any(m["emission"]):
            shape["emitter"] = {"type": "area", "radiance": rgb(m["emission"])}
            shape["flip_normals"] = flip_emissive
        scene[f"material_{k}"] = shape
    for k, l in enumerate(exported["lights"]):
        if l["type"] == "quad":
            c, u, v = (l[x] for x in ("corner", "edge_u", "edge_v"))
            n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
            ln = math.sqrt(sum(x * x for x in n))
            centre = [c[i] + 0.5 * (u[i] + v[i]) for i in range(3)]
            # The rectangle spans [-1, 1]^2 in x, y with normal +z.
            matrix = [[0.5 * u[i], 0.5 * v[i], n[i] / ln, centre[i]] for i in range(3)] + [[0, 0, 0, 1]]
            scene[f"light_{k}"] = {"type": "rectangle", "to_world": T(matrix), "bsdf": black, "emitter": {"type": "area", "radiance": rgb(l["radiance"])}}
        elif l["type"] == "sphere":
            scene[f"light_{k}"] = {"type": "sphere", "center": l["center"], "radius": l["radius"], "bsdf": black, "emitter": {"type": "area", "radiance": rgb(l["radiance"])}}
        elif l["type"] == "point":
            scene[f"light_{k}"] = {"type": "point", "position": l["position"], "intensity": rgb(l["intensity"])}
        elif l["type"] == "directional":
            scene[f"light_{k}"] = {"type": "directional", "direction": l["direction"], "irradiance": rgb(l["irradiance"])}
        else:
            sys.exit(f"light {k}: {l['type']} lights are not converted")
    env = exported["environment"]
    if env is not None:
        if env["type"] != "constant":
            sys.exit(f"environment {env['type']}: only a constant environment is converted")
        scene["environment"] = {"type": "constant", "radiance": rgb(env["radiance"])}
    return scene


def render_mitsuba(variant, exported, folder, size, max_depth, flip, spp, chunks, sampler):
    import mitsuba as mi
    import numpy as np

    mi.set_variant(variant)
    scene = mi.load_dict(mitsuba_scene(mi, exported, folder, size, max_depth, flip, sampler))
    per_chunk = spp
    if variant.startswith(("llvm", "cuda")):
        np.array(mi.render(scene, spp=1, seed=999))  # compiles the kernels outside the timing
    means, images, seconds = [], [], 0.0
    for c in range(chunks):
        t0 = time.perf_counter()
        img = np.array(mi.render(scene, spp=per_chunk, seed=c))
        seconds += time.perf_counter() - t0
        images.append(img[..., :3].astype(np.float64))
        means.append(img.reshape(-1, img.shape[-1])[:, :3].mean(axis=0))
    means = np.array(means)
    mean = means.mean(axis=0)
    se = means.std(axis=0, ddof=1) / math.sqrt(chunks) if chunks > 1 else np.full(3, float("nan"))
    rate = size[0] * size[1] * per_chunk * chunks / seconds
    # Per pixel and channel, the variance of one sample: that of the renders times their spp.
    variance = np.var(np.array(images), axis=0, ddof=1) * per_chunk if chunks > 1 else None
    return rate, mean, se, variance


def read_rgb(path):
    import mitsuba as mi
    import numpy as np

    return np.array(mi.Bitmap(str(path)), dtype=np.float64)[..., :3]


def relative_variance(variance, reference):
    """Per-sample variance over the pixels and channels, each relative to the pixel's value as
    the chart's relative MSE weighs it (over reference^2 + 0.01), averaged."""
    return float((variance / (reference**2 + 0.01)).mean())


def penumbra_renders(args, scene, pargs, spp, extra):
    """CHUNKS renders of the full spp with seeds 1.. CHUNKS: the rate over all of them, the mean
    of their image means and its standard error from their scatter, their average image, and
    per pixel and channel the variance of one sample (that of the renders times their spp)."""
    import numpy as np

    samples, seconds, means, images = 0.0, 0.0, [], []
    for seed in range(1, args.chunks + 1):
        rate, mean, _, out = run_penumbra(args.penumbra, scene, pargs, args.size, spp, seed, extra)
        img = read_rgb(out)
        samples += img.shape[0] * img.shape[1] * spp
        seconds += img.shape[0] * img.shape[1] * spp / rate
        means.append(mean)
        images.append(img)
    means = np.array(means)
    se = means.std(axis=0, ddof=1) / math.sqrt(args.chunks) if args.chunks > 1 else np.full(3, float("nan"))
    variance = np.var(np.array(images), axis=0, ddof=1) * spp if args.chunks > 1 else None
    return samples / seconds, means.mean(axis=0), se, np.mean(images, axis=0), variance


def main():
    args = parse_args()
    setup_llvm(args.libllvm)
    w, h = (int(x) for x in args.size.lower().split("x"))
    variants = jit_variants_that_run([v for v in args.variants.split(",") if v])
    extra = args.penumbra_args.split()
    rows = []
    for name in args.cases.split(","):
        scene, pargs, max_depth, spp, flip = CASES[name]
        spp = max(args.chunks, int(spp * args.spp_scale))
        folder = work_dir(f"mitsuba-{name}-")
        exported = export_scene(args.penumbra, scene, folder)
        rate, mean, se, image, pvariance = penumbra_renders(args, scene, pargs, spp, extra)
        row = {"case": name, "spp": spp, "penumbra": (rate, mean, se), "mitsuba": {}, "efficiency": {}}
        for v in variants:
            try:
                row["mitsuba"][v] = render_mitsuba(v, exported, folder, (w, h), max_depth, flip, spp, args.chunks, args.mitsuba_sampler)
            except Exception as e:  # a variant that cannot run here is reported, not fatal
                row["mitsuba"][v] = str(e).splitlines()[0][:60]
                continue
            mvariance = row["mitsuba"][v][3]
            if mvariance is not None and pvariance is not None:
                # Equal error: a renderer reaches a given noise in time proportional to its
                # variance per sample over its samples per second, so the ratio of
                # samples/s / variance is the speed ratio at equal error. Both variances are
                # taken relative to penumbra's image, so they weigh the pixels alike.
                reference = image
                row["efficiency"][v] = (relative_variance(pvariance, reference), relative_variance(mvariance, reference))
        rows.append(row)
        print(f"{name}: done", file=sys.stderr, flush=True)

    def lum(c):
        return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]

    head = f"| case ({w}x{h}) | spp | penumbra samples/s | " + " | ".join(f"Mitsuba {v} samples/s (penumbra / it)" for v in variants)
    head += " | penumbra mean (lum.) | " + " | ".join(f"{v} mean (lum.)" for v in variants) + " | worst per-channel z |"
    head += " penumbra variance per sample (rel.) | " + " | ".join(f"{v} variance per sample (rel.) | penumbra / {v} at equal error" for v in variants) + " |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for r in rows:
        rate, mean, se = r["penumbra"]
        cells = [r["case"], str(r["spp"]), f"{rate / 1e3:.1f} k"]
        means, zs = [], []
        for v in variants:
            m = r["mitsuba"][v]
            if isinstance(m, str):
                cells.append(f"failed: {m}")
                means.append("-")
                continue
            mrate, mmean, mse, _ = m
            cells.append(f"{mrate / 1e3:.1f} k ({rate / mrate:.2f}x)")
            means.append(f"{lum(mmean):.5f}")
            zs += [abs(mean[c] - mmean[c]) / math.sqrt(se[c] ** 2 + mse[c] ** 2) for c in range(3) if se[c] + mse[c] > 0]
        cells.append(f"{lum(mean):.5f}")
        cells += means
        cells.append(f"{max(zs):.2f}" if zs else "-")
        effs = r["efficiency"]
        cells.append(f"{next(iter(effs.values()))[0]:.3g}" if effs else "-")
        for v in variants:
            m = r["mitsuba"][v]
            if v not in effs or isinstance(m, str):
                cells += ["-", "-"]
                continue
            pv, mv = effs[v]
            cells.append(f"{mv:.3g}")
            cells.append(f"{(rate / pv) / (m[0] / mv):.2f}x" if pv > 0 and mv > 0 else "-")
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory(prefix="penumbra-vs-mitsuba-") as WORK:
        main()
