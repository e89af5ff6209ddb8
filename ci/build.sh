#!/usr/bin/env bash
# Configures and builds vxr (release) into build/release. Used by demo.sh and test.sh.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)"
