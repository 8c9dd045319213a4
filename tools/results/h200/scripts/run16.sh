#!/usr/bin/env bash
# Third lease: the reference with the octant-ordered stackless walk (516612b) against the stack
# walk (0e406c2), stripped release builds in .gl/bin, alternating, three rounds, 1024x1024.
set -u
for f in .gl/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
exec > >(tee -a "$OUT/log16.txt") 2>&1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
for r in 1 2 3; do
  for c in "cornell32|scenes/cornell.toml|--bounces 32 --spp 64" "direct|scenes/cornell.toml|--direct-only --spp 256" "furnace|scenes/furnace.toml|--spp 16" "terrain|scenes/terrain_mountains.toml|--spp 64"; do
    IFS='|' read -r name scene args <<< "$c"
    for v in old new; do
      echo -n "round $r $name $v: "
      timeout 60 .gl/bin/penumbra_$v reference $scene --size 1024x1024 --seed 1 $args -o /tmp/ref_$v.exr 2>&1 | grep -E "samples/s|rror" | head -1
    done
    cmp -s /tmp/ref_old.exr /tmp/ref_new.exr && echo "  identical" || echo "  DIFFERENT"
  done
done
echo "== validation"
PENUMBRA_VALIDATION=1 timeout 60 .gl/bin/penumbra_new reference scenes/sh_courtyard.toml --size 256x256 --spp 16 -o /tmp/v.exr 2>&1 | tail -2
echo "== done"
