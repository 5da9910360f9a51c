#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: docs/accuracy.md's "--mode auto against the fixed proxies" table, re-measured.
#
# Usage: tools/analysis/proxy_table.sh [BUILD_DIR] [CALIBRATION] [WORK_DIR]
#   defaults: build/host, tools/replay/data/sim-calibration.toml, /tmp/tacse3-proxy-table
# Renders seven sphere recordings with tacse3-sim (seed 5: used by neither the calibration set nor
# the test set; grey PNGs), replays each with --mode auto, velocity and displacement, and prints
# one markdown row per recording: final rotation error (deg) / translation error (mm) per mode and
# the detector's per-frame agreement with sim_labels.csv (from tacse3-replay's summary).
# Recordings are reused from WORK_DIR by name: use a fresh WORK_DIR after changing the simulator.
set -euo pipefail
[ $# -le 3 ] || { echo "usage: $0 [BUILD_DIR] [CALIBRATION] [WORK_DIR]" >&2; exit 2; }

root="$(cd "$(dirname "$0")/../.." && pwd)"
build="$(realpath -m "${1:-$root/build/host}")"
cal="$(realpath -m "${2:-$root/tools/replay/data/sim-calibration.toml}")"
work="$(realpath -m "${3:-/tmp/tacse3-proxy-table}")"
sim="$build/tools/sim/tacse3-sim"
replay="$build/tools/replay/tacse3-replay"
for f in "$sim" "$replay"; do
  [ -x "$f" ] || { echo "proxy_table.sh: $f missing: build first (cmake --build --preset host)" >&2; exit 2; }
done
[ -f "$cal" ] || { echo "proxy_table.sh: calibration $cal not found" >&2; exit 2; }
mkdir -p "$work"

# "label|motion magnitude" (all spheres, seed 5)
cases=(
  "sphere rz 30° (slide)|rz 30"
  "sphere rx 30° (slide)|rx 30"
  "sphere ry 60° (slide)|ry 60"
  "sphere tx 10 mm (slide)|tx 10"
  "sphere rz 4° (stick)|rz 4"
  "sphere rx 2° (stick)|rx 2"
  "sphere tx 0.4 mm (stick)|tx 0.4"
)

echo "| recording (regime) | \`--mode auto\` | \`--mode velocity\` | \`--mode displacement\` | detector: frames agreeing |"
echo "|---|---|---|---|---|"
for c in "${cases[@]}"; do
  label="${c%%|*}"
  read -r motion magnitude <<<"${c#*|}"
  name="sphere_${motion}${magnitude}_s5"
  rec="$work/$name"
  if [ ! -f "$rec/recording.json" ]; then
    rm -rf "$rec.tmp" "$rec"   # a folder without recording.json is an interrupted render
    "$sim" -q -o "$rec.tmp" --object sphere --motion "$motion" --magnitude "$magnitude" --seed 5 \
      --colour grey --png-level 0
    mv "$rec.tmp" "$rec"
  fi
  row="| $label"
  detector=""
  for mode in auto velocity displacement; do
    log="$work/$name.$mode.txt"
    "$replay" "$rec" --calibration "$cal" --mode "$mode" --out "$work/$name.$mode.csv" \
      >"$log" 2>&1 || { echo "proxy_table.sh: replay of $rec ($mode) failed, see $log" >&2; exit 1; }
    cell="$(awk '/^  rotation:/ {r = $(NF-1)} /^  translation:/ {t = $(NF-1)}
                 END {if (r == "" || t == "") exit 1; printf "%s / %s", r, t}' "$log")" ||
      { echo "proxy_table.sh: no error summary in $log (tacse3-replay's output changed?)" >&2; exit 1; }
    row="$row | $cell"
    if [ "$mode" = auto ]; then
      detector="$(sed -n 's/^  slip detector vs sim_labels.csv: \([0-9.]*%\) of \([0-9]*\) in-contact sensor-frames (\(.*\))$/\1 of \2 (\3)/p' "$log")"
    fi
  done
  echo "$row | ${detector:-–} |"
done
