#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: copy a recording with its clock moved on from one frame, a gap in the stream.
"""Copies recording SRC to DST (which must not exist) and adds GAP_S seconds to the time of every
frame from index FRAME on, in frames.csv and in truth.csv alike; the images are untouched, so the
frames continue where they were and only the one increment across the gap is missing. Replaying
DST then exercises the pipeline's frame-gap restart (docs/dsp.md §4.2c).

Usage: frame_gap.py SRC DST FRAME [--gap-s 0.2]
"""
import argparse
import csv
import os
import shutil
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("frame", type=int)
    ap.add_argument("--gap-s", type=float, default=0.2)
    a = ap.parse_args()
    if os.path.exists(a.dst):
        sys.exit(f"frame_gap: {a.dst} exists; choose a new folder")
    with open(os.path.join(a.src, "frames.csv"), newline="") as f:
        frames = list(csv.reader(f))
    if frames[0] != ["index", "t_ns"] or not 0 < a.frame < len(frames) - 1:
        sys.exit(f"frame_gap: {a.src}/frames.csv: need the header index,t_ns and frame 1..{len(frames) - 2}")
    t_from = int(frames[a.frame + 1][1])
    gap_ns = round(a.gap_s * 1e9)
    shutil.copytree(a.src, a.dst)
    for name, col in (("frames.csv", 1), ("truth.csv", 0)):
        path = os.path.join(a.dst, name)
        if not os.path.exists(path):
            continue
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        for r in rows[1:]:
            if int(r[col]) >= t_from:
                r[col] = str(int(r[col]) + gap_ns)
        with open(path, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)


if __name__ == "__main__":
    main()
