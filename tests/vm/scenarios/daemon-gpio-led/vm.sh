# SPDX-License-Identifier: Apache-2.0
# Scenario 4, GPIO: the status LED on the virt machine's PL061 (gpiochip0 line 0) follows tacse3d's state.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 90
set -eu
. /tacse3/lib.sh

gpiodetect | tee "$TACSE3_OUT/gpiodetect.txt"
grep -q '^gpiochip0 \[9030000.pl061\] (8 lines)' "$TACSE3_OUT/gpiodetect.txt" || fail "no PL061 gpiochip0"
# The global number of line 0 in /sys/kernel/debug/gpio: the chip's base.
base=
for c in /sys/class/gpio/gpiochip*; do
  [ "$(cat "$c/label")" = 9030000.pl061 ] && base=$(cat "$c/base")
done
[ -n "$base" ] || fail "PL061 base not found in /sys/class/gpio"
led="gpio-$base "
log "status LED: gpiochip0 line 0 = ${led}in /sys/kernel/debug/gpio"
vivid_two_sensors
vcan_up vcan0
need_daemon

# LED sampler, builtins only (read, case, arithmetic): a fork per sample would make it far too slow
# under TCG. /sys/kernel/debug/gpio lists the requested lines only: line 2 of the file is ours.
# The pause is a 20 ms read timeout on a FIFO nobody writes.
mkfifo /tmp/led.fifo
(
  exec 8<>/tmp/led.fifo
  while :; do
    read -r up _ </proc/uptime
    l=; { read -r _; read -r l; } </sys/kernel/debug/gpio || :   # one line while nothing is requested
    case "$l" in *"$led"*"out hi"*) v=1 ;; *) v=0 ;; esac
    echo "$(( ${up%.*} * 1000 + 1${up#*.} * 10 - 1000 )) $v"
    read -t 0.02 _ <&8 || :
  done
) >"$TACSE3_OUT/led.txt" &
sampler=$!
daemon_streaming ./board.toml
# Tie the sampler's clock (uptime) to the candump clock: marker 05 and the uptime next to it.
read -r up _ </proc/uptime
can_marker 05
echo "sync $(( ${up%.*} * 1000 + 1${up#*.} * 10 - 1000 ))" >"$TACSE3_OUT/led-sync.txt"
gpioinfo gpiochip0 | tee "$TACSE3_OUT/gpioinfo-running.txt"
grep -q 'line *0:.*"tacse3d".*output' "$TACSE3_OUT/gpioinfo-running.txt" ||
  grep -q 'line *0:.*output.*used' "$TACSE3_OUT/gpioinfo-running.txt" || fail "line 0 is not an output held by tacse3d"
sleep 4.5                      # NO_CONTACT: a short flash every 2 s
vivid_unplug 1
sleep 4.5                      # DEGRADED: a double flash every second
vivid_replug 1
sleep 2
daemon_stop_timed
sleep 1.5                      # the LED is dark once tacse3d is gone
kill "$sampler" 2>/dev/null || fail "the LED sampler died early (see led.txt)"
candump_stop
gpioinfo gpiochip0 >"$TACSE3_OUT/gpioinfo-after.txt"
grep -q 'line *0:.*unused' "$TACSE3_OUT/gpioinfo-after.txt" || fail "line 0 still requested after tacse3d stopped"
expect_ge "$(wc -l <"$TACSE3_OUT/led.txt")" 100 "LED samples"
