#!/usr/bin/env bash
# Installs what is missing, then runs every test on lavapipe with the Khronos validation layer
# (synchronization validation on; the tests fail on any message). The demo test needs an X
# display, so the suite runs under Xvfb.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
# Force lavapipe so results do not depend on whatever GPU the machine has.
export PENUMBRA_TEST_DEVICE="${PENUMBRA_TEST_DEVICE:-llvmpipe}"
xvfb-run -a -s "-screen 0 1024x768x24" cargo test "$@"
