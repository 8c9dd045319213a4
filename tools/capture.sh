#!/usr/bin/env bash
# The main job: install what is missing, then capture the Ca3D-Engine thesis's composed frame headless: the
# BSP level scenes/bsp_rooms.toml as the `seed000` combination (a radiosity light-map, baked on
# the first run into .penumbra-cache, under per-pixel Phong with stencil shadow volumes).
# Arguments replace that choice and go to `penumbra capture` (e.g. a scene file, --size 1280x720;
# `penumbra capture` with no scene renders the built-in default scene).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
if [ "$#" -eq 0 ]; then
    set -- scenes/bsp_rooms.toml --method seed000
fi
cargo run --quiet -- capture -o capture.png --exr capture.exr "$@"
