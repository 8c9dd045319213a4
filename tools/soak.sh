#!/usr/bin/env bash
# Soak: every shipped scene with every method it enables and every combination it declares,
# rendered for many frames on lavapipe under validation, with the process's resident anonymous
# memory (RssAnon) and device memory (live allocations) recorded every 100 frames. Writes
# CSV (scene,method,frame,rss_anon_mib,device_mib) to soak.csv, or to the file given.
#   PENUMBRA_SOAK_FRAMES  frames per scene and method (default 10000; a height-field frame
#                         takes about a second on lavapipe, so that is hours)
#   PENUMBRA_SOAK_SIZE    image size (default 64x36)
#   PENUMBRA_SOAK_SCENES  comma-separated scene-name prefixes to run (default: all)
#   PENUMBRA_SOAK_METHODS comma-separated configuration names to run (default: all)
#   PENUMBRA_SOAK_SCENE_DIR read the scenes from this folder instead of scenes/ (e.g. a
#                         shipped scene with a smaller height-field resolution)
# PENUMBRA_UNIFORM_BLOCKS_AS_STORAGE=0 turns off the lavapipe workaround (to see the leak).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-soak.csv}"
bash tools/setup.sh
export PENUMBRA_TEST_DEVICE="${PENUMBRA_TEST_DEVICE:-llvmpipe}"
cargo test --quiet --test memory -- --ignored --nocapture --test-threads 1 soak_every_shipped_scene_and_method | grep --line-buffered -E '^(scene,|[a-z_0-9]+\.toml,)' | tee "$out"
