# SPDX-License-Identifier: Apache-2.0
# Smoke: the fault injections of scenarios 3/4 without the daemon: vivid's per-instance disconnect
# (ENODEV under an open stream, back after the last close) and a sysfs unbind/bind of vivid.0.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 90
set -eu
. /tacse3/lib.sh

vivid_two_sensors
vcan_up vcan0
right=$(vivid_node 1)
# A stream on the right pad, then the unplug under it: v4l2-ctl must fail (ENODEV), the left one not.
v4l2-ctl -d /dev/tacse3-right --stream-mmap=4 --stream-count=100000 >/tmp/right-stream.txt 2>&1 &
s1=$!
v4l2-ctl -d /dev/tacse3-left --stream-mmap=4 --stream-count=100000 >/tmp/left-stream.txt 2>&1 &
s0=$!
sleep 1.5
vivid_unplug 1
i=0; while kill -0 "$s1" 2>/dev/null && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
kill -0 "$s1" 2>/dev/null && fail "the stream on the unplugged device is still running after 5 s"
wait "$s1" || true
tail -2 /tmp/right-stream.txt
# v4l2-ctl exits 0 even then; its stream loop reports the failed ioctl.
grep -q 'error' /tmp/right-stream.txt || fail "no ioctl error on the unplugged device's stream"
echo "ok: the stream on the unplugged device failed ($(grep -m1 error /tmp/right-stream.txt))"
kill -0 "$s0" || fail "the left stream stopped too"
v4l2-ctl -d "$right" --info >/dev/null 2>&1 && fail "$right opens while disconnected"
echo "ok: $right refuses to open while disconnected"
vivid_replug 1                 # all files of it are closed: back
check "$right streams again after the replug" v4l2-ctl -d "$right" --stream-mmap=2 --stream-count=5
check "$right is still 320x240 (the instance kept its setup)" sh -c \
  "v4l2-ctl -d $right --get-fmt-video | grep -q 'Width/Height *: 320/240'"
kill "$s0"; wait "$s0" 2>/dev/null || true

# sysfs: both pads go, their nodes with them; bind brings fresh instances (reconfigured here).
vivid_unbind_all
[ -z "$(vivid_node 0)$(vivid_node 1)" ] || fail "vivid nodes still there after the unbind"
echo "ok: no vivid node after the sysfs unbind"
vivid_rebind_all
check "left streams after the rebind" v4l2-ctl -d /dev/tacse3-left --stream-mmap=2 --stream-count=5
check "right streams after the rebind" v4l2-ctl -d /dev/tacse3-right --stream-mmap=2 --stream-count=5
