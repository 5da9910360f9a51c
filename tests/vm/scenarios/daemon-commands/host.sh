#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Scenario 2 on the host: every command's Ack (or its absence) and the RejectedCommands counter.
set -euo pipefail
L=$TACSE3_VM_LOGDIR
"$TACSE3_HOST_BIN/tacse3-canmon" --log "$L/can.log" --format json >"$L/can.jsonl"
python3 "$TACSE3_REPO/tests/vm/lib/cancheck.py" commands --json "$L/can.jsonl" --log "$L/can.log" \
  --expect 1:TARE:ACK 2:RESET_POSE:ACK 3:SET_FINGER_SEPARATION:ACK 4:QUERY:ACK \
           5:10:UNKNOWN_COMMAND 6:TARE:BAD_CRC 7:TARE:BAD_LENGTH 8:TARE:WRONG_NODE \
           9:SET_FINGER_SEPARATION:OUT_OF_RANGE 10:TARE:RESERVED_NOT_ZERO \
  --ignored 11 --rejected 6 --query-separation 4000
