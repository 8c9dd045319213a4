#!/usr/bin/env bash
# Checks that penumbra builds with the minimum Rust version Cargo.toml declares (rust-version).
# With rustup, the toolchain is installed when missing (minimal profile) and `cargo check` runs
# every target with it, in target/msrv so the main build's artifacts stay as they are. Where no
# such toolchain can be had (no rustup, or the install fails), the check falls back to what the
# current toolchain can tell: every dependency's declared rust-version, and clippy's
# incompatible_msrv lint (penumbra's own calls into std), and says so.
set -euo pipefail
cd "$(dirname "$0")/.."
msrv=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml)
[ -n "$msrv" ] || { echo "msrv_check: Cargo.toml declares no rust-version" >&2; exit 1; }
current=$(rustc --version | sed -n 's/^rustc \([0-9]*\.[0-9]*\).*/\1/p')
if [ "$current" = "$msrv" ]; then
  echo "msrv_check: the toolchain here is Rust $msrv, the declared minimum: the build above is the check" >&2
  exit 0
fi
if command -v rustup >/dev/null; then
  if ! rustup run "$msrv" rustc --version >/dev/null 2>&1; then
    echo "msrv_check: installing Rust $msrv (minimal profile)" >&2
    rustup toolchain install "$msrv" --profile minimal >/dev/null 2>&1 || true
  fi
  if rustup run "$msrv" rustc --version >/dev/null 2>&1; then
    CARGO_TARGET_DIR=target/msrv cargo "+$msrv" check --quiet --all-targets
    echo "msrv_check: every target builds with Rust $msrv" >&2
    exit 0
  fi
fi
echo "msrv_check: no Rust $msrv toolchain here; checking declared versions and clippy's incompatible_msrv" >&2
cargo metadata --format-version 1 --locked | python3 -c '
import json, sys
msrv = tuple(int(x) for x in sys.argv[1].split(".")[:2])
newer = [f"{p[\"name\"]} {p[\"version\"]} needs Rust {p[\"rust_version\"]}"
         for p in json.load(sys.stdin)["packages"]
         if p.get("rust_version") and tuple(int(x) for x in p["rust_version"].split(".")[:2]) > msrv]
if newer:
    sys.exit("msrv_check: dependencies newer than the declared rust-version: " + "; ".join(newer))
' "$msrv"
cargo clippy --quiet --all-targets -- -D clippy::incompatible_msrv
