#!/usr/bin/env bash
# Measures peak memory (RSS) and speed of `vxr import --memory 256M` on a
# >= 2 GiB u16 TIFF stack (issue 3 acceptance: peak under 600 MB).
#
#   tools/measure-import-memory.sh [VXR] [--dims X,Y,Z] [--memory 256M] [--slices] [--compression lzw|deflate]
#                                  [--keep] [--dir SCRATCH]
#
# Generates the synthetic microscopy volume (cells + shot noise, see
# engine/volume/synthetic_microscopy.h) as one multi-page TIFF (or, with
# --slices, a folder of single-page TIFFs) with `vxr bench synth-tiff`, imports
# it under /usr/bin/time -v, runs `vxr verify` on the result, prints peak RSS
# and MB/s, and deletes everything it wrote (unless --keep).
# Needs /usr/bin/time (Debian package `time`) and ~2x the volume size free.
set -euo pipefail

vxr=build/release/tools/vxr
dims=1024,1024,1100
memory=256M
slices=
compression=none
keep=
scratch=${TMPDIR:-/tmp}
while [ $# -gt 0 ]; do
  case $1 in
    --dims) dims=$2; shift 2 ;;
    --memory) memory=$2; shift 2 ;;
    --slices) slices=--slices; shift ;;
    --compression) compression=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --dir) scratch=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) vxr=$1; shift ;;
  esac
done
[ -x "$vxr" ] || { echo "measure-import-memory: $vxr is not an executable vxr; build first or pass its path" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "measure-import-memory: /usr/bin/time is missing; apt-get install time" >&2; exit 2; }

work=$(mktemp -d "$scratch/vxr-import-mem.XXXXXX")
[ -n "$keep" ] || trap 'rm -rf "$work"' EXIT
if [ -n "$slices" ]; then input=$work/slices; else input=$work/big.tif; fi

echo "== generating $dims u16 TIFF ${slices:+(single-page slices) }(compression $compression) in $work"
"$vxr" bench synth-tiff --dims "$dims" -o "$input" $slices --compression "$compression"
input_bytes=$(du -sb "$input" | cut -f1)

echo "== vxr import --memory $memory"
VXR_PROGRESS=1 /usr/bin/time -v "$vxr" import "$input" -o "$work/big.vxc" --memory "$memory" 2> "$work/time.txt" \
  || { cat "$work/time.txt" >&2; exit 1; }
# The progress bar (percent, MB/s, ETA) redraws with \r: show a mid-run line and the last one.
tr '\r' '\n' < "$work/time.txt" | grep -a 'ETA' | awk '{ l[NR] = $0 } END { if (NR) { print "progress: " l[int((NR + 1) / 2)]; print "progress: " l[NR] } }' || true
tr '\r' '\n' < "$work/time.txt" | grep -a -v '^\s' | grep -a -v 'ETA' | grep -a -v 'Command being timed' || true
peak_kb=$(sed -n 's/^\s*Maximum resident set size (kbytes): //p' "$work/time.txt")
wall=$(sed -n 's/^\s*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$work/time.txt")
secs=$(echo "$wall" | awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; print s }')

echo "== vxr verify"
"$vxr" verify "$work/big.vxc" | tail -n 1
"$vxr" info "$work/big.vxc" | sed -n '1,12p'

IFS=, read -r dx dy dz <<< "$dims"
awk -v kb="$peak_kb" -v b="$input_bytes" -v s="$secs" -v m="$memory" -v d="$dims" -v c="$compression" \
    -v v="$((dx * dy * dz * 2))" 'BEGIN {
  printf "RESULT: input %s u16 (%.2f GiB of voxels, %.2f GiB on disk, compression %s), --memory %s: peak RSS %.0f MB, wall %.1f s, %.1f MB/s of voxels\n",
         d, v / 2^30, b / 2^30, c, m, kb * 1024 / 1e6, s, v / s / 1e6 }'
