# SPDX-License-Identifier: Apache-2.0
# Smoke: a v4l2loopback device; a frame written to its output side is read back from its capture side.
# shellcheck shell=sh
# vm-arch: x86_64
# vm-timeout: 60
set -eu
. /tacse3/lib.sh
W=320 H=240 DEV=/dev/video20

check "modprobe v4l2loopback" modprobe v4l2loopback devices=1 video_nr=20 card_label=tacse3-loop exclusive_caps=1
wait_for "$DEV" 5
v4l2-ctl -d "$DEV" --info | tee "$TACSE3_OUT/info.txt"

# A known frame: a 320x240 YUYV gradient with a frame-specific header.
awk -v w=$W -v h=$H 'BEGIN { for (y = 0; y < h; y++) { line = ""; for (x = 0; x < w; x++)
    line = line sprintf("%c%c", (x + y) % 200 + 16, (x % 2) ? 160 : 96); printf "%s", line } }' \
  >/tmp/frame.yuyv
expect_eq "$(stat -c %s /tmp/frame.yuyv)" $((W * H * 2)) "test frame size"

# keep_format: the format set here outlives this v4l2-ctl (otherwise it resets on the last close).
check "set output format" v4l2-ctl -d "$DEV" -c keep_format=1 \
  --set-fmt-video-out=width=$W,height=$H,pixelformat=YUYV
# The writer uses write(): one write() of sizeimage bytes is one frame, ~20 frames/s. (v4l2-ctl
# --stream-out-mmap --stream-from wants file frames as long as the page-rounded buffer, 155648.)
( while :; do dd if=/tmp/frame.yuyv bs=$((W * H * 2)) count=1 2>/dev/null; sleep 0.05; done ) >"$DEV" &
writer=$!
sleep 1
v4l2-ctl -d "$DEV" --info >"$TACSE3_OUT/info-streaming.txt"
grep -A1 'Device Caps' "$TACSE3_OUT/info-streaming.txt" | grep -q 'Video Capture' ||
  fail "with a writer, the device does not offer capture (exclusive_caps=1)"
v4l2-ctl -d "$DEV" --get-fmt-video | tee "$TACSE3_OUT/fmt.txt"
grep -q "Width/Height *: $W/$H" "$TACSE3_OUT/fmt.txt" || fail "capture side is not ${W}x$H"
check "capture 3 frames" v4l2-ctl -d "$DEV" --stream-mmap=2 --stream-count=3 --stream-to=/tmp/back.yuyv
kill "$writer" 2>/dev/null; wait "$writer" 2>/dev/null || true
expect_eq "$(stat -c %s /tmp/back.yuyv)" $((3 * W * H * 2)) "bytes read back"
tail -c $((W * H * 2)) /tmp/back.yuyv >"$TACSE3_OUT/frame-read.yuyv"
cp /tmp/frame.yuyv "$TACSE3_OUT/frame-written.yuyv"
check "frame read back equals frame written" cmp /tmp/frame.yuyv "$TACSE3_OUT/frame-read.yuyv"
