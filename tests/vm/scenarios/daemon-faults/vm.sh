# SPDX-License-Identifier: Apache-2.0
# Scenario 3, faults: unplug/replug one vivid device, sysfs unbind/rebind of vivid, vcan0 down/up, SIGTERM, all under a running tacse3d.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 120
set -eu
. /tacse3/lib.sh

vivid_two_sensors
vcan_up vcan0
need_daemon

daemon_streaming ./board.toml
sleep 2

# 1. The right sensor disappears mid-stream (vivid's per-instance disconnect), comes back.
vivid_unplug 1
sleep 3
kill -0 "$DAEMON_PID" || fail "tacse3d exited after the unplug"
vivid_replug 1
sleep 3
# 1b. Both sensors through sysfs: unbind the vivid platform device, bind it again 2 s later.
vivid_unbind_all
sleep 2
kill -0 "$DAEMON_PID" || fail "tacse3d exited after the sysfs unbind"
vivid_rebind_all
sleep 4

# 2. The CAN interface goes away for 1 s; tacse3d must keep running and resume by itself.
can_marker 03
check "vcan0 down" ip link set vcan0 down
sleep 1
check "vcan0 up" ip link set vcan0 up
can_marker 04
sleep 2
kill -0 "$DAEMON_PID" || fail "tacse3d exited after vcan0 down/up"

# 3. SIGTERM: a clean stop within 1 s.
daemon_stop_timed
sleep 0.2
candump_stop
# The exit status and the 1 s bound are judged on the host (cancheck faults), with the rest.
