#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 6 on the host: one tare (TARE Ack or PoseReset cycle) right after the press, none before.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" tare --json "$L/can.jsonl" --log "$L/can.log"
