#!/usr/bin/env bash
# Installs what penumbra needs on Debian 12 that is not there yet, then returns.
#  - lavapipe (mesa-vulkan-drivers), the Vulkan loader and headers, the Khronos validation layer
#  - shaderc and glslang as static libraries: shaderc is linked statically from Debian's archives
#    (see .cargo/config.toml) instead of being built from source, which takes ~6 minutes
#  - Xvfb and xauth for the windowed demo test; a TrueType font for the chart's text
#  - python3 for the measurement tools and the check that the docs' tables match their data
#  - Chromium, in which the test suite opens a report (tests/commands/report.rs) headless
# Needs root (or sudo) only when something is missing. The Rust toolchain itself must be present.
set -euo pipefail

packages=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers
          libshaderc-dev glslang-dev xvfb xauth fonts-dejavu-core python3 chromium)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null; then
  echo "setup: cargo not found; install a Rust toolchain (1.95 or newer) first" >&2
  exit 1
fi
# The test script checks formatting and lints; rustup toolchains may lack the components.
for c in rustfmt clippy; do
  if ! cargo "${c/rustfmt/fmt}" --version >/dev/null 2>&1 && command -v rustup >/dev/null; then
    rustup component add "$c" >&2
  fi
done
# egui 0.36 (the demo panel) needs Rust 1.95 (Cargo.toml's rust-version); say so before a long build fails.
rust_minor=$(rustc --version | sed -n 's/^rustc 1\.\([0-9]*\).*/\1/p')
if [ -n "$rust_minor" ] && [ "$rust_minor" -lt 95 ]; then
  echo "setup: $(rustc --version) is too old; penumbra needs Rust 1.95 or newer (rustup update)" >&2
  exit 1
fi
