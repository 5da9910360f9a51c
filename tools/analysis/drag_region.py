#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: where a drag leaves the contact mask, and what the mean flow over it reads (docs/dsp.md §4.2d).
"""Reads a `tacse3-replay --dump-fields DIR` folder and the recording's truth.csv (standard
library only, no NumPy) and prints, per pad:
  - the contact mask Ω in the last frame before the truth starts to move (the patch, as the
    anchor holds it) and at the frame where the mean raw flow over that patch peaks: cell
    counts, how many of the patch's cells are still in Ω, and the mean raw flow (mm) over Ω and
    over the patch;
  - the mean raw flow summed over every frame from the motion's start (mm), over each frame's Ω
    and over the patch, and their ratio;
  - Ω in the last frame: cell count and how many of the patch's cells it holds.
A slide's gel shear is c·v, so its sum over the frames is proportional to the angle at any
speed; a sum that depends on the speed shows a region that does.

Usage: drag_region.py DUMP_DIR RECORDING_DIR
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mask_growth import motion_start_after_rest  # noqa: E402
from torsion_increments import CELLS, load_npy  # noqa: E402


def mean_flow(flow, frame, cells, mm_per_px):
    """Mean raw flow (x, y) in mm over `cells` of `frame`; (0, 0) without cells."""
    if not cells:
        return (0.0, 0.0)
    sx = sum(flow[(frame * CELLS + k) * 2] for k in cells)
    sy = sum(flow[(frame * CELLS + k) * 2 + 1] for k in cells)
    n = len(cells)
    return (sx / n * mm_per_px, sy / n * mm_per_px)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    folder, recording = sys.argv[1], sys.argv[2]
    try:
        with open(f"{folder}/index.json") as f:
            mm_per_px = float(json.load(f)["pixel_pitch_mm"])  # raw flow is in sensor pixels
    except (OSError, ValueError, KeyError) as e:
        sys.exit(f"{folder}/index.json: not a tacse3-replay --dump-fields folder ({e})")
    start = motion_start_after_rest(recording)
    for pad in ("left", "right"):
        try:
            mask, shape = load_npy(f"{folder}/{pad}/mask.npy")
            flow, _ = load_npy(f"{folder}/{pad}/flow.npy")
        except OSError:
            continue
        frames = shape[0]
        patch = [k for k in range(CELLS) if mask[(start - 1) * CELLS + k]]
        if not patch:
            print(f"{pad}: no contact before the motion")
            continue
        patch_set = set(patch)
        sum_omega = [0.0, 0.0]
        sum_patch = [0.0, 0.0]
        peak = (-1.0, start)
        for n in range(start, frames):
            omega = [k for k in range(CELLS) if mask[n * CELLS + k]]
            a = mean_flow(flow, n, omega, mm_per_px)
            b = mean_flow(flow, n, patch, mm_per_px)
            for i in range(2):
                sum_omega[i] += a[i]
                sum_patch[i] += b[i]
            if math.hypot(*b) > peak[0]:
                peak = (math.hypot(*b), n)
        n = peak[1]
        omega = [k for k in range(CELLS) if mask[n * CELLS + k]]
        held = sum(1 for k in omega if k in patch_set)
        a = math.hypot(*mean_flow(flow, n, omega, mm_per_px))
        b = math.hypot(*mean_flow(flow, n, patch, mm_per_px))
        so, sp = math.hypot(*sum_omega), math.hypot(*sum_patch)
        print(f"{pad}: patch before the motion {len(patch)} cells; at frame {n} (peak over the "
              f"patch) Ω {len(omega)} cells, {held} of the patch's; mean flow over Ω "
              f"{a:.3f} mm, over the patch {b:.3f} mm")
        print(f"{pad}: mean flow summed from frame {start}: over each Ω {so:.2f} mm, over the "
              f"patch {sp:.2f} mm, ratio {so / sp if sp > 0 else float('nan'):.3f}")
        last = [k for k in range(CELLS) if mask[(frames - 1) * CELLS + k]]
        print(f"{pad}: last frame {frames - 1}: Ω {len(last)} cells, "
              f"{sum(1 for k in last if k in patch_set)} of the patch's")


if __name__ == "__main__":
    main()
