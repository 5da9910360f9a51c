#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 5 on the host: the single-sensor stream from vimc/libcamera, checked like scenario 1.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" stream --json "$L/can.jsonl" --log "$L/can.log" \
  --rate-ref "$L/vimc-rate.txt" --right-health NOT_AVAILABLE \
  --seconds "$(sed -n 's/.*stream_s=\([0-9]*\).*/\1/p' "$L/run.txt")"
