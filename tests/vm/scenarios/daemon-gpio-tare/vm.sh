# SPDX-License-Identifier: Apache-2.0
# Scenario 6, GPIO input: pulling a gpio-sim tare-button line makes tacse3d tare (seen on vcan0).
# The pads are v4l2loopback devices holding an undeformed frame: cheap, unlike the sim backend
# rendering in the emulated CPU (about 1 cycle/s there).
# shellcheck shell=sh
# vm-arch: x86_64
# vm-timeout: 90
set -eu
. /tacse3/lib.sh

info=$(gpiosim_chip tacse3-tare 8 tare-button status-led) || fail "gpio-sim chip: $info"
chip=${info% *} dev=${info#* }
sim=/sys/devices/platform/$dev/$chip
log "gpio-sim: $chip ($dev)"
gpioinfo "$chip" | tee "$TACSE3_OUT/gpioinfo-before.txt"
echo pull-up >"$sim/sim_gpio0/pull"          # the button's resting level (active low: released)
vcan_up vcan0
loopback_pads 4                # the first frame only (no /tmp/go): no contact, nothing moves
need_daemon

sed "s/@CHIP@/$chip/" board.toml.in >/tmp/board.toml
cp /tmp/board.toml "$TACSE3_OUT/board.toml"
check "tacse3d --check accepts the board" tacse3d --board /tmp/board.toml --check
daemon_streaming /tmp/board.toml
gpioinfo "$chip" | tee "$TACSE3_OUT/gpioinfo-running.txt"
grep -q 'line *0:.*input' "$TACSE3_OUT/gpioinfo-running.txt" || fail "tare-button line is not an input"
sleep 1
can_marker 05                  # from here on: no tare until the button
sleep 2
can_marker 06
echo pull-down >"$sim/sim_gpio0/pull"        # press (held 300 ms, far above the 20 ms debounce)
sleep 0.3
can_marker 07
echo pull-up >"$sim/sim_gpio0/pull"          # release
sleep 1.5
kill -0 "$DAEMON_PID" || fail "tacse3d exited"
daemon_stop_timed
candump_stop
expect_eq "$(kv "$TACSE3_OUT/stop.txt" exit)" 0 "tacse3d exit status after SIGTERM"
