#!/usr/bin/env bash
# Captures every shipped scene with each of its methods and combinations at 64x48 (the linear EXR,
# bakes built afresh in a private cache) and prints one line per image: scene, configuration and
# the SHA-256 of the EXR. Run it before and after a change that must not change any image (a
# refactoring) and compare the two outputs with `diff`.
#
#   bash tools/image_hashes.sh [PENUMBRA_BINARY] > hashes.txt
#
# The binary defaults to target/debug/penumbra (build it first); compare runs of the same profile.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/debug/penumbra}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export PENUMBRA_CACHE="$work/cache"
export PENUMBRA_DEVICE_NAME="${PENUMBRA_DEVICE_NAME:-llvmpipe}"
for scene in scenes/*.toml; do
  # Method names (plain strings or tables with `name`) and combination names, in file order.
  configs=$(python3 - "$scene" <<'EOF'
import sys, tomllib
with open(sys.argv[1], "rb") as f:
    s = tomllib.load(f)
names = [m if isinstance(m, str) else m["name"] for m in s.get("methods", [])]
names += [c["name"] for c in s.get("combinations", [])]
seen = []
for n in names:
    if n not in seen:
        seen.append(n)
print("\n".join(seen))
EOF
)
  for config in $configs; do
    out="$work/img.exr"
    rm -f "$out"
    if "$bin" capture "$scene" --method "$config" --size 64x48 --exr "$out" --device "$PENUMBRA_DEVICE_NAME" \
      >"$work/log" 2>&1; then
      echo "$scene $config $(sha256sum "$out" | cut -d' ' -f1)"
    else
      echo "$scene $config FAILED: $(tail -n1 "$work/log")"
    fi
  done
done
