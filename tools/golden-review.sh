#!/usr/bin/env bash
# Review and bless golden images after a failing test run.
#
#   tools/golden-review.sh [BUILD_DIR]            # compose old | new | diff for every failed golden
#   tools/golden-review.sh [BUILD_DIR] --bless NAME...   # copy the new image over golden_images/NAME.png
#
# A failing golden test writes BUILD_DIR/tests/test_out/<name>.actual.png. This
# script writes <name>.review.png beside it (golden | actual | difference x16)
# and prints max_abs / rmse / psnr for each; look at the pictures, then bless
# only the ones whose change you can explain. Blessing copies the PNG and keeps
# the golden's JSON; edit its "why" (or add "reblessed") to say why it changed.
# VXR_BLESS=1 on a test run rewrites PNG and JSON for every golden it checks.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build/release}"
shift || true
out="$build/tests/test_out"
vxr="$build/tools/vxr"
[[ -x "$vxr" ]] || { echo "golden-review: $vxr not built (cmake --build --preset release)" >&2; exit 2; }

if [[ "${1:-}" == "--bless" ]]; then
  shift
  [[ $# -gt 0 ]] || { echo "golden-review: --bless needs golden names" >&2; exit 2; }
  for name in "$@"; do
    src="$out/$name.actual.png"
    [[ -f "$src" ]] || { echo "golden-review: no $src (run the failing test first)" >&2; exit 1; }
    cp "$src" "$root/golden_images/$name.png"
    echo "blessed golden_images/$name.png (now say why in golden_images/$name.json)"
  done
  exit 0
fi

shopt -s nullglob
found=0
for actual in "$out"/*.actual.png; do
  name="$(basename "$actual" .actual.png)"
  golden="$root/golden_images/$name.png"
  [[ -f "$golden" ]] || { echo "$name: no golden yet (new image at $actual)"; continue; }
  found=1
  printf '%s: ' "$name"
  "$vxr" compare "$golden" "$actual" --side-by-side "$out/$name.review.png" || true
  echo "    review: $out/$name.review.png"
done
[[ $found == 1 ]] || echo "golden-review: no failed goldens under $out"
