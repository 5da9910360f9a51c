# SPDX-License-Identifier: Apache-2.0
# Smoke: a gpio-sim chip made through configfs; lines pulled from sysfs are read and seen as edges.
# shellcheck shell=sh
# vm-arch: x86_64
# vm-timeout: 60
set -eu
. /tacse3/lib.sh

check "modprobe gpio-sim" modprobe gpio-sim
cfg=/sys/kernel/config/gpio-sim/tacse3
mkdir "$cfg" "$cfg/bank0" "$cfg/bank0/line0" "$cfg/bank0/line1"
echo 8 >"$cfg/bank0/num_lines"
echo tare-button >"$cfg/bank0/line0/name"
echo status-led >"$cfg/bank0/line1/name"
echo 1 >"$cfg/live"
chip=$(cat "$cfg/bank0/chip_name")
dev=$(cat "$cfg/dev_name")
echo "gpio-sim chip: $chip ($dev)"
gpiodetect | tee "$TACSE3_OUT/gpiodetect.txt"
grep -q "^$chip \[$dev-node0\] (8 lines)" "$TACSE3_OUT/gpiodetect.txt" || fail "$chip not listed"
gpioinfo "$chip" | tee "$TACSE3_OUT/gpioinfo.txt"
expect_eq "$(gpiofind tare-button)" "$chip 0" "gpiofind tare-button"
sim=/sys/devices/platform/$dev/$chip

# Input: the simulator pulls line 0, libgpiod reads it.
echo pull-up >"$sim/sim_gpio0/pull"
expect_eq "$(gpioget "$chip" 0)" 1 "line 0 read after pull-up"
echo pull-down >"$sim/sim_gpio0/pull"
expect_eq "$(gpioget "$chip" 0)" 0 "line 0 read after pull-down"

# Edge events through the bundled irq_sim: a press (rising) and release (falling).
gpiomon --num-events=2 --format='%e' "$chip" 0 >"$TACSE3_OUT/gpiomon.txt" &
mon=$!
sleep 0.5
echo pull-up >"$sim/sim_gpio0/pull"
sleep 0.2
echo pull-down >"$sim/sim_gpio0/pull"
i=0; while kill -0 "$mon" 2>/dev/null && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
kill "$mon" 2>/dev/null || true
cat "$TACSE3_OUT/gpiomon.txt"
expect_eq "$(tr '\n' ' ' <"$TACSE3_OUT/gpiomon.txt")" "1 0 " "edge events on line 0 (1 rising, 0 falling)"

# Output: libgpiod drives line 1, the simulator's sysfs shows the value.
gpioset --mode=signal "$chip" 1=1 &
setter=$!
sleep 0.5
expect_eq "$(cat "$sim/sim_gpio1/value")" 1 "line 1 value seen by gpio-sim while set to 1"
kill "$setter"; wait "$setter" 2>/dev/null || true
