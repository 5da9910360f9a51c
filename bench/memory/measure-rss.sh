#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: the daemon's memory on the sim board and on a replay board (docs/performance.md).
#
# Usage: bench/memory/measure-rss.sh [BUILD_DIR] [SECONDS]
#   BUILD_DIR  a build with tacse3d and tacse3-sim (default: build/host)
#   SECONDS    how long each daemon streams (default: 30)
#
# Runs tacse3d for SECONDS on each board, reads /proc/PID/status every second and prints, per
# board: the peak resident set (VmHWM), the resident set (VmRSS) and the data segment (VmData:
# heap and anonymous mappings) 2 s after start and at the last sample before the end (a VmData
# that does not grow after start means no heap growth), and at the end the thread count, the
# resident thread stacks, the anonymous (not file-backed) resident memory and the rest of the
# resident set, mapped files (the program and its libraries), and of those the objects the daemon
# locks in full (the program, libc, libm, libstdc++, libgcc_s, the dynamic loader). The replay board plays a tacse3-sim
# recording (rendered into a temporary directory, removed at exit) on both pads at its own frame
# times, looping; the sim board renders both pads live.
set -euo pipefail
cd "$(dirname "$0")/../.."

usage() {
  echo "usage: bench/memory/measure-rss.sh [BUILD_DIR] [SECONDS]" >&2
  exit 2
}
[ $# -le 2 ] || usage
BUILD=${1:-build/host}
SECONDS_RUN=${2:-30}
[[ "$SECONDS_RUN" =~ ^[0-9]+$ ]] && [ "$SECONDS_RUN" -ge 5 ] ||
  { echo "measure-rss: SECONDS must be a whole number >= 5, got '$SECONDS_RUN'" >&2; exit 2; }
DAEMON="$BUILD/firmware/tacse3d"
SIM="$BUILD/tools/sim/tacse3-sim"
for bin in "$DAEMON" "$SIM"; do
  [ -x "$bin" ] || { echo "measure-rss: $bin not found; build it (ninja -C $BUILD tacse3d tacse3-sim)" >&2; exit 1; }
done

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

field() {  # field PID NAME -> value from /proc/PID/status (KiB for the Vm* fields)
  awk -v k="$2:" '$1 == k { print $2 }' "/proc/$1/status" 2>/dev/null || true
}

# stacks PID -> KiB resident in anonymous mappings of exactly the default thread stack size
# (ulimit -s): the stacks of threads created without an explicit size (the daemon sizes its own,
# bench/memory/thread-stacks.py), which mlockall makes resident in full.
STACK_KIB=$(ulimit -s)
stacks() {
  awk -v want="$STACK_KIB" '
    /^[0-9a-f]+-[0-9a-f]+ / { anon = (NF == 5) }
    $1 == "Size:" { size = $2 }
    $1 == "Rss:" && anon && size == want { sum += $2 }
    END { print sum + 0 }' "/proc/$1/smaps" 2>/dev/null || true
}

# realtime PID -> KiB resident in the mappings of the objects lock_memory() locks in full.
realtime() {
  awk '/^[0-9a-f]+-[0-9a-f]+ / { n = split($NF, p, "/"); f = p[n]
      rt = (NF >= 6) && (f == "tacse3d" || f ~ /^(libc|libm)\.so/ || f ~ /^libstdc\+\+\.so/ ||
                         f ~ /^libgcc_s\.so/ || f ~ /^ld-linux/) }
    $1 == "Rss:" && rt { sum += $2 }
    END { print sum + 0 }' "/proc/$1/smaps" 2>/dev/null || true
}

# measure NAME BOARD: runs the daemon, prints one table row.
measure() {
  local name=$1 board=$2
  "$DAEMON" --board "$board" --seconds "$SECONDS_RUN" --can-log /dev/null --quiet \
    2>"$TMP/$name.err" &
  local pid=$! t=0 rss_start="" data_start="" rss_end="" data_end="" hwm="" thr="" rt="" stk="" anon=""
  while kill -0 "$pid" 2>/dev/null; do
    sleep 1
    t=$((t + 1))
    local rss data peak
    rss=$(field "$pid" VmRSS) data=$(field "$pid" VmData) peak=$(field "$pid" VmHWM)
    [ -n "$rss" ] || break
    if [ "$t" -eq 2 ]; then rss_start=$rss data_start=$data; fi
    rss_end=$rss data_end=$data hwm=$peak
    thr=$(field "$pid" Threads) stk=$(stacks "$pid") rt=$(realtime "$pid")
    anon=$(awk '$1 == "Anonymous:" { print $2 }' "/proc/$pid/smaps_rollup" 2>/dev/null || true)
  done
  if ! wait "$pid"; then
    echo "measure-rss: tacse3d on $name failed:" >&2
    cat "$TMP/$name.err" >&2
    exit 1
  fi
  [ -n "$rss_start" ] || { echo "measure-rss: $name ended before 2 s" >&2; exit 1; }
  printf "$ROW" "$name" "$hwm" "$rss_start" "$rss_end" "$data_start" "$data_end" "$thr" "$stk" "$anon" "$((rss_end - anon))" "$rt"
}

# The replay board: the sim board's file with both pads replaying a recording, paced, looping.
"$SIM" --out "$TMP/rec" --motion rz --magnitude 30 >/dev/null 2>"$TMP/sim.err" ||
  { echo "measure-rss: tacse3-sim failed:" >&2; cat "$TMP/sim.err" >&2; exit 1; }
sed -e "s|^backend = \"sim\"|backend = \"replay\"\ndevice = \"$TMP/rec\"|" \
    -e 's|^repeat = .*|repeat = true|' -e 's|^realtime = .*|realtime = true|' \
    boards/sim/board.toml >"$TMP/replay.toml"

echo "tacse3d, $SECONDS_RUN s per board; KiB from /proc/PID/status (start = 2 s after launch)"
ROW='%-7s %8s %12s %10s %13s %11s %8s %7s %10s %6s %15s\n'
printf "$ROW" board VmHWM "VmRSS start" "VmRSS end" "VmData start" "VmData end" threads stacks anonymous files "locked in full"
measure sim sim
measure replay "$TMP/replay.toml"
