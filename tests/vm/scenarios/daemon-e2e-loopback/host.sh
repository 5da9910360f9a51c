#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 7 on the host: the final pose decoded from the CAN log against the simulator's truth, within
# the replay tool's error on the same recording (same calibration, method and proxy) + 3 degrees.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
REC=${TACSE3_VM_E2E_REC:?tests/vm/suite.sh sets TACSE3_VM_E2E_REC (the recording played in the VM)}
CAL=$TACSE3_REPO/tools/replay/data/sim-calibration.toml
cal=(); [ -f "$CAL" ] && cal=(--calibration "$CAL")
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
"$TACSE3_HOST_BIN/tacse3-replay" "$REC" "${cal[@]}" --method joint --mode displacement \
  --out "$L/replay.csv" >"$L/replay-summary.txt" 2>&1
cat "$L/replay-summary.txt"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" e2e --json "$L/can.jsonl" --truth "$REC/truth.csv" \
  --replay-summary "$L/replay-summary.txt" --tolerance-deg 3
