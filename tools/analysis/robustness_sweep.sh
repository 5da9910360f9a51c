#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: replay a sweep of simulated grasps off the benchmark's sizes (objects x motions, sphere
# radius, indentation, offset, noise) with one calibration and print one line per recording:
#   name  estimated_deg  rotation_error_deg  estimated_mm  translation_error_mm
#   (or: name FAILED reason, and the sweep goes on; the exit status is then 1)
# Usage: tools/analysis/robustness_sweep.sh [BUILD_DIR] [CALIBRATION] [WORK_DIR]
# Defaults (relative to the repository): build/host, tools/replay/data/sim-calibration.toml,
# build/robustness. Recordings are rendered once into WORK_DIR/rec (grey, PNG level 0) and reused
# by later runs; a recording rendered by an older simulator is reused too, so use a fresh
# WORK_DIR to compare commits that change the simulator (docs/accuracy.md item 8).
set -euo pipefail
here=$(pwd)
abs() { case "$1" in /*) printf '%s\n' "$1" ;; *) printf '%s\n' "$here/$1" ;; esac; }
REPO="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="$(abs "${1:-$REPO/build/host}")"
CAL="$(abs "${2:-$REPO/tools/replay/data/sim-calibration.toml}")"
WORK="$(abs "${3:-$REPO/build/robustness}")"
SIM="$BUILD/tools/sim/tacse3-sim"
REPLAY="$BUILD/tools/replay/tacse3-replay"
for b in "$SIM" "$REPLAY"; do
  [ -x "$b" ] || { echo "robustness_sweep: $b not built (cmake --build --preset host)" >&2; exit 2; }
done
[ -f "$CAL" ] || { echo "robustness_sweep: calibration file $CAL not found" >&2; exit 2; }
mkdir -p "$WORK/rec" "$WORK/out"

cases() {
  local o m r i axis mag
  for o in sphere large-sphere ellipsoid bumpy cylinder cube wooden-cube textured-cube screwdriver; do
    for m in "rz 3" "rx 2" "ty 0.5" "rz 30" "rx 30" "tx 10"; do
      read -r axis mag <<<"$m"
      echo "${o}_${axis}${mag}_s2|--object $o --motion $axis --magnitude $mag --seed 2"
    done
  done
  for r in 12 15 25 30; do
    for m in "rz 3" "ry 2" "rz 30" "ry 30" "ty 10"; do
      read -r axis mag <<<"$m"
      echo "sphere_r${r}_${axis}${mag}|--object sphere --radius $r --motion $axis --magnitude $mag --seed 3"
    done
  done
  for i in 0.5 1.5 2; do
    for m in "rz 3" "rz 30" "rx 30" "tx 10"; do
      read -r axis mag <<<"$m"
      echo "sphere_i${i}_${axis}${mag}|--object sphere --indentation $i --motion $axis --magnitude $mag --seed 4"
    done
  done
  for m in "rz 3" "rz 30" "rx 30" "tx 10"; do
    read -r axis mag <<<"$m"
    echo "sphere_offset_${axis}${mag}|--object sphere --offset 3 -2 --motion $axis --magnitude $mag --seed 5"
    echo "sphere_noise3_${axis}${mag}|--object sphere --noise 3 --motion $axis --magnitude $mag --seed 6"
  done
}

failed=0
while IFS='|' read -r name args; do
  rec="$WORK/rec/$name"
  if [ ! -f "$rec/.complete" ]; then
    # Rendered into a scratch folder and moved into place, so an interrupted run leaves nothing
    # that a later run would take for a finished recording.
    rm -rf "$rec.partial" "$rec"
    # shellcheck disable=SC2086  # args is a list of options
    if ! "$SIM" -q -o "$rec.partial" $args --colour grey --png-level 0 -j 1 </dev/null; then
      echo "$name FAILED tacse3-sim $args"
      failed=1
      continue
    fi
    touch "$rec.partial/.complete"
    mv "$rec.partial" "$rec"
  fi
  if ! out=$("$REPLAY" "$rec" --calibration "$CAL" --out "$WORK/out/$name.csv" </dev/null 2>&1); then
    echo "$name FAILED tacse3-replay: $(printf '%s\n' "$out" | tail -n 1)"
    failed=1
    continue
  fi
  rot=$(printf '%s\n' "$out" | sed -nE 's/.*rotation: +estimated +([0-9.]+) deg.*error ([0-9.]+) deg.*/\1 \2/p')
  tr=$(printf '%s\n' "$out" | sed -nE 's/.*translation: +estimated +([0-9.]+) mm.*error ([0-9.]+) mm.*/\1 \2/p')
  if [ -z "$rot" ] || [ -z "$tr" ]; then
    echo "$name FAILED no rotation/translation summary in the replay's output"
    failed=1
    continue
  fi
  echo "$name $rot $tr"
done < <(cases)
exit "$failed"
