#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 3 on the host: degraded within 100 ms of the unbind, dual after the rebind, the vcan0 gap
# counted without a restart, SIGTERM clean within 1 s.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" faults --json "$L/can.jsonl" --log "$L/can.log" \
  --stop "$L/stop.txt"
