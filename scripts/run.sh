#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: the main job with no hardware attached. Builds the host preset's demo, which simulates
# two mirrored DM-Tac pads grasping a sphere that is then rotated in the grip, runs the firmware's
# fixed-point pipeline on every frame pair in memory and prints the estimated rotation against
# the simulator's truth. No flags, no hardware; about a minute on a fresh machine after setup.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS="${TACSE3_JOBS:-$(nproc)}"
echo "tacse3: building the demo (cmake preset \"host\") ..."
cmake --preset host >/dev/null
cmake --build --preset host -j "$JOBS" --target tacse3-demo >/dev/null
exec build/host/tools/demo/tacse3-demo
