# SPDX-License-Identifier: Apache-2.0
# Smoke: the out-of-tree vimc driver, seen by v4l2-ctl/media-ctl and listed by libcamera's cam.
# shellcheck shell=sh
# vm-arch: x86_64
# vm-timeout: 120
set -eu
. /tacse3/lib.sh

check "modprobe vimc" modprobe vimc
wait_for /dev/media0 10
media-ctl -d /dev/media0 -p >"$TACSE3_OUT/media-topology.txt" 2>&1 || fail "media-ctl -p"
grep -q 'driver *vimc' "$TACSE3_OUT/media-topology.txt" || fail "media0 is not vimc"
v4l2-ctl --list-devices 2>&1 | tee "$TACSE3_OUT/devices.txt"

# libcamera 0.0.3 enumerates through libudev and ignores devices udev has not initialised.
udev_mark_devices
ls /run/udev/data >"$TACSE3_OUT/udev-data.txt"
export LIBCAMERA_LOG_LEVELS="*:WARN"
cam -l >"$TACSE3_OUT/cam-list.txt" 2>&1 || { cat "$TACSE3_OUT/cam-list.txt"; fail "cam -l"; }
cat "$TACSE3_OUT/cam-list.txt"
grep -q "^1: .*platform/vimc" "$TACSE3_OUT/cam-list.txt" || fail "cam -l does not list the vimc camera"
cam -c 1 -I >"$TACSE3_OUT/cam-info.txt" 2>&1 || true
grep -q -- '- 320x240' "$TACSE3_OUT/cam-info.txt" || fail "vimc offers no 320x240 through libcamera"

# Stream 10 frames through the libcamera pipeline (sensor -> debayer -> scaler -> capture).
# Note: libcamera 0.0.3's vimc handler assumes a fixed 3x scaler and adjusts 320x240 to 318x240
# ("Camera configuration adjusted"); 960x720 is exact. The configured size is saved for the host.
LIBCAMERA_LOG_LEVELS="Camera:INFO,*:ERROR" cam -c 1 --capture=10 --stream width=320,height=240 \
  >"$TACSE3_OUT/cam-capture.txt" 2>&1 || { tail -20 "$TACSE3_OUT/cam-capture.txt"; fail "cam --capture"; }
sed -n 's/.*configuring streams: (0) \([0-9]*x[0-9]*-[A-Z0-9]*\).*/\1/p' "$TACSE3_OUT/cam-capture.txt" \
  >"$TACSE3_OUT/cam-configured.txt"
echo "libcamera configured $(cat "$TACSE3_OUT/cam-configured.txt") for a 320x240 request"
grep -q . "$TACSE3_OUT/cam-configured.txt" || fail "no stream configuration in cam's log"
grep 'seq:' "$TACSE3_OUT/cam-capture.txt" | tail -3
expect_eq "$(grep -c 'seq: ' "$TACSE3_OUT/cam-capture.txt")" 10 "frames completed by libcamera"
