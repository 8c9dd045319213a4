#!/usr/bin/env bash
# Sixth run: the reference with path regeneration (a pixel whose sample ends starts the next in
# the same loop iteration; bit-identical output) against the loop per sample, both compiled at
# run time from .gl/glsl_{old,new} (PENUMBRA_REF_GLSL), alternating, 1024x1024.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
exec > >(tee -a "$OUT/log11.txt") 2>&1
bin=.gl/bin/penumbra
for r in 1 2 3; do
  for c in "cornell32|scenes/cornell.toml|--bounces 32 --spp 64" "direct|scenes/cornell.toml|--direct-only --spp 256" "furnace|scenes/furnace.toml|--spp 16" "terrain|scenes/terrain_mountains.toml|--spp 64"; do
    IFS='|' read -r name scene args <<< "$c"
    for v in old new; do
      echo -n "round $r $name $v: "
      PENUMBRA_REF_GLSL=.gl/glsl_$v timeout 60 $bin reference $scene --size 1024x1024 --seed 1 $args -o /tmp/ref_$v.exr 2>&1 | grep -E "samples/s|rror" | head -1
    done
    cmp -s /tmp/ref_old.exr /tmp/ref_new.exr && echo "  identical" || echo "  DIFFERENT"
  done
done
echo "== done"
