#!/usr/bin/env bash
# The main job: install what is missing, then capture the built-in default scene headless.
# Extra arguments go to `penumbra capture` (e.g. a scene file, --size 1280x720).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cargo run --quiet -- capture -o capture.png --exr capture.exr "$@"
