#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: the contact mask's centroid over a replay, and what the mask-change gate keeps of it.
"""Reads a `tacse3-replay --dump-fields DIR` folder (standard library only, no NumPy) and prints,
per pad: the sum of the mask centroid's per-frame steps (x, y in the pad's image axes, mm) over
all frames in contact, the sum over the frames whose mask change 1 - |common| / |union| is at or
below --gate (what the sliding translation rule kept with that `max_mask_change`), how many frames
exceeded it, and, at the first and last frame in contact, the mask centroid, the number of cells
of each connected component of the mask, the centroid of the largest component alone, the
centroid weighted by the contact points' height z, and (with --recording, a simulator recording
holding sim_labels.csv) the simulator's true patch centroid. With --frames, the same z-weighted
centroid at each listed frame against the simulator's, with the mask's size and how many of its
cells lie within --border grid cells of the pad's edge (docs/accuracy.md item 5). It also prints
the largest area ratio between consecutive masks (larger cell count over smaller) and how many
frames exceed --area-ratio (`max_mask_area_ratio`), per simulator phase with --recording.

Usage: mask_centroid.py DIR [--gate 0.3] [--area-ratio 1.5] [--recording REC_DIR]
                        [--frames 72,239 [--border 3]]
(docs/dsp.md section 4.1)
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from torsion_increments import CELLS, GRID_H, GRID_W, load_npy  # noqa: E402


def components(cells):
    """The 4-connected components of a set of grid indices (lists of indices), largest first."""
    seen, found = set(), []
    for start in cells:
        if start in seen:
            continue
        seen.add(start)
        stack, comp = [start], []
        while stack:
            k = stack.pop()
            comp.append(k)
            x, y = k % GRID_W, k // GRID_W
            for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
                q = ny * GRID_W + nx
                if 0 <= nx < GRID_W and 0 <= ny < GRID_H and q in cells and q not in seen:
                    seen.add(q)
                    stack.append(q)
        found.append(comp)
    return sorted(found, key=len, reverse=True)


def sim_labels(recording, pad):
    """The simulator's per-frame patch centroid (mm) and phase for one pad, from sim_labels.csv."""
    centroids, phases = {}, {}
    with open(os.path.join(recording, "sim_labels.csv"), newline="") as f:
        for row in csv.DictReader(f):
            if row["sensor"] == pad:
                n = int(row["index"])
                centroids[n] = (float(row["centroid_u_mm"]), float(row["centroid_v_mm"]))
                phases[n] = row["phase"]
    return centroids, phases


def centroid_mm(points, n, cells, weighted=False):
    """Mask centroid (x, y, mm) of frame n over cells; weighted: by the contact point's height z
    (the indentation estimate from f^z), as the sliding translation rule weights it."""
    w = [points[3 * (n * CELLS + i) + 2] if weighted else 1.0 for i in cells]
    total = sum(w) or 1.0
    sx = sum(wi * points[3 * (n * CELLS + i)] for wi, i in zip(w, cells))
    sy = sum(wi * points[3 * (n * CELLS + i) + 1] for wi, i in zip(w, cells))
    return sx / total * 1e3, sy / total * 1e3


