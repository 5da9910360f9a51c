#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: a slide's shear over the deepest part of the patch (accuracy.md item 2 (f)).
"""Reads a `tacse3-replay --dump-fields DIR` folder and the recording's truth.csv (standard
library only, no NumPy) and prints, per pad, the calibrated shear (f^x, f^y) averaged over a
region of the patch and summed over the frames from the motion's start, per degree of the
truth's final rotation. The regions: the contact mask Ω in the last frame before the motion (the
patch, as the displacement proxy's anchor holds it) and its cores, the patch cells whose
filter(f^z) in that frame is at least a fraction of the patch's largest.

A slide's gel shear is c·v up to the friction cap μκd, which is lowest where the object is
shallowest, so the rim saturates first: a region whose sum per degree stays the same at every
speed reads the speed; the deeper the core, the later it saturates (and the fewer cells it
averages).

Usage: depth_core.py DUMP_DIR RECORDING_DIR [--fractions 0 0.5 0.7]
"""
import argparse
import csv
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mask_growth import motion_start_after_rest  # noqa: E402
from torsion_increments import CELLS, load_npy  # noqa: E402


def read_truth(recording):
    """(frame count, final rotation in degrees) of the recording's truth.csv."""
    try:
        with open(f"{recording}/truth.csv") as f:
            qw = [float(row["qw"]) for row in csv.DictReader(f)]
    except OSError as e:
        sys.exit(f"{recording}: cannot read truth.csv ({e.strerror})")
    except (KeyError, TypeError, ValueError) as e:
        sys.exit(f"{recording}/truth.csv: missing or malformed qw column ({e})")
    if not qw or not all(math.isfinite(q) and abs(q) <= 1.0 + 1e-6 for q in qw):
        sys.exit(f"{recording}/truth.csv: no rows, or a qw that is not a finite value in [-1, 1]")
    return len(qw), math.degrees(2.0 * math.acos(min(1.0, abs(qw[-1]))))


def read_index(dump):
    """The dump's sensors and frame count, after checking it is a field dump of this grid."""
    try:
        with open(f"{dump}/index.json") as f:
            index = json.load(f)
        grid = index["grid"]
        if index["format"] != "tacse3-fields" or grid["width"] * grid["height"] != CELLS:
            raise ValueError(f"format {index['format']!r}, grid {grid['width']}x{grid['height']}")
        return list(index["sensors"]), int(index["frames"])
    except OSError as e:
        sys.exit(f"{dump}: not a tacse3-replay --dump-fields folder ({e.strerror})")
    except (KeyError, TypeError, ValueError) as e:
        sys.exit(f"{dump}/index.json: not a tacse3-fields index of a {CELLS}-cell grid ({e})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dump", help="tacse3-replay --dump-fields folder")
    ap.add_argument("recording", help="the recording it was replayed from (truth.csv)")
    ap.add_argument("--fractions", type=float, nargs="+", default=[0.0, 0.5, 0.7],
                    help="core thresholds as fractions of the patch's largest filter(f^z)")
    args = ap.parse_args()
    if any(not 0.0 <= f < 1.0 for f in args.fractions):
        sys.exit("--fractions must lie in [0, 1)")
    sensors, frames = read_index(args.dump)
    truth_rows, angle = read_truth(args.recording)
    if truth_rows != frames:
        sys.exit(f"{args.dump}: {frames} frames, but {args.recording}/truth.csv has {truth_rows} "
                 f"rows: a dump of another recording?")
    if angle < 1e-6:
        sys.exit(f"{args.recording}: the truth ends unrotated; this reads rotations only")
    start = motion_start_after_rest(args.recording)
    print(f"{args.recording}: truth rotation {angle:.2f} deg, motion from frame {start}")
    for pad in sensors:
        try:
            mask, shape = load_npy(f"{args.dump}/{pad}/mask.npy")
            force, _ = load_npy(f"{args.dump}/{pad}/force.npy")
            fz, _ = load_npy(f"{args.dump}/{pad}/fz_filtered.npy")
        except OSError as e:
            sys.exit(f"{args.dump}/{pad}: cannot read the fields ({e})")
        if not (len(mask) == len(fz) == frames * CELLS and len(force) == 3 * frames * CELLS):
            sys.exit(f"{args.dump}/{pad}: the fields do not hold {frames} frames of {CELLS} cells")
        anchor = (start - 1) * CELLS
        patch = [k for k in range(CELLS) if mask[anchor + k]]
        if not patch:
            print(f"  {pad}: no contact before the motion")
            continue
        peak = max(fz[anchor + k] for k in patch)
        parts = []
        for fraction in args.fractions:
            core = [k for k in patch if fz[anchor + k] >= fraction * peak]
            total = [0.0, 0.0]
            for n in range(start, shape[0]):
                for i in range(2):
                    total[i] += sum(force[(n * CELLS + k) * 3 + i] for k in core) / len(core)
            parts.append(f"f^z >= {fraction:g} peak: {len(core)} cells, "
                         f"{math.hypot(*total) / angle:.3f} per deg")
        print(f"  {pad}: " + "; ".join(parts))


if __name__ == "__main__":
    main()
