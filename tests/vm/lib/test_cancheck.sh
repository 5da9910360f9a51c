#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# ctest vm_cancheck: the VM suite's host checker on real encoder output, without a VM. The replay
# tool's --can-log is what the firmware sends for a simulated grasp: its pose must pass the e2e
# check; one corrupted byte must fail the stream check with a CRC error and an incomplete cycle.
# Usage: test_cancheck.sh TACSE3_SIM TACSE3_REPLAY TACSE3_CANMON
set -euo pipefail
SIM=$1 REPLAY=$2 CANMON=$3
HERE=$(cd "$(dirname "$0")" && pwd)
CHECK="python3 $HERE/cancheck.py"
T=$(mktemp -d "${TMPDIR:-/tmp}/tacse3_vm_cancheck.XXXXXX")
trap 'rm -rf "$T"' EXIT

$CHECK selftest
"$SIM" -q --overwrite --out "$T/rec" --object sphere --motion rz --magnitude 5 --colour grey
CAL=$HERE/../../../tools/replay/data/sim-calibration.toml
cal=(); [ -f "$CAL" ] && cal=(--calibration "$CAL")
"$REPLAY" "$T/rec" "${cal[@]}" --method joint --mode displacement --out "$T/replay.csv" --can-log "$T/can.log" \
  >"$T/summary.txt" 2>&1
"$CANMON" --log "$T/can.log" --format json >"$T/can.jsonl" 2>/dev/null
$CHECK e2e --json "$T/can.jsonl" --truth "$T/rec/truth.csv" --replay-summary "$T/summary.txt" \
  --tolerance-deg 0.5
n=$(grep -c . "$T/can.log")
echo "sim frames=2 delivered_fps=120.0 nominal_fps=120.0" >"$T/rate.txt"
# Corrupt the payload of one TwistAngular frame in the middle of the log.
awk -v n=$((n / 2)) 'NR >= n && !done && $3 ~ /^022#/ { sub(/#../, "#A5"); done = 1 } { print }' \
  "$T/can.log" >"$T/bad.log"
cmp -s "$T/can.log" "$T/bad.log" && { echo "FAIL: the corruption did not change the log"; exit 1; }
"$CANMON" --log "$T/bad.log" --format json >"$T/bad.jsonl" 2>/dev/null
if $CHECK stream --json "$T/bad.jsonl" --log "$T/bad.log" --rate-ref "$T/rate.txt" --seconds 1 >"$T/out.txt"; then
  cat "$T/out.txt"; echo "FAIL: the stream check passed a log with a corrupted frame"; exit 1
fi
grep -q '^FAIL: node 1 frames with a bad CRC: 1 (want 0)' "$T/out.txt" || { cat "$T/out.txt"; exit 1; }
grep -q '^FAIL: cycle counter gaps 0 + incomplete cycles 1 <= CAN TX drops reported in StatusCounters 0' "$T/out.txt" ||
  { cat "$T/out.txt"; exit 1; }
echo "ok: the corrupted log fails the stream check (bad CRC, incomplete cycle)"
