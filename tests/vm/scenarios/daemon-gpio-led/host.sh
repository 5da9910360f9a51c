#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 4 on the host: the sampled LED duty cycle matches the blink pattern of the state in Status.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" led --json "$L/can.jsonl" --log "$L/can.log" \
  --samples "$L/led.txt" --sync "$L/led-sync.txt"
