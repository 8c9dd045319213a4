#!/usr/bin/env bash
# The reference's actual error with each sampler: renders SCENE at 64x64 with
# `--sampler independent` and `--sampler sobol` for seeds 1..SEEDS and prints, per sampler, the
# relative MSE of one render (the scatter of the seeds' images per pixel and channel, over
# mean^2 + 0.01 as the chart weighs errors), what the Sobol renders' standard-error images
# claim, the image means and the rates. The scatter over seeds is the error whatever the
# sampler; a stratified sampler's standard-error image is not.
#   tools/sampler_error.sh SCENE SPP [SEEDS] [-- extra penumbra reference arguments]
# Needs tools/.venv with mitsuba and numpy (for reading EXR), as tools/reference_vs_mitsuba.py.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: tools/sampler_error.sh SCENE SPP [SEEDS] [-- ARGS]" >&2
  exit 2
fi
scene=$1 spp=$2 seeds=8
shift 2
if [ $# -gt 0 ] && [ "$1" != "--" ]; then seeds=$1; shift; fi
[ $# -gt 0 ] && [ "$1" = "--" ] && shift
bin=${PENUMBRA:-target/release/penumbra}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for ((s = 1; s <= seeds; s++)); do
  for sampler in independent sobol; do
    log=$("$bin" reference "$scene" --size 64x64 --seed "$s" --spp "$spp" --sampler "$sampler" "$@" -o "$out/${sampler}_$s.exr" 2>&1) || { echo "$log" >&2; exit 1; }
    grep -o '[0-9]* samples/s' <<< "$log" | cut -d' ' -f1 >> "$out/$sampler.rate"
  done
done
tools/.venv/bin/python - "$out" "$seeds" <<'PY'
import sys, numpy as np, mitsuba as mi
mi.set_variant('scalar_rgb')
out, n = sys.argv[1], int(sys.argv[2])
def load(k, suffix=''):
    return np.stack([np.array(mi.Bitmap(f'{out}/{k}_{s}{suffix}.exr'))[..., :3] for s in range(1, n + 1)])
I, Q, EQ = load('independent'), load('sobol'), load('sobol', '.stderr')
w = 1.0 / (np.concatenate([I, Q]).mean(0) ** 2 + 0.01)
vi, vq = np.mean(I.var(0, ddof=1) * w), np.mean(Q.var(0, ddof=1) * w)
claimed = np.mean((EQ ** 2).mean(0) * w)
rate = lambda k: float(np.median(np.loadtxt(f'{out}/{k}.rate', ndmin=1)))
print(f'relative MSE of one render: independent {vi:.3e}, sobol {vq:.3e} (ratio {vi / vq:.2f}); '
      f'sobol standard-error image {claimed:.3e} ({claimed / vq:.2f} x its error); '
      f'means {I.mean():.5f} / {Q.mean():.5f}; samples/s {rate("independent"):.0f} / {rate("sobol"):.0f}')
PY
