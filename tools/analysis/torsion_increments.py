#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: torsion of the dumped fields vs the summed per-frame increments (docs/accuracy.md).
"""Reads a `tacse3-replay --dump-fields DIR` folder (standard library only, no NumPy) and prints,
per pad: the least-squares torsion of the raw flow, the smoothed field and the NHHD part r in the
last frame's contact mask; the torsion of the calibrated shear's per-frame increments summed over
all frames, once over the cells in the current mask and once over the cells in both the current
and the previous mask; the summed mean shear increment over both cell sets; and how many cells entered the mask, how
many of those the flow had not tracked the frame before, and their median increment.

Usage: torsion_increments.py DIR [--pitch-mm 0.1]   (the recording's rig.pixel_pitch_mm)
"""
import argparse
import array
import ast
import math
import struct
import sys

GRID_W, GRID_H = 40, 30
CELLS = GRID_W * GRID_H


def load_npy(path):
    data = open(path, "rb").read()
    if data[:6] != b"\x93NUMPY":
        sys.exit(f"{path}: not a .npy file")
    header_len = struct.unpack("<H", data[8:10])[0]
    header = ast.literal_eval(data[10:10 + header_len].decode("latin1"))
    codes = {"<f4": "f", "|u1": "B", "<u1": "B", "<i8": "q"}
    if header["descr"] not in codes or header["fortran_order"]:
        sys.exit(f"{path}: unsupported dtype {header['descr']}")
    values = array.array(codes[header["descr"]])
    values.frombytes(data[10 + header_len:])
    return values, header["shape"]


def torsion(points):
    """Least-squares rotation of (x, y, ux, uy) samples about their centroid: sum of cross terms
    over the polar moment. Units: those of u per unit of x."""
    if len(points) < 3:
        return 0.0
    n = len(points)
    cx = sum(p[0] for p in points) / n
    cy = sum(p[1] for p in points) / n
    mx = sum(p[2] for p in points) / n
    my = sum(p[3] for p in points) / n
    num = sum((p[0] - cx) * (p[3] - my) - (p[1] - cy) * (p[2] - mx) for p in points)
    den = sum((p[0] - cx) ** 2 + (p[1] - cy) ** 2 for p in points)
    return num / den if den > 0 else 0.0


def pad_report(folder, pad, metres_per_working_px):
    d = f"{folder}/{pad}"
    mask, shape = load_npy(f"{d}/mask.npy")
    frames = shape[0]
    flow, _ = load_npy(f"{d}/flow.npy")
    flow_valid, _ = load_npy(f"{d}/flow_valid.npy")
    smoothed, _ = load_npy(f"{d}/displacement.npy")
    r_part, _ = load_npy(f"{d}/r.npy")
    force, _ = load_npy(f"{d}/force.npy")
    points, _ = load_npy(f"{d}/points.npy")

    last = frames - 1

    def field_torsion_deg(field, valid=None):
        samples = []
        for gy in range(GRID_H):
            for gx in range(GRID_W):
                i = last * CELLS + gy * GRID_W + gx
                if not mask[i] or (valid is not None and not valid[i]):
                    continue
                # Sensor pixels, pad centre at (159.5, 119.5); the fields are in sensor pixels.
                x, y = 8 * gx + 3.5 - 159.5, 8 * gy + 3.5 - 119.5
                samples.append((x, y, field[2 * i], field[2 * i + 1]))
        return math.degrees(torsion(samples))

    entering = untracked_before = 0
    increment_entering, increment_staying = [], []
    summed = {"current": 0.0, "both": 0.0}
    mean_sum = {"current": [0.0, 0.0], "both": [0.0, 0.0]}
    for n in range(1, frames):
        sets = {"current": [], "both": []}
        for j in range(CELLS):
            i, ip = n * CELLS + j, (n - 1) * CELLS + j
            if not mask[i]:
                continue
            # Shear in working px (force.npy f^x, f^y), points in metres.
            s = (points[3 * i], points[3 * i + 1],
                 force[3 * i] - force[3 * ip], force[3 * i + 1] - force[3 * ip + 1])
            sets["current"].append(s)
            size = math.hypot(s[2], s[3])
            if mask[ip]:
                sets["both"].append(s)
                increment_staying.append(size)
            else:
                entering += 1
                untracked_before += 0 if flow_valid[ip] else 1
                increment_entering.append(size)
        for key, samples in sets.items():
            if not samples:
                continue
            summed[key] += torsion(samples) * metres_per_working_px
            for k in range(2):
                mean_sum[key][k] += sum(p[2 + k] for p in samples) / len(samples)

    print(f"{pad}: last-frame torsion (deg): raw flow {field_torsion_deg(flow, flow_valid):.2f}, "
          f"smoothed {field_torsion_deg(smoothed):.2f}, r {field_torsion_deg(r_part):.2f}")
    print(f"{pad}: summed increment torsion (deg): over the current mask "
          f"{math.degrees(summed['current']):.2f}, over current and previous mask "
          f"{math.degrees(summed['both']):.2f}")
    def median(values):
        return sorted(values)[len(values) // 2] if values else float("nan")

    print(f"{pad}: {entering} cell-frames entered the mask, {untracked_before} of them not tracked "
          f"by the flow the frame before; median |shear increment| entering "
          f"{median(increment_entering):.3f}, staying {median(increment_staying):.3f} working px")
    print(f"{pad}: summed mean shear increment (working px): current mask "
          f"({mean_sum['current'][0]:.3f}, {mean_sum['current'][1]:.3f}), current and previous "
          f"({mean_sum['both'][0]:.3f}, {mean_sum['both'][1]:.3f})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", help="tacse3-replay --dump-fields folder")
    ap.add_argument("--pitch-mm", type=float, default=0.1,
                    help="rig pixel pitch (mm per sensor px); one working px is two sensor px")
    a = ap.parse_args()
    for pad in ("left", "right"):
        try:
            pad_report(a.dir, pad, 2.0 * a.pitch_mm * 1e-3)
        except FileNotFoundError:
            continue


if __name__ == "__main__":
    main()
