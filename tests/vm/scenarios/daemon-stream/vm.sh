# SPDX-License-Identifier: Apache-2.0
# Scenario 1, stream: tacse3d (aarch64) on two vivid devices at 320x240 (V4L2 backend), cycles on vcan0.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 90
set -eu
. /tacse3/lib.sh
STREAM_S=${STREAM_S:-6}

vivid_two_sensors
vcan_up vcan0
# What vivid delivers here with both devices streaming (the reference for the cycle rate).
vivid_measure 120 "$TACSE3_OUT/vivid-rate.txt"
need_daemon

check "tacse3d --check accepts the board" tacse3d --board ./board.toml --check
candump_start
t0=$(uptime_ms)
rc=0
tacse3d --board ./board.toml --seconds "$STREAM_S" --verbose 2>"$TACSE3_OUT/daemon.log" || rc=$?
t1=$(uptime_ms)
sleep 0.3
candump_stop
echo "daemon_exit=$rc daemon_wall_ms=$((t1 - t0)) stream_s=$STREAM_S" | tee "$TACSE3_OUT/run.txt"
tail -5 "$TACSE3_OUT/daemon.log"
expect_eq "$rc" 0 "tacse3d exit status after --seconds $STREAM_S"
expect_ge "$(wc -l <"$TACSE3_OUT/can.log")" 100 "CAN frames captured"