def frame_report(folder, pad, recording, frames, border):
    """Per listed frame: the z-weighted mask centroid against the simulator's patch centroid."""
    mask, shape = load_npy(f"{folder}/{pad}/mask.npy")
    points, _ = load_npy(f"{folder}/{pad}/points.npy")
    truth = sim_labels(recording, pad)[0] if recording else {}
    for n in frames:
        if not 0 <= n < shape[0]:
            print(f"{pad}: frame {n} is not in the dump ({shape[0]} frames)")
            continue
        cells = [i for i in range(CELLS) if mask[n * CELLS + i]]
        if not cells:
            print(f"{pad}: frame {n}: no contact")
            continue
        c = centroid_mm(points, n, cells, weighted=True)
        at_edge = sum(1 for i in cells
                      if min(i % GRID_W, GRID_W - 1 - i % GRID_W,
                             i // GRID_W, GRID_H - 1 - i // GRID_W) < border)
        line = (f"{pad}: frame {n}: z-weighted centroid ({c[0]:.3f}, {c[1]:.3f}) mm, "
                f"{len(cells)} cells, {at_edge} within {border} of the edge")
        if n in truth:
            line += (f", simulator ({truth[n][0]:.3f}, {truth[n][1]:.3f}) mm, "
                     f"difference ({c[0] - truth[n][0]:+.3f}, {c[1] - truth[n][1]:+.3f}) mm")
        print(line)


def pad_report(folder, pad, gate, area_bound, recording):
    mask, shape = load_npy(f"{folder}/{pad}/mask.npy")
    points, _ = load_npy(f"{folder}/{pad}/points.npy")
    frames = shape[0]
    truth, phases = sim_labels(recording, pad) if recording else ({}, {})
    ratios = {}  # phase -> (largest area ratio, frames above area_bound)

    def cells_of(n):
        return {i for i in range(CELLS) if mask[n * CELLS + i]}

    all_steps, kept_steps = [0.0, 0.0], [0.0, 0.0]
    over_gate = 0
    prev, prev_c = None, None
    first = last = None
    for n in range(frames):
        cells = cells_of(n)
        if not cells:
            prev = None
            continue
        c = centroid_mm(points, n, cells)
        if first is None:
            first = (n, cells, c)
        last = (n, cells, c)
        if prev:
            common = len(cells & prev)
            if common:  # the rule reads no translation when the masks share no cell
                ratio = max(len(cells), len(prev)) / min(len(cells), len(prev))
                phase = phases.get(n, "unlabelled") if recording else "all frames"
                top, above = ratios.get(phase, (1.0, 0))
                ratios[phase] = (max(top, ratio), above + (ratio > area_bound))
            change = 1.0 - common / len(cells | prev)
            for k in range(2):
                all_steps[k] += c[k] - prev_c[k]
                if change <= gate:
                    kept_steps[k] += c[k] - prev_c[k]
            if change > gate:
                over_gate += 1
        prev, prev_c = cells, c
    if first is None:
        print(f"{pad}: no frame in contact")
        return
    print(f"{pad}: centroid steps summed over all frames in contact: "
          f"({all_steps[0]:.3f}, {all_steps[1]:.3f}) mm")
    print(f"{pad}: summed over frames with mask change <= {gate}: "
          f"({kept_steps[0]:.3f}, {kept_steps[1]:.3f}) mm; {over_gate} frame(s) above it")
    for phase, (top, above) in ratios.items():
        print(f"{pad}: {phase}: largest area ratio between consecutive masks {top:.2f}, "
              f"{above} frame(s) above {area_bound}")
    for label, (n, cells, c) in (("first", first), ("last", last)):
        comps = components(cells)
        big = centroid_mm(points, n, comps[0])
        zw = centroid_mm(points, n, cells, weighted=True)
        line = (f"{pad}: {label} frame in contact {n}: mask centroid ({c[0]:.3f}, {c[1]:.3f}) mm, "
                f"components {[len(k) for k in comps]}, largest component's centroid "
                f"({big[0]:.3f}, {big[1]:.3f}) mm, z-weighted centroid ({zw[0]:.3f}, {zw[1]:.3f}) mm")
        if n in truth:
            line += f", simulator patch centroid ({truth[n][0]:.3f}, {truth[n][1]:.3f}) mm"
        print(line)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", help="tacse3-replay --dump-fields folder")
    ap.add_argument("--gate", type=float, default=0.3, help="max_mask_change to evaluate")
    ap.add_argument("--area-ratio", type=float, default=1.5,
                    help="max_mask_area_ratio to count frames against")
    ap.add_argument("--recording", help="the replayed simulator recording (for sim_labels.csv)")
    ap.add_argument("--frames", help="comma-separated frame indices: the centroid at each instead")
    ap.add_argument("--border", type=int, default=3, help="edge band for --frames, grid cells")
    a = ap.parse_args()
    try:
        frames = [int(f) for f in a.frames.split(",")] if a.frames else None
    except ValueError:
        sys.exit(f"mask_centroid.py: --frames {a.frames!r}: expected comma-separated integers")
    for pad in ("left", "right"):
        if not os.path.exists(f"{a.dir}/{pad}/mask.npy"):
            continue
        if frames is not None:
            frame_report(a.dir, pad, a.recording, frames, a.border)
        else:
            pad_report(a.dir, pad, a.gate, a.area_ratio, a.recording)


if __name__ == "__main__":
    main()
