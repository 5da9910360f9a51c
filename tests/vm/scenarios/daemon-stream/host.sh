#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 1 on the host: decode the CAN log with tacse3-canmon and check the stream against vivid.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" stream --json "$L/can.jsonl" --log "$L/can.log" \
  --rate-ref "$L/vivid-rate.txt" --seconds "$(sed -n 's/.*stream_s=\([0-9]*\).*/\1/p' "$L/run.txt")"
