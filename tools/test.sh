#!/usr/bin/env bash
# Installs what is missing, checks formatting (rustfmt.toml) and lints (clippy, warnings are
# errors), then runs every test on lavapipe with the Khronos validation layer
# (synchronization validation on; the tests fail on any message). The demo test needs an X
# display, so the suite runs under Xvfb.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
# Formatting and lints first: they are part of the suite, so CI keeps them.
cargo fmt --check
cargo clippy --quiet --all-targets -- -D warnings
# Force lavapipe so results do not depend on whatever GPU the machine has.
export PENUMBRA_TEST_DEVICE="${PENUMBRA_TEST_DEVICE:-llvmpipe}"
xvfb-run -a -s "-screen 0 1024x768x24" cargo test "$@"
