#!/usr/bin/env bash
# vxr beside VTK on the same scenes, scored against the same CPU reference:
# installs deps (VTK's Python bindings too), builds, runs
# `vxr bench peer --export-scenes`, then tools/peer/vtk_peer.py under Xvfb.
# Extra arguments go to vtk_peer.py (e.g. --mappers fixed gpu).
# Reports: out/peer/peer.json and peer.png (vxr), out/peer/vtk-peer.json and vtk-peer.png (VTK beside vxr).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
./ci/install-deps.sh
./ci/install-deps.sh ci/packages-peer.txt
./ci/build.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
# Steps down from 4 voxels: VTK's coarse distances (2, 4) meet a vxr step of
# no more error than theirs, not only vxr's 2.
./build/release/tools/vxr bench peer --export-scenes --out out/peer \
  --steps 4 3 2.5 2 1.5 1.25 1 0.75 0.5 0.25 --reference-step 0.0625 --repeats 3
# Debian's python3-vtk9 is for the system Python, whatever python3 is first on PATH.
xvfb-run -a -s "-screen 0 1024x768x24" /usr/bin/python3 tools/peer/vtk_peer.py out/peer/peer.json "$@"
