# SPDX-License-Identifier: Apache-2.0
# Scenario 7, end to end: a simulated grasp-and-rotate played into two v4l2loopback devices, captured by
# tacse3d's V4L2 backend, streamed on vcan0; the host compares the pose with the simulator's truth.
# shellcheck shell=sh
# vm-arch: x86_64
# vm-timeout: 240
set -eu
. /tacse3/lib.sh
CAL=$TACSE3_PREFIX/share/tacse3/vm/sim-calibration.toml
SLOWDOWN=${SLOWDOWN:-4}        # play at 120/4 = 30 fps: what the emulated x86_64 CPU keeps up with

vcan_up vcan0
loopback_pads "$SLOWDOWN"
need_daemon

cal=""
[ -f "$CAL" ] && cal="--calibration $CAL"
# shellcheck disable=SC2086
daemon_streaming ./board.toml $cal
sleep 2                        # streaming on the held first frame
log "go"
touch /tmp/go
wait "$FEEDER_PID" || fail "feeder failed: $(tail -2 "$TACSE3_OUT/feed.log")"
cat "$TACSE3_OUT/feed.log"
sleep 1
kill -0 "$DAEMON_PID" || fail "tacse3d exited during the playback"
daemon_stop_timed
candump_stop
expect_eq "$(kv "$TACSE3_OUT/stop.txt" exit)" 0 "tacse3d exit status after SIGTERM"
