# SPDX-License-Identifier: Apache-2.0
# CAN flap: vcan0 down and up 1000 times under a streaming tacse3d; the stream resumes every time.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 3600
# vm-default: no
set -eu
. /tacse3/lib.sh

vivid_two_sensors
vcan_up vcan0
need_daemon

daemon_start ./board.toml
timeout 30 candump -n 1 vcan0,028:7FF >/dev/null 2>&1 || fail "no Status frame within 30 s of the start"
can_flap 1000
daemon_stop_timed
