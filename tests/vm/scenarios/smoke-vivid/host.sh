# SPDX-License-Identifier: Apache-2.0
# Host check of smoke-vivid: the returned frames are 320x240 YUYV with content; rates were measured.
# shellcheck shell=bash
# (The daemon's stream scenario will compare its CAN cycle rate against delivered_fps.)
set -euo pipefail
cd "$TACSE3_VM_LOGDIR"
for d in video0 video1; do
  [ "$(stat -c %s "$d-frame.yuyv")" = 153600 ] || { echo "$d-frame.yuyv is not 320x240x2 bytes"; exit 1; }
  distinct=$(od -An -v -tu1 "$d-frame.yuyv" | tr -s ' ' '\n' | sort -u | wc -l)
  [ "$distinct" -gt 16 ] || { echo "$d frame has only $distinct distinct byte values"; exit 1; }
  grep -q 'delivered_fps=' "$d-rate.txt" || { echo "no rate for $d"; exit 1; }
  echo "$d: $(cat "$d-rate.txt")"
done
