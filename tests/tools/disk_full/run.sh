#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A full disk, end to end: the daemon's --record and --can-log and the tools' outputs on small
# tmpfs mounts that fill up. Each must say so clearly, exit with the right code and leave what it
# wrote before readable: a recording cut short replays up to its last complete frame pair, a CAN
# log ends at a whole line, an output file is whole or absent.
#
# Usage: run.sh BUILD_DIR
# Mounting needs a private mount namespace: the script re-runs itself under `unshare -rm` (an
# unprivileged user namespace) or, as root, `unshare -m`. Where neither is allowed it exits 77,
# which ctest reports as skipped, saying why.
set -uo pipefail
B="${1:?usage: run.sh BUILD_DIR}"
if [ "${TACSE3_DISK_FULL_INSIDE:-}" != 1 ]; then
  export TACSE3_DISK_FULL_INSIDE=1
  for ns in "unshare -rm" "unshare -m"; do
    # shellcheck disable=SC2016  # expanded by the inner shell
    if $ns sh -c 'd=$(mktemp -d); mount -t tmpfs -o size=64k none "$d"; r=$?; umount "$d"; rmdir "$d"; exit $r' \
        2>/dev/null; then
      exec $ns "$0" "$@"
    fi
  done
  echo "SKIP: cannot mount a tmpfs here (no user namespaces and not root); the log channel's" \
       "full-disk unit test (RLIMIT_FSIZE) still runs" >&2
  exit 77
fi

T=$(mktemp -d "${TMPDIR:-/tmp}/tacse3-disk-full.XXXXXX")
trap 'umount "$T"/m* 2>/dev/null; rm -rf "$T"' EXIT
TACSE3D="$B/firmware/tacse3d"
REPLAY="$B/tools/replay/tacse3-replay"
CANMON="$B/tools/canmon/tacse3-canmon"
DBCGEN="$B/tools/dbcgen/tacse3-dbcgen"
SIM="$B/tools/sim/tacse3-sim"
fails=0
check() { # check NAME CONDITION...
  local name="$1"; shift
  if "$@"; then echo "ok   $name"; else echo "FAIL $name"; fails=$((fails + 1)); fi
}
has() { grep -qF -- "$2" "$1"; }
# disk NAME SIZE [FILL_BYTES]: a tmpfs of SIZE at $T/NAME, FILL_BYTES of it taken.
disk() {
  mkdir -p "$T/$1"
  mount -t tmpfs -o "size=$2" none "$T/$1" || { echo "FAIL: mount $1" >&2; exit 1; }
  if [ -n "${3:-}" ]; then head -c "$3" /dev/zero >"$T/$1/fill"; fi
}

# 1. tacse3d --record on 1 MB: the recording stops, streaming goes on, what was written replays.
# A sim frame pair is about 120 KB of PNG, so the disk fills after about 8 pairs: within 3 s even
# under the sanitizers, where the recorder keeps only a few pairs a second.
disk m_rec 1m
"$TACSE3D" --board sim --seconds 3 --record "$T/m_rec/rec" --can-log "$T/can1.log" 2>"$T/e1"
rc=$?
check "daemon --record full: exit 0 (streaming went on)" test "$rc" -eq 0
check "daemon --record full: says so" has "$T/e1" "recording stopped, streaming goes on"
check "daemon --record full: names the cause" has "$T/e1" "No space left on device"
frames=$(($(wc -l <"$T/m_rec/rec/frames.csv") - 1))
check "daemon --record full: some frames recorded ($frames)" test "$frames" -gt 0
pngs() { find "$1" -name '*.png' | wc -l; }
check "daemon --record full: a PNG pair per listed frame" \
  test "$(pngs "$T/m_rec/rec/left")" -eq "$frames" -a "$(pngs "$T/m_rec/rec/right")" -eq "$frames"
"$REPLAY" "$T/m_rec/rec" --out "$T/replay1.csv" -q 2>"$T/e1r"
check "the cut recording replays" test $? -eq 0
check "the replay has a row per recorded frame" test "$(($(wc -l <"$T/replay1.csv") - 1))" -eq "$frames"

# 2. tacse3d --can-log on 16 KB: exit 1 naming the log; the log ends at a whole line.
disk m_can 16k
"$TACSE3D" --board sim --seconds 3 --can-log "$T/m_can/can.log" 2>"$T/e2"
rc=$?
check "daemon --can-log full: exit 1" test "$rc" -eq 1
check "daemon --can-log full: names the log and the cause" \
  has "$T/e2" "CAN log $T/m_can/can.log: write failed: No space left on device"
check "daemon --can-log full: the log ends with a newline" test "$(tail -c 1 "$T/m_can/can.log" | od -An -c | tr -d ' ')" = '\n'
"$CANMON" --log "$T/m_can/can.log" --format csv >"$T/mon2.csv" 2>"$T/e2m"
check "the cut CAN log decodes: exit 0" test $? -eq 0
check "the cut CAN log has no broken line" sh -c "! grep -q 'lines that are not candump' '$T/e2m'"

# 3. tacse3-replay --out on a full disk: exit 1, no partial CSV.
"$SIM" -q --out "$T/rec3" --object sphere --motion rz --magnitude 2 --colour grey \
  --approach-s 0.02 --grasp-s 0.3 --settle-s 0.02 --hold-s 0.3 || { echo "FAIL: tacse3-sim" >&2; exit 1; }
disk m_out 64k 60000
"$REPLAY" "$T/rec3" --out "$T/m_out/out.csv" -q 2>"$T/e3"
rc=$?
check "replay --out full: exit 1" test "$rc" -eq 1
check "replay --out full: names the file" has "$T/e3" "$T/m_out/out.csv: write error"
check "replay --out full: no partial CSV" test ! -e "$T/m_out/out.csv"

# 3b. tacse3-replay --plot on a full disk: exit 1, neither the figure nor the CSV left.
disk m_plot 64k 60000
"$REPLAY" "$T/rec3" --out "$T/plot.csv" --plot "$T/m_plot/fig.png" -q 2>"$T/e3b"
rc=$?
check "replay --plot full: exit 1" test "$rc" -eq 1
check "replay --plot full: names the file" has "$T/e3b" "--plot $T/m_plot/fig.png"
check "replay --plot full: no partial figure" sh -c "! ls -A '$T/m_plot' | grep -v '^fill$'"
check "replay --plot full: no CSV" test ! -e "$T/plot.csv"

# 4. tacse3-canmon to a full stdout: exit 1, says the output is incomplete.
"$CANMON" --log "$T/can1.log" --format csv >"$T/m_out/mon.csv" 2>"$T/e4"
check "canmon stdout full: exit 1" test $? -eq 1
# The cause is named when the final flush is what fails; a write that failed earlier leaves only
# the stream's error flag (tools/cli/include/tacse3/tools/cli.hpp, finish_stdout), and which of
# the two happens depends on how much the log holds.
check "canmon stdout full: says so" grep -q "standard output: write error.*; the output is incomplete" "$T/e4"

# 5. tacse3-dbcgen -o on a full disk: exit 1, no file (written atomically).
rm -f "$T/m_out/mon.csv"
head -c 4000 /dev/zero >"$T/m_out/fill2" 2>/dev/null
"$DBCGEN" -o "$T/m_out/x.dbc" 2>"$T/e5"
check "dbcgen full: exit 1" test $? -eq 1
check "dbcgen full: no partial file" test ! -e "$T/m_out/x.dbc"

echo "disk full: $fails failed"
[ "$fails" -eq 0 ]
