# SPDX-License-Identifier: Apache-2.0
# Scenario 5, libcamera: tacse3d's libcamera backend on the vimc virtual camera, cycles on vcan0.
# shellcheck shell=sh
# vm-arch: x86_64
# vm-timeout: 120
set -eu
. /tacse3/lib.sh
STREAM_S=${STREAM_S:-8}

lsmod | grep -q '^vimc' || check "modprobe vimc" modprobe vimc
wait_for /dev/media0 10
udev_mark_devices              # libcamera 0.0.3 lists only devices udev has initialised
export LIBCAMERA_LOG_LEVELS="*:WARN"
cam -l >"$TACSE3_OUT/cam-list.txt" 2>&1 || fail "cam -l"
grep -q "^1: .*platform/vimc" "$TACSE3_OUT/cam-list.txt" || fail "libcamera does not list vimc"
vcan_up vcan0
# What vimc delivers through libcamera here (the reference for the cycle rate): 30 frames with cam.
LIBCAMERA_LOG_LEVELS="*:ERROR" cam -c 1 --capture=30 --stream width=320,height=240 \
  >"$TACSE3_OUT/cam-capture.txt" 2>&1 || fail "cam --capture"
awk '/seq:/ { t = $1 + 0; for (i = 1; i <= NF; i++) if ($i == "seq:") s = $(i + 1) + 0
              n++; if (n == 1) { t0 = t; s0 = s } }
     END { if (n < 2 || t == t0) exit 1
           printf "vimc frames=%d dropped=%d span_s=%.3f delivered_fps=%.1f nominal_fps=%.1f\n",
                  n, s - s0 + 1 - n, t - t0, (n - 1) / (t - t0), (s - s0) / (t - t0) }' \
  "$TACSE3_OUT/cam-capture.txt" | tee "$TACSE3_OUT/vimc-rate.txt"
grep -q delivered_fps "$TACSE3_OUT/vimc-rate.txt" || fail "no frame times in cam's output"
need_daemon

check "tacse3d --check accepts the board" tacse3d --board ./board.toml --check
candump_start
rc=0
tacse3d --board ./board.toml --seconds "$STREAM_S" --verbose 2>"$TACSE3_OUT/daemon.log" || rc=$?
sleep 0.3
candump_stop
echo "daemon_exit=$rc stream_s=$STREAM_S" | tee "$TACSE3_OUT/run.txt"
tail -5 "$TACSE3_OUT/daemon.log"
expect_eq "$rc" 0 "tacse3d exit status after --seconds $STREAM_S"
expect_ge "$(wc -l <"$TACSE3_OUT/can.log")" 50 "CAN frames captured"
