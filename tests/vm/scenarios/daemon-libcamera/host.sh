#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 5 on the host: the single-sensor stream from vimc/libcamera, checked like scenario 1.
# vimc has no frame clock: it renders as fast as the TCG guest lets it, and the reference rate is a
# 30-frame cam run in another mode (318 wide) just before, so the cycle rate may exceed it: seen
# 49.3 Hz against cam's 46.9 fps in a CI run. Hence the ceiling of 1.25 x (vivid's is 1.02 x).
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" stream --json "$L/can.jsonl" --log "$L/can.log" \
  --rate-ref "$L/vimc-rate.txt" --right-health NOT_AVAILABLE --rate-ceiling 1.25 \
  --seconds "$(sed -n 's/.*stream_s=\([0-9]*\).*/\1/p' "$L/run.txt")"
