#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The VM suite as the README and CI run it: builds what the guests and host checks need, then run.sh.
# Usage: tests/vm/suite.sh [run.sh options and arguments]     (default: every default scenario)
# Builds (only these targets, in existing or new build folders):
#   host (TACSE3_VM_HOST_BUILD, default build/host):   tacse3-canmon, tacse3-replay, tacse3-sim,
#        tacse3-v4l2-feed, and tacse3d when the tree has it (x86_64 guest: scenarios 5-7)
#   aarch64 (TACSE3_VM_A64_BUILD, default build/aarch64): tacse3d when the tree has it (scenarios 1-4)
# then renders the scenario-6/7 recording with tacse3-sim (build/vm/e2e/, kept while tacse3-sim is
# unchanged), stages the guests' files under build/vm/stage/ and runs tests/vm/run.sh --quiet with
# them. Scenarios whose tacse3d is missing are reported SKIP; TACSE3_VM_REQUIRE_ALL=1 (or
# TACSE3_VM_REQUIRE_DAEMON=1) makes that a failure. TACSE3_JOBS: build parallelism (default 2).
# TACSE3_VM_PARALLEL=1: boot the two VMs at once (default: one after the other).
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$PWD
JOBS=${TACSE3_JOBS:-2}
HOST_BUILD=${TACSE3_VM_HOST_BUILD:-build/host}
A64_BUILD=${TACSE3_VM_A64_BUILD:-build/aarch64}
VMB=${TACSE3_VM_BUILD:-$REPO/build/vm}
STAGE=$VMB/stage
say() { echo "vm-suite: $*"; }

# configure DIR PRESET: configures a build folder for PRESET, or re-runs cmake in an existing one
# (a folder configured before firmware/ had its CMakeLists.txt would not know tacse3d).
configure() {
  if [ -f "$1/CMakeCache.txt" ]; then
    cmake "$1" >"$VMB/configure-$2.log" 2>&1
  else
    cmake --preset "$2" -B "$1" >"$VMB/configure-$2.log" 2>&1
  fi || { tail -20 "$VMB/configure-$2.log"; say "configuring $1 ($2) failed"; exit 1; }
}
# has_target DIR NAME: the configured build folder defines target NAME.
has_target() { [ -n "$(find "$1" -maxdepth 4 -type d -path '*/CMakeFiles/*' -name "$2.dir" | head -1)" ]; }
# build DIR TARGET...: builds the targets, the log goes to build/vm/build-<dir>.log.
build() {
  local dir=$1; shift
  local log
  log="$VMB/build-$(basename "$dir").log"
  cmake --build "$dir" -j "$JOBS" --target "$@" >"$log" 2>&1 ||
    { tail -30 "$log"; say "building $* in $dir failed (log: $log)"; exit 1; }
}

mkdir -p "$VMB"
t0=$(date +%s)
configure "$HOST_BUILD" host
host_targets=(tacse3-canmon tacse3-replay tacse3-sim tacse3-v4l2-feed)
host_daemon=0
if has_target "$HOST_BUILD" tacse3d; then host_targets+=(tacse3d); host_daemon=1; fi
say "building ${host_targets[*]} in $HOST_BUILD"
build "$HOST_BUILD" "${host_targets[@]}"

a64_daemon=0
configure "$A64_BUILD" aarch64
if has_target "$A64_BUILD" tacse3d; then
  say "building tacse3d in $A64_BUILD"
  build "$A64_BUILD" tacse3d
  a64_daemon=1
else
  say "no tacse3d target in the tree yet: the daemon scenarios will report SKIP"
fi

# find_bin DIR NAME: the built executable NAME under DIR (tools/<x>/NAME, firmware/NAME, ...).
find_bin() {
  local f
  f=$(find "$1" -type f -name "$2" -perm -u+x -not -path '*/CMakeFiles/*' | head -1)
  [ -n "$f" ] || { say "$2 not found under $1"; exit 1; }
  echo "$f"
}

# Host tools for the host.sh checks.
rm -rf "$STAGE"; mkdir -p "$STAGE/host-bin" "$STAGE/aarch64/bin" "$STAGE/x86_64/bin" \
  "$STAGE/x86_64/share/tacse3/vm"
for t in tacse3-canmon tacse3-replay; do cp "$(find_bin "$HOST_BUILD" "$t")" "$STAGE/host-bin/"; done

# The scenario-6/7 recording: a 20 mm sphere gripped and rotated 5 deg about z (stick regime, where
# the displacement proxy the VM board uses is the right model), grey frames; re-rendered when
# tacse3-sim changes.
SIM=$(find_bin "$HOST_BUILD" tacse3-sim)
REC=$VMB/e2e/sphere_rz5
if [ ! -f "$REC/truth.csv" ] || [ "$SIM" -nt "$REC/truth.csv" ]; then
  say "rendering $REC with tacse3-sim"
  mkdir -p "$VMB/e2e"
  "$SIM" -q --overwrite --out "$REC" --object sphere --motion rz --magnitude 5 --colour grey
fi
cp "$(find_bin "$HOST_BUILD" tacse3-v4l2-feed)" "$STAGE/x86_64/bin/"
cp -r "$REC" "$STAGE/x86_64/share/tacse3/vm/e2e-rec"
cp tools/replay/data/sim-calibration.toml "$STAGE/x86_64/share/tacse3/vm/" 2>/dev/null || true
if [ "$host_daemon" = 1 ]; then cp "$(find_bin "$HOST_BUILD" tacse3d)" "$STAGE/x86_64/bin/"; fi
if [ "$a64_daemon" = 1 ]; then cp "$(find_bin "$A64_BUILD" tacse3d)" "$STAGE/aarch64/bin/"; fi
say "builds and staging done in $(($(date +%s) - t0)) s"

if [ "${TACSE3_VM_REQUIRE_DAEMON:-0}" = 1 ]; then export TACSE3_VM_REQUIRE_ALL=1; fi
export TACSE3_HOST_BIN=$STAGE/host-bin TACSE3_VM_E2E_REC=$REC
# One VM at a time: the aarch64 guest has 2 vCPUs and the x86_64 guest 1, and CI has 2 cores.
# Booting both at once overcommits the host, and the daemon scenarios time real-time behaviour
# (Status at 10 Hz, LOST within 100 ms, the cycle rate against the driver's). About 40 s slower.
# TACSE3_VM_PARALLEL=1 boots them together.
order=(--sequential)
if [ "${TACSE3_VM_PARALLEL:-0}" = 1 ]; then order=(); fi
exec tests/vm/run.sh --quiet "${order[@]}" --bin "aarch64=$STAGE/aarch64" --bin "x86_64=$STAGE/x86_64" "$@"
