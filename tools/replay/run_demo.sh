#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: the no-hardware main job through the replay tool (proposed body of scripts/run.sh).
# Builds the simulator and the replay tool (host preset), simulates (or reuses) a short
# grasp-and-rotate recording of two mirrored DM-Tac pads under build/run/, replays it through the
# firmware's fixed-point pipeline with the calibration fitted on simulated grasps
# (tools/replay/data/sim-calibration.toml, from tacse3-bench-accuracy) and prints the estimated
# rotation against the simulator's truth. No flags.
# TACSE3_RUN_BUILD_DIR: use an already configured build folder instead of the host preset.
set -euo pipefail
cd "$(dirname "$0")/../.."

JOBS="${TACSE3_JOBS:-2}"
BUILD="${TACSE3_RUN_BUILD_DIR:-build/host}"
OUT=build/run
REC="$OUT/sphere_rx30"
CAL=tools/replay/data/sim-calibration.toml

if [ -z "${TACSE3_RUN_BUILD_DIR:-}" ]; then
  echo "tacse3: building the simulator and the replay tool (cmake preset \"host\") ..."
  cmake --preset host >/dev/null
  cmake --build --preset host -j "$JOBS" --target tacse3-sim tacse3-replay >/dev/null
else
  cmake --build "$BUILD" -j "$JOBS" --target tacse3-sim tacse3-replay >/dev/null
fi

mkdir -p "$OUT"
if [ -f "$REC/recording.json" ] && [ -f "$REC/truth.csv" ]; then
  echo "tacse3: reusing the simulated recording $REC"
else
  echo "tacse3: simulating a grasp of a 20 mm sphere that is then rotated 30 deg about the"
  echo "        gripper's x axis (two 320x240 pads at 120 fps, 2 s) into $REC ..."
  "$BUILD/tools/sim/tacse3-sim" -q --overwrite --out "$REC" --object sphere --motion rx \
    --magnitude 30 --colour grey
fi

cal_args=()
if [ -f "$CAL" ]; then cal_args=(--calibration "$CAL"); fi
echo "tacse3: replaying it through the firmware's fixed-point pipeline ..."
echo
"$BUILD/tools/replay/tacse3-replay" "$REC" "${cal_args[@]}" --out "$OUT/sphere_rx30.csv"
echo
echo "Per-frame twist and pose: $OUT/sphere_rx30.csv (docs/replay.md)."
echo "Accuracy over the paper's experiments: docs/accuracy.md."
