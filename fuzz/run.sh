#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 fuzz: build the libFuzzer targets with clang (ASan+UBSan) and run each one.
#
#   fuzz/run.sh [total_seconds]     bounded (CI): default 72 s in total, split evenly across targets
#   TACSE3_FUZZ_SECONDS=20 fuzz/run.sh
#   fuzz/run.sh --long [runs]       each target until it has executed `runs` inputs (default 10 M);
#                                   takes hours (docs/testing.md gives the rates)
#   fuzz/run.sh --only board,png ...  (either mode) a subset of the targets
#   TACSE3_FUZZ_BUILD_DIR=/tmp/fz fuzz/run.sh   (default: build/fuzz)
#
# Each target starts from its committed corpus fuzz/corpus/<target>/ (never modified: new inputs
# go to <build>/corpus/<target>/). A crash, leak, sanitizer report or timeout fails the script;
# the reproducer is left in <build>/artifacts/. The recording and PNG targets write their input to
# scratch files under $TMPDIR (/dev/shm when it is writable: a RAM file system is faster).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${TACSE3_FUZZ_BUILD_DIR:-$root/build/fuzz}"
targets=(decoder reassembler command candump board calibration recording png mjpeg)

long_runs=""
total="${TACSE3_FUZZ_SECONDS:-72}"
while [ $# -gt 0 ]; do
  case "$1" in
    --long) long_runs=10000000
            if [[ "${2:-}" =~ ^[0-9]+$ ]]; then long_runs="$2"; shift; fi ;;
    --only) IFS=, read -r -a targets <<<"${2:?--only needs a comma-separated list of targets}"; shift ;;
    [0-9]*) total="$1" ;;
    *) echo "usage: fuzz/run.sh [total_seconds | --long [runs]] [--only t1,t2]" >&2; exit 2 ;;
  esac
  shift
done
for t in "${targets[@]}"; do
  [ -f "$root/fuzz/fuzz_$t.cpp" ] || { echo "fuzz/run.sh: no target '$t' (fuzz/fuzz_$t.cpp)" >&2; exit 2; }
done

command -v clang++ >/dev/null || { echo "fuzz/run.sh: clang++ not found (apt-get install clang)" >&2; exit 1; }
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$root/fuzz" -B "$build" "${generator[@]}" -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j2

if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
if [ -n "$long_runs" ]; then
  budget=(-runs="$long_runs")
else
  per=$(( total / ${#targets[@]} ))
  (( per >= 1 )) || per=1
  budget=(-max_total_time="$per")
fi
mkdir -p "$build/artifacts"
passed=0
failed=0
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t"
  echo "fuzz/run.sh: fuzz_$t (${budget[*]})" >&2
  start=$(date +%s)
  # -max_len: the largest committed seed (a board file) with room to grow; longer inputs only
  # slow the TOML and CSV targets down.
  if "$build/fuzz_$t" "$build/corpus/$t" "$root/fuzz/corpus/$t" "${budget[@]}" -max_len=8192 \
      -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$build/artifacts/${t}-" > "$build/fuzz_$t.log" 2>&1; then
    passed=$((passed + 1))
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/fuzz_$t.log")
    cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$build/fuzz_$t.log" | tail -1)
    echo "fuzz/run.sh: fuzz_$t ok: $runs runs in $(( $(date +%s) - start )) s, $cov" >&2
  else
    failed=$((failed + 1))
    tail -40 "$build/fuzz_$t.log" >&2
    echo "fuzz/run.sh: fuzz_$t FAILED (reproducer in $build/artifacts/)" >&2
  fi
done
echo "fuzz: $passed passed, $failed failed"
(( failed == 0 ))
