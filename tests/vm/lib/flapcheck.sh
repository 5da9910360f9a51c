#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Host check of the CAN flap scenarios: every vcan0 down/up cycle resumed (flap.txt), and SIGTERM
# was still clean after them (stop.txt). Usage: flapcheck.sh LOGDIR
set -euo pipefail
L=$1
kv() { tr ' ' '\n' <"$1" | sed -n "s/^$2=//p"; }
cycles=$(kv "$L/flap.txt" cycles); resumed=$(kv "$L/flap.txt" resumed)
[ -n "$cycles" ] && [ "$resumed" = "$cycles" ] || { echo "FAIL: resumed $resumed of $cycles cycles"; exit 1; }
echo "ok: the stream resumed after each of $cycles vcan0 down/up cycles ($(cat "$L/flap.txt"))"
[ "$(kv "$L/stop.txt" exit)" = 0 ] || { echo "FAIL: tacse3d exit after SIGTERM: $(cat "$L/stop.txt")"; exit 1; }
ms=$(kv "$L/stop.txt" sigterm_ms)
[ "$ms" -le 1000 ] || { echo "FAIL: SIGTERM took $ms ms (> 1000)"; exit 1; }
echo "ok: SIGTERM clean in $ms ms"
