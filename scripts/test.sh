#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: the test command. Builds and runs the host tests, the ASan+UBSan build and the aarch64
# build under qemu-user (the host presets include the Python package's tests) and the armhf SIMD
# equivalence test under qemu-arm, then builds and
# checks the arm64/armhf .deb packages, the controller SDK .debs (amd64/arm64/armhf, with programs
# built against them) and the Python wheel and .deb, runs the bounded fuzzers of
# every input parser (fuzz/run.sh) and the real-driver VM suite (tests/vm: SocketCAN, V4L2,
# libcamera, GPIO in
# qemu-system guests). Exits non-zero on any failure.
# Skips: TACSE3_SKIP_PACKAGE=1, TACSE3_SKIP_FUZZ=1, TACSE3_SKIP_VM=1, TACSE3_SKIP_ARMHF_SIMD=1.
# Usage: scripts/test.sh [preset ...]      (default: host host-sanitize aarch64)
set -euo pipefail
cd "$(dirname "$0")/.."

JOBS="${TACSE3_JOBS:-$(nproc)}"
# With ccache (scripts/setup.sh installs it), builds that compile the same sources with the same
# flags share objects: the arm64 package build (scripts/package.sh) is then mostly cache hits on
# the aarch64 build. Relative to the source tree, so build directories of equal depth match.
# TACSE3_NO_CCACHE=1 turns it off; a launcher the caller set is kept.
if [ "${TACSE3_NO_CCACHE:-0}" != 1 ] && command -v ccache >/dev/null; then
  export CMAKE_C_COMPILER_LAUNCHER="${CMAKE_C_COMPILER_LAUNCHER:-ccache}"
  export CMAKE_CXX_COMPILER_LAUNCHER="${CMAKE_CXX_COMPILER_LAUNCHER:-ccache}"
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
fi
presets=("$@")
if [ ${#presets[@]} -eq 0 ]; then presets=(host host-sanitize aarch64); fi

declare -a summary=()
# Each stage's wall time goes into the summary, so a slow CI run shows where its time went.
stage_start=$SECONDS
done_stage() {
  summary+=("$1: ok ($((SECONDS - stage_start)) s)")
  stage_start=$SECONDS
}
for preset in "${presets[@]}"; do
  echo "=== [$preset] configure + build ==="
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset" -j "$JOBS"
  echo "=== [$preset] ctest ==="
  ctest --preset "$preset" -j "$JOBS"
  done_stage "$preset"
done

# The armhf build's SIMD kernels (NEON on ARMv7) against their scalar path under qemu-arm, when
# the full armhf preset did not run: one test program, so the suite stays short.
if [[ " ${presets[*]} " != *" armhf "* ]] && [ "${TACSE3_SKIP_ARMHF_SIMD:-0}" != "1" ]; then
  echo "=== [armhf] SIMD equivalence (dsp_test_simd) ==="
  cmake --preset armhf >/dev/null
  cmake --build --preset armhf -j "$JOBS" --target dsp_test_simd
  ctest --preset armhf -j "$JOBS" -R '^Simd'
  done_stage "armhf SIMD"
fi

# The arm64 and armhf .deb packages, built and checked against tests/packaging/contents.txt, the
# SDK packages (scripts/package-sdk.sh, tests/packaging/contents-sdk.txt and test_sdk.sh), and
# the Python package's wheel and python3-tacse3 .deb (build/python-package).
if [ "${TACSE3_SKIP_PACKAGE:-0}" != "1" ]; then
  echo "=== .deb packages (arm64, armhf; SDK also amd64) ==="
  scripts/package.sh
  echo "=== Python package (wheel, python3-tacse3 .deb) ==="
  scripts/package-python.sh
  done_stage package
fi

if [ -x fuzz/run.sh ] && [ "${TACSE3_SKIP_FUZZ:-0}" != "1" ]; then
  echo "=== fuzzers (bounded) ==="
  fuzz/run.sh
  done_stage fuzz
fi

# Needs the host and aarch64 builds (the suite builds its few targets there if a preset was skipped).
if [ "${TACSE3_SKIP_VM:-0}" != "1" ]; then
  echo "=== real-driver VM suite (tests/vm, qemu TCG) ==="
  TACSE3_VM_REQUIRE_DAEMON=1 tests/vm/suite.sh
  done_stage vm
fi

echo "=== summary ==="
printf '%s\n' "${summary[@]}"
