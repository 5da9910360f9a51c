#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 fuzz: build the libFuzzer targets with clang (ASan+UBSan) and run each for a bounded time.
#
#   fuzz/run.sh [total_seconds]     default 60 s in total, split evenly across the targets
#   TACSE3_FUZZ_SECONDS=20 fuzz/run.sh
#   TACSE3_FUZZ_BUILD_DIR=/tmp/fz fuzz/run.sh   (default: build/fuzz)
#
# Each target starts from its committed corpus fuzz/corpus/<target>/ (never modified: new inputs
# go to <build>/corpus/<target>/). A crash, leak, sanitizer report or timeout fails the script;
# the reproducer is left in <build>/artifacts/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
total="${1:-${TACSE3_FUZZ_SECONDS:-60}}"
build="${TACSE3_FUZZ_BUILD_DIR:-$root/build/fuzz}"
targets=(decoder reassembler command candump)

command -v clang++ >/dev/null || { echo "fuzz/run.sh: clang++ not found (apt-get install clang)" >&2; exit 1; }
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$root/fuzz" -B "$build" "${generator[@]}" -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j2

per=$(( total / ${#targets[@]} ))
(( per >= 1 )) || per=1
mkdir -p "$build/artifacts"
passed=0
failed=0
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t"
  echo "fuzz/run.sh: fuzz_$t for ${per}s" >&2
  if "$build/fuzz_$t" "$build/corpus/$t" "$root/fuzz/corpus/$t" \
      -max_total_time="$per" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$build/artifacts/${t}-" > "$build/fuzz_$t.log" 2>&1; then
    passed=$((passed + 1))
    grep -E "stat::number_of_executed_units|cov:" "$build/fuzz_$t.log" | tail -2 >&2 || true
  else
    failed=$((failed + 1))
    tail -40 "$build/fuzz_$t.log" >&2
    echo "fuzz/run.sh: fuzz_$t FAILED (reproducer in $build/artifacts/)" >&2
  fi
done
echo "fuzz: $passed passed, $failed failed"
(( failed == 0 ))
