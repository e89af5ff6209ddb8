#!/usr/bin/env bash
# Installs dependencies, builds vxr, renders the bundled sample to out/demo.png.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
./ci/install-deps.sh
./ci/build.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
./build/release/tools/vxr version
./build/release/tools/vxr demo --out out
