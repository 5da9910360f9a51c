#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: how a held tangential load grows the contact mask (docs/dsp.md §4.2c).
"""Reads a `tacse3-replay --dump-fields DIR` folder and the recording's truth.csv (standard
library only, no NumPy) and prints, per pad: the contact mask's cell count in the last frame
before the truth starts to move and in the last frame, the peak of filter(f^z) in both, and the
mean smoothed displacement (working px) in the last frame over the earlier mask and over the last
one. A tangential load stretches the gel behind the patch; 𝒢 reads the stretch as normal load, so
the mask grows over gel that does not move with the object, and a mean over it is diluted.

Usage: mask_growth.py DUMP_DIR RECORDING_DIR
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from torsion_increments import CELLS, load_npy  # noqa: E402


def motion_start(recording):
    """Index of the first frame whose truth pose differs from the identity."""
    with open(f"{recording}/truth.csv") as f:
        for i, row in enumerate(csv.DictReader(f)):
            moved = sum(abs(float(row[k])) for k in ("qx", "qy", "qz", "px", "py", "pz"))
            if moved > 1e-9:
                return i
    sys.exit(f"{recording}/truth.csv: the object never moves")


def motion_start_after_rest(recording):
    """motion_start, which must leave at least one frame before the motion."""
    start = motion_start(recording)
    if start < 1:
        sys.exit("the motion starts at the first frame: no frame before it")
    return start


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    folder, recording = sys.argv[1], sys.argv[2]
    start = motion_start_after_rest(recording)
    for pad in ("left", "right"):
        try:
            mask, shape = load_npy(f"{folder}/{pad}/mask.npy")
        except FileNotFoundError:
            continue
        fz, _ = load_npy(f"{folder}/{pad}/fz_filtered.npy")
        disp, _ = load_npy(f"{folder}/{pad}/displacement.npy")
        last = shape[0] - 1
        before = start - 1

        def cells(n):
            return [k for k in range(CELLS) if mask[n * CELLS + k]]

        def peak(n):
            return max(fz[n * CELLS + k] for k in range(CELLS))

        def mean_displacement(ks, n):
            if not ks:
                return (0.0, 0.0)
            sx = sum(disp[(n * CELLS + k) * 2] for k in ks)
            sy = sum(disp[(n * CELLS + k) * 2 + 1] for k in ks)
            return (sx / len(ks), sy / len(ks))

        early, final = cells(before), cells(last)
        me = mean_displacement(early, last)
        mf = mean_displacement(final, last)
        print(f"{pad}: mask {len(early)} cells at frame {before} (before the motion), "
              f"{len(final)} at frame {last}; peak filter(f^z) {peak(before):.3f} -> "
              f"{peak(last):.3f}; mean displacement at frame {last} over the earlier mask "
              f"({me[0]:.3f}, {me[1]:.3f}) px, over the last mask ({mf[0]:.3f}, {mf[1]:.3f}) px")


if __name__ == "__main__":
    main()
