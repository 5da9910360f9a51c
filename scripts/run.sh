#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: the main job with no hardware attached. Builds the firmware daemon and the bus monitor
# (cmake preset "host"), runs tacse3d on the simulated board for 5 seconds -- two simulated DM-Tac
# pads grasp a sphere that then turns 30 degrees in the grip -- and pipes its CAN stream (candump
# -L format on stdout) into tacse3-canmon, which decodes the twist/pose cycles. At the end the
# daemon compares the final pose it sent with the simulator's truth. Ends by itself.
# TACSE3_RUN_BUILD_DIR: use an already configured build folder instead of the host preset.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS="${TACSE3_JOBS:-2}"
BUILD="${TACSE3_RUN_BUILD_DIR:-build/host}"
SECONDS_TO_RUN="${TACSE3_RUN_SECONDS:-5}"

if [ -z "${TACSE3_RUN_BUILD_DIR:-}" ]; then
  echo "tacse3: building tacse3d and tacse3-canmon (cmake preset \"host\") ..."
  cmake --preset host >/dev/null
fi
cmake --build "$BUILD" -j "$JOBS" --target tacse3d tacse3-canmon >/dev/null

OUT=build/run
mkdir -p "$OUT"
echo "tacse3: tacse3d --board sim --seconds $SECONDS_TO_RUN --can-log - | tacse3-canmon --log -"
echo "        (one CSV row per decoded cycle; every 60th shown; the daemon's diagnostics on stderr)"
# No --calibration: the sim board defaults to the simulated pads' fitted calibration
# (tools/replay/data/sim-calibration.toml, from tacse3-bench-accuracy).
"$BUILD/firmware/tacse3d" --board sim --seconds "$SECONDS_TO_RUN" --can-log - 2>"$OUT/tacse3d.err" |
  "$BUILD/tools/canmon/tacse3-canmon" --log - --format csv 2>"$OUT/canmon.err" |
  awk -F, 'NR == 1 { printf "%10s %4s %5s %8s %8s %8s %9s %9s %9s %9s %s\n", "t_s", "cnt", "valid",
                       "wx", "wy", "wz", "qw", "qx", "qy", "qz", "state"; next }
           { if (t0 == "") t0 = $1; last = $0; n++ }
           n % 60 == 1 { printf "%10.3f %4s %5s %8s %8s %8s %9s %9s %9s %9s %s\n", ($1 - t0) / 1e6,
                         $3, $4, $8, $9, $10, $14, $15, $16, $17, $21 }
           END { split(last, f, ","); printf "%10.3f %4s %5s %8s %8s %8s %9s %9s %9s %9s %s  (last)\n",
                   (f[1] - t0) / 1e6, f[3], f[4], f[8], f[9], f[10], f[14], f[15], f[16], f[17], f[21] }'
echo
cat "$OUT/canmon.err"
grep -E "calibration|UNCALIBRATED|stopped after|sim truth" "$OUT/tacse3d.err" || cat "$OUT/tacse3d.err"
# The simulated pads are rendered in real time on the capture threads (~2.5 ms CPU per pad and
# frame). On a machine too busy for that each pad skips the instants it rendered too late, on its
# own, so fewer frames pair and the estimate degrades: say so rather than leave a bad number
# unexplained.
awk '/stopped after/ { for (i = 1; i <= NF; i++) { if ($i == "pairs,") p = $(i - 1); if ($i == "single),") s = $(i - 1) }
                       gsub(/\(/, "", p); if (s + 0 > p + 0)
                         print "tacse3: note: most samples had one pad only (" s " single, " p " pairs): this machine could not render both simulated pads at 120 Hz; see docs/firmware.md (\"sim board under load\")." }' "$OUT/tacse3d.err"
