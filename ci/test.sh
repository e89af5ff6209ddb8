#!/usr/bin/env bash
# Installs dependencies, builds vxr, runs every test (Vulkan validation on).
# ../shared/testdata beside the checkout holds the third-party test files.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
if [[ ! -d ../shared/testdata ]]; then
  echo "test.sh: ../shared/testdata is missing (tests read real third-party files from it)" >&2
  exit 1
fi
./ci/install-deps.sh
./ci/build.sh
# Every Debian package the build used must be in ci/packages.txt, or a fresh machine fails.
if [[ -x ../shared/tools/check-packages.sh ]]; then
  ../shared/tools/check-packages.sh build/release ci/packages.txt
fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
cd build/release
ctest --output-on-failure -j"$(nproc)" --timeout 600
