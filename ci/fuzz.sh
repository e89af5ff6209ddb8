#!/usr/bin/env bash
# Builds the `fuzz` preset (clang-14, libFuzzer, ASan + UBSan) and runs each
# harness of tests/fuzz for SECONDS (default 60), one at a time, then prints
# executions, exec/s, crashes, OOMs and timeouts per harness.
#   ci/fuzz.sh 600            all harnesses, 10 minutes each
#   ci/fuzz.sh 60 tiff codec  only these
#   FUZZ_RUNS=1000000 ci/fuzz.sh 3600 codec   stop after 10^6 executions (or the time)
# Findings land in build/fuzz/findings/<name>/ (crash-*, oom-*, timeout-*);
# new coverage inputs in build/fuzz/grown/<name>/. The committed corpus
# (tests/fuzz/corpus/<name>) is read, never written. Exit 1 on any finding.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
# Harnesses write their input to a scratch file: keep that in memory when we can.
if [[ -z "${TMPDIR:-}" && -d /dev/shm ]]; then export TMPDIR=/dev/shm; fi
# Leaks inside third-party libraries only (each listed with its reason).
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
seconds="${1:-60}"
shift || true
all=(tiff ims slices raw_sidecar container codec settings obj)
if [[ $# -eq 0 ]]; then names=("${all[@]}"); else names=("$@"); fi

declare -A max_len=([tiff]=4096 [ims]=32768 [slices]=2048 [raw_sidecar]=512 [container]=8192 [codec]=1024 [settings]=2048 [obj]=4096)

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
cmake --preset fuzz "${launcher[@]}" >/dev/null
cmake --build --preset fuzz -j"${FUZZ_BUILD_JOBS:-2}"

failed=0
printf '%-12s %12s %8s %8s %8s %6s %9s\n' harness execs exec/s corpus crashes ooms timeouts
for name in "${names[@]}"; do
  bin="build/fuzz/tests/fuzz/fuzz_${name}"
  grown="build/fuzz/grown/${name}"
  findings="build/fuzz/findings/${name}"
  mkdir -p "$grown" "$findings"
  log="build/fuzz/findings/${name}.log"
  # Count only what this run finds (earlier findings stay for inspection).
  stamp="$findings/.run-start"
  touch "$stamp"
  # One process, one job (the CI machine is shared); the first finding stops the run.
  set +e
  "$bin" "$grown" "tests/fuzz/corpus/${name}" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
    -max_len="${max_len[$name]}" -runs="${FUZZ_RUNS:--1}" -print_final_stats=1 -artifact_prefix="$findings/" >"$log" 2>&1
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  corpus=$(find "$grown" "tests/fuzz/corpus/${name}" -type f | wc -l)
  crashes=$(find "$findings" -newer "$stamp" \( -name 'crash-*' -o -name 'leak-*' \) | wc -l)
  ooms=$(find "$findings" -newer "$stamp" -name 'oom-*' | wc -l)
  timeouts=$(find "$findings" -newer "$stamp" \( -name 'timeout-*' -o -name 'slow-unit-*' \) | wc -l)
  printf '%-12s %12s %8s %8s %8s %6s %9s\n' "$name" "${execs:-?}" "${rate:-?}" "$corpus" "$crashes" "$ooms" "$timeouts"
  if (( crashes + ooms + timeouts > 0 )) || [[ -z "$execs" ]]; then
    failed=1
    echo "  findings in $findings (log: $log)"
  fi
done
exit "$failed"
