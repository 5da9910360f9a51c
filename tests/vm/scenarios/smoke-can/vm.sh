# SPDX-License-Identifier: Apache-2.0
# Smoke: SocketCAN on vcan0 with Debian's can-utils; candump's log is checked on the host.
# shellcheck shell=sh
# vm-arch: aarch64 x86_64
# vm-timeout: 60
set -eu
. /tacse3/lib.sh

check "modprobe can-raw" modprobe can-raw
vcan_up vcan0
ip -details link show vcan0

candump -L vcan0 >"$TACSE3_OUT/candump.log" &
dump=$!
sleep 0.5
# Classic frames with known payloads, one RTR, one extended id, then a burst from cangen.
check "cansend 123#DEADBEEF" cansend vcan0 123#DEADBEEF
check "cansend 7FF#R" cansend vcan0 7FF#R
check "cansend 1ABCDE01#0102" cansend vcan0 1ABCDE01#0102
for i in 0 1 2 3 4 5 6 7 8 9; do cansend vcan0 "100#0$i"; done
check "cangen burst" cangen vcan0 -g 1 -n 50 -I 321 -L 8 -D i
sleep 0.5
kill "$dump"; wait "$dump" 2>/dev/null || true
n=$(wc -l <"$TACSE3_OUT/candump.log")
expect_eq "$n" 63 "frames captured by candump"
ip -s link show vcan0 >"$TACSE3_OUT/link-stats.txt"
