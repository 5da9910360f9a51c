#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Soak: tacse3d on a replay board, unpaced and looping, for SECONDS, with its resident memory
# (VmRSS) and open file descriptors sampled once a second. After a warm-up (the first quarter of
# the samples) both must stay flat: RSS within 1 MiB of its value after the warm-up, and the
# fewest fds seen in the last quarter no more than the fewest in the second. The floor, not the
# peak: any sample may catch a frame's PNG open, but a leak raises every later sample. With
# PEAK_MIB, the peak resident set (VmHWM) must also stay below it (docs/performance.md, Memory).
#
# Usage: run.sh BUILD_DIR [SECONDS [PEAK_MIB]]   (ctest firmware_soak: 20 s, docs/testing.md)
set -uo pipefail
B="${1:?usage: run.sh BUILD_DIR [SECONDS [PEAK_MIB]]}"
seconds="${2:-20}"
peak_mib="${3:-0}"
T=$(mktemp -d "${TMPDIR:-/tmp}/tacse3-soak.XXXXXX")
trap 'kill "$pid" 2>/dev/null; rm -rf "$T"' EXIT
pid=""

"$B/tools/sim/tacse3-sim" -q --out "$T/rec" --object sphere --motion rz --magnitude 2 --colour grey \
  --approach-s 0.02 --grasp-s 0.1 --settle-s 0.02 --hold-s 0.1 || { echo "FAIL: tacse3-sim" >&2; exit 1; }
sensor() { # sensor SIDE ROTATION
  printf '[sensors.%s]\nbackend = "replay"\ndevice = "%s"\nwidth = 320\nheight = 240\nfps = 120\nrotation = %s\n\n' \
    "$1" "$T/rec" "$2"
}
{
  printf 'version = 1\nname = "soak"\n\n'
  sensor left '[[1, 0, 0], [0, 1, 0], [0, 0, 1]]'
  sensor right '[[1, 0, 0], [0, -1, 0], [0, 0, -1]]'
  printf '[sim]\nrealtime = false\nrepeat = true\n'
} >"$T/board.toml"

"$B/firmware/tacse3d" --board "$T/board.toml" --seconds "$seconds" --can-log /dev/null 2>"$T/err" &
pid=$!
: >"$T/samples"
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS:/ { print $2 }' "/proc/$pid/status" 2>/dev/null)
  hwm=$(awk '/^VmHWM:/ { print $2 }' "/proc/$pid/status" 2>/dev/null)
  fds=$(find "/proc/$pid/fd" -mindepth 1 2>/dev/null | wc -l)
  [ -n "$rss" ] && echo "$rss $fds $hwm" >>"$T/samples"
  sleep 1
done
wait "$pid"
rc=$?
pid=""
summary=$(grep -m1 "stopped after" "$T/err")
if [ "$rc" -ne 0 ] || [ -z "$summary" ]; then
  echo "FAIL: tacse3d exited $rc" >&2; tail -5 "$T/err" >&2; exit 1
fi
n=$(wc -l <"$T/samples")
[ "$n" -ge 4 ] || { echo "FAIL: only $n samples" >&2; exit 1; }
awk -v n="$n" -v summary="$summary" -v peak_mib="$peak_mib" '
  { rss[NR] = $1; fds[NR] = $2; if ($3 > hwm) hwm = $3 }
  END {
    w = int(n / 4) + 1
    base = rss[w]; top = base; early = -1; late = -1
    for (i = w; i <= n; ++i) {
      if (rss[i] > top) top = rss[i]
      if (i < 2 * w && (early < 0 || fds[i] < early)) early = fds[i]
      if (i > n - w && (late < 0 || fds[i] < late)) late = fds[i]
    }
    printf "soak: %s\n", summary
    printf "soak: %d samples; after warm-up RSS %d -> %d kB (max %d), fds at least %d early, %d late; peak RSS %d kB\n", n, base, rss[n], top, early, late, hwm
    bad = 0
    if (peak_mib > 0 && hwm > peak_mib * 1024) { printf "FAIL: peak RSS above %d MiB\n", peak_mib; bad = 1 }
    if (late > early) { print "FAIL: more open descriptors at the end than after the warm-up"; bad = 1 }
    if (top - base > 1024) { print "FAIL: RSS grew by more than 1 MiB after the warm-up"; bad = 1 }
    exit bad
  }' "$T/samples"
