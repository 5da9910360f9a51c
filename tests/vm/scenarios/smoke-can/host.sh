# SPDX-License-Identifier: Apache-2.0
# Host check of smoke-can: the candump -L log returned from the VM has the frames that were sent.
# shellcheck shell=bash
set -euo pipefail
log="$TACSE3_VM_LOGDIR/candump.log"
[ -s "$log" ] || { echo "no candump log"; exit 1; }
# candump -L lines: (timestamp) vcan0 ID#DATA
bad=$(grep -cvE '^\([0-9]+\.[0-9]{6}\) vcan0 [0-9A-F]+#' "$log" || true)
[ "$bad" = 0 ] || { echo "$bad malformed lines"; exit 1; }
grep -q ' vcan0 123#DEADBEEF$' "$log" || { echo "123#DEADBEEF missing"; exit 1; }
grep -q ' vcan0 7FF#R' "$log" || { echo "RTR frame missing"; exit 1; }
grep -q ' vcan0 1ABCDE01#0102$' "$log" || { echo "extended frame missing"; exit 1; }
[ "$(grep -c ' vcan0 100#0[0-9]$' "$log")" = 10 ] || { echo "sequence 100#00..09 incomplete"; exit 1; }
# cangen -D i -L 8: the payload increments by one per frame, so the 50 frames are contiguous.
awk 'function hex(s,  i, v) { v = 0; for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789ABCDEF", substr(s, i, 1)) - 1; return v }
     $3 ~ /^321#/ { split($3, f, "#"); v = hex(substr(f[2], 1, 2));
       if (n && v != (last + 1) % 256) { print "gap after " last; bad = 1 } last = v; n++ }
     END { if (n != 50) { print "cangen frames: " n; bad = 1 } exit bad }' "$log"
# timestamps never go backwards
awk '{ t = substr($1, 2, length($1) - 2) + 0; if (t < prev) { print "time went back at " NR; exit 1 } prev = t }' "$log"
echo "candump log OK: $(wc -l <"$log") frames"
