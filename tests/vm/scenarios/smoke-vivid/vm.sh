# SPDX-License-Identifier: Apache-2.0
# Smoke: two vivid capture devices at 320x240 (HDMI input + DV timings + scaler), streamed together.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 90
set -eu
. /tacse3/lib.sh
FRAMES=${FRAMES:-240}
W=320 H=240

# Only the video-capture node per instance; inputs: 0 webcam, 1 TV, 2 S-Video, 3 HDMI.
check "modprobe vivid n_devs=2" modprobe vivid n_devs=2 node_types=0x1,0x1
v4l2-ctl --list-devices >"$TACSE3_OUT/devices.txt" 2>&1 || true
cat "$TACSE3_OUT/devices.txt"
for dev in /dev/video0 /dev/video1; do
  wait_for "$dev" 5
  d=$(basename "$dev")
  v4l2-ctl -d "$dev" --info | grep -q 'Driver name *: vivid' || fail "$dev is not vivid"
  # The webcam input has no 320x240 (it offers 320x180); HDMI with 640x480@120 CVT-RB timings
  # plus vivid's scaler gives 320x240 at 119.1 Hz nominal.
  check "$d: select HDMI input" v4l2-ctl -d "$dev" --set-input 3
  check "$d: DV timings 640x480@120" v4l2-ctl -d "$dev" \
    --set-dv-bt-timings cvt,width=640,height=480,fps=120,reduced-blanking=1
  v4l2-ctl -d "$dev" --get-dv-timings >"$TACSE3_OUT/$d-dv-timings.txt"
  check "$d: set ${W}x${H} YUYV" v4l2-ctl -d "$dev" --set-fmt-video=width=$W,height=$H,pixelformat=YUYV
  v4l2-ctl -d "$dev" --get-fmt-video >"$TACSE3_OUT/$d-fmt.txt" 2>/dev/null
  grep -q "Width/Height *: $W/$H" "$TACSE3_OUT/$d-fmt.txt" || fail "$d: format is not ${W}x$H"
  grep -q "'YUYV'" "$TACSE3_OUT/$d-fmt.txt" || fail "$d: pixel format is not YUYV"
  v4l2-ctl -d "$dev" --get-parm >"$TACSE3_OUT/$d-parm.txt" 2>&1
  grep -q 'Frames per second: 119' "$TACSE3_OUT/$d-parm.txt" || fail "$d: nominal rate is not 119 Hz"
done

# Stream both at once, as the daemon will. vivid stamps buffers on its nominal 119.1 Hz schedule and
# skips sequence numbers when the (emulated) CPU falls behind, so the delivered rate is
# (frames - 1) / (last - first timestamp), and the skipped sequence numbers are the drops.
for dev in /dev/video0 /dev/video1; do
  v4l2-ctl -d "$dev" --stream-mmap=4 --stream-count="$FRAMES" --verbose \
    >"$TACSE3_OUT/$(basename "$dev")-stream.txt" 2>&1 &
done
wait
for dev in /dev/video0 /dev/video1; do
  d=$(basename "$dev")
  awk -v want=$((W * H * 2)) '/cap dqbuf:/ {
      for (i = 1; i <= NF; i++) { if ($i == "seq:") s = $(i + 1); if ($i == "ts:") t = $(i + 1);
                                  if ($i == "bytesused:" && $(i + 1) != want) bad++ }
      n++; if (n == 1) { s0 = s; t0 = t } }
    END { if (n < 2 || t == t0) { print "no frames"; exit 1 }
          printf "frames=%d first_seq=%d last_seq=%d dropped=%d span_s=%.3f delivered_fps=%.1f nominal_fps=%.1f bad_size=%d\n",
                 n, s0, s, s - s0 + 1 - n, t - t0, (n - 1) / (t - t0), (s - s0) / (t - t0), bad + 0 }' \
    "$TACSE3_OUT/$d-stream.txt" | tee "$TACSE3_OUT/$d-rate.txt"
  r="$TACSE3_OUT/$d-rate.txt"
  expect_eq "$(kv "$r" frames)" "$FRAMES" "$d: frames dequeued"
  expect_eq "$(kv "$r" bad_size)" 0 "$d: frames with a wrong size"
  fps=$(kv "$r" delivered_fps)
  awk -v f="$fps" 'BEGIN { exit !(f >= 20) }' || fail "$d: delivered rate $fps fps is implausibly low"
  # One frame of each to the host.
  v4l2-ctl -d "$dev" --stream-mmap=2 --stream-count=1 --stream-to="$TACSE3_OUT/$d-frame.yuyv" 2>/dev/null
  expect_eq "$(stat -c %s "$TACSE3_OUT/$d-frame.yuyv")" $((W * H * 2)) "$d: saved frame size"
done
