#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: where the untracked flow points, the radial bulge and the density G sit in one frame.
"""Reads a `tacse3-replay --dump-fields DIR` folder (standard library only, no NumPy) and prints,
per pad, for one frame (positions in mm in the pad's image axes, from the pad centre):

- how many flow points were not tracked, and their centroid;
- the centre of the radial bulge fitted to the raw flow and to the smoothed displacement within
  --radius sensor px of the pad centre (least squares u = a (p - c));
- the centroids of the positive and negative lobes of the dumped density G, and of the mask;
- the largest difference between the dumped G and a double-precision recomputation of
  dsp::GaussianDensity (sigma 1 grid cell, cut at 3 sigma, normalised by the undeformed density)
  from the dumped smoothed displacement, i.e. whether an offset of G comes from the arithmetic
  or from the field.

Usage: density_offset.py DIR FRAME [--radius 60]   (docs/accuracy.md item 8)
"""
import argparse
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from torsion_increments import CELLS, GRID_H, GRID_W, load_npy  # noqa: E402

STRIDE_SENSOR_PX = 8.0  # grid stride (index.json: stride_sensor_px)
X0_SENSOR_PX = 3.5
CENTRE = (159.5, 119.5)
SIGMA_WORKING_PX = 4.0  # dsp::DensityConfig::sigma_cells = 1 cell of 4 working px
CUT_SIGMAS = 3.0


def position(k):
    """Grid point k in sensor px from the pad centre."""
    gx, gy = k % GRID_W, k // GRID_W
    return X0_SENSOR_PX + STRIDE_SENSOR_PX * gx - CENTRE[0], X0_SENSOR_PX + STRIDE_SENSOR_PX * gy - CENTRE[1]


def radial_centre(samples):
    """Least squares u = a (p - c) over (x, y, ux, uy) samples: (a, cx, cy) or None."""
    n = len(samples)
    if n < 3:
        return None
    sx = sum(s[0] for s in samples)
    sy = sum(s[1] for s in samples)
    spp = sum(s[0] ** 2 + s[1] ** 2 for s in samples)
    su = sum(s[2] for s in samples)
    sv = sum(s[3] for s in samples)
    spu = sum(s[0] * s[2] + s[1] * s[3] for s in samples)
    # Unknowns a, bx, by with u = a p + b: normal equations, eliminated in closed form.
    den = spp - (sx * sx + sy * sy) / n
    if den <= 0.0:
        return None
    a = (spu - (sx * su + sy * sv) / n) / den
    if a == 0.0:
        return None
    bx = (su - a * sx) / n
    by = (sv - a * sy) / n
    return a, -bx / a, -by / a


def lobe_centroid(values, sign):
    sw = sx = sy = 0.0
    for k, v in enumerate(values):
        w = v * sign
        if w <= 0.0:
            continue
        x, y = position(k)
        sw += w
        sx += w * x
        sy += w * y
    return (sx / sw, sy / sw) if sw > 0.0 else None


def recomputed_density(disp, valid):
    """Double-precision G from the smoothed displacement (sensor px), as dsp::GaussianDensity."""
    k_cut = math.exp(-0.5 * CUT_SIGMAS ** 2)
    reach = CUT_SIGMAS * 1.0 + 0.5  # cells, as the fixed code's neighbour offsets

    def kernel(r2):
        t = r2 / (2.0 * SIGMA_WORKING_PX ** 2)
        return 0.0 if t >= 0.5 * CUT_SIGMAS ** 2 else (math.exp(-t) - k_cut) / (1.0 - k_cut)

    rmax = int(math.floor(reach))
    out = [0.0] * CELLS
    for k in range(CELLS):
        if not valid[k]:
            continue
        gx, gy = k % GRID_W, k // GRID_W
        d = d0 = 0.0
        for oy in range(-rmax, rmax + 1):
            for ox in range(-rmax, rmax + 1):
                if ox * ox + oy * oy > reach * reach:
                    continue
                x, y = gx + ox, gy + oy
                if not (0 <= x < GRID_W and 0 <= y < GRID_H):
                    continue
                q = y * GRID_W + x
                if not valid[q]:
                    continue
                bx, by = 4.0 * ox, 4.0 * oy  # working px
                dx = bx + (disp[2 * q] - disp[2 * k]) / 2.0
                dy = by + (disp[2 * q + 1] - disp[2 * k + 1]) / 2.0
                d += kernel(dx * dx + dy * dy)
                d0 += kernel(bx * bx + by * by)
        out[k] = d / d0 - 1.0 if d0 > 0.0 else 0.0
    return out


def mm(p, pitch):
    return "(%.2f, %.2f)" % (p[0] * pitch, p[1] * pitch) if p else "-"


def pad_report(folder, pad, frame, radius, pitch):
    flow, shape = load_npy(f"{folder}/{pad}/flow.npy")
    if not 0 <= frame < shape[0]:
        sys.exit(f"{folder}: frame {frame} outside 0..{shape[0] - 1}")
    flow_valid, _ = load_npy(f"{folder}/{pad}/flow_valid.npy")
    disp, _ = load_npy(f"{folder}/{pad}/displacement.npy")
    valid, _ = load_npy(f"{folder}/{pad}/valid.npy")
    density, _ = load_npy(f"{folder}/{pad}/density.npy")
    mask, _ = load_npy(f"{folder}/{pad}/mask.npy")
    base = frame * CELLS
    fv = flow_valid[base:base + CELLS]
    fl = flow[2 * base:2 * (base + CELLS)]
    va = valid[base:base + CELLS]
    dp = disp[2 * base:2 * (base + CELLS)]
    g = density[base:base + CELLS]
    m = mask[base:base + CELLS]

    lost = [position(k) for k in range(CELLS) if not fv[k]]
    lost_c = (sum(p[0] for p in lost) / len(lost), sum(p[1] for p in lost) / len(lost)) if lost else None

    def samples(field, ok):
        out = []
        for k in range(CELLS):
            x, y = position(k)
            if ok[k] and x * x + y * y <= radius * radius:
                out.append((x, y, field[2 * k], field[2 * k + 1]))
        return out

    raw = radial_centre(samples(fl, fv))
    smooth = radial_centre(samples(dp, va))
    cells = [k for k in range(CELLS) if m[k]]
    mask_c = (sum(position(k)[0] for k in cells) / len(cells),
              sum(position(k)[1] for k in cells) / len(cells)) if cells else None
    again = recomputed_density(dp, va)
    worst = max(abs(again[k] - g[k]) for k in range(CELLS))
    print(f"{pad}, frame {frame}:")
    print(f"  untracked flow points {len(lost)} of {CELLS}, centroid {mm(lost_c, pitch)} mm")
    print(f"  radial centre: raw flow {mm(raw[1:] if raw else None, pitch)} mm, smoothed "
          f"displacement {mm(smooth[1:] if smooth else None, pitch)} mm (within {radius:g} px)")
    print(f"  density G: negative lobe {mm(lobe_centroid(g, -1.0), pitch)} mm, positive lobe "
          f"{mm(lobe_centroid(g, 1.0), pitch)} mm; mask ({len(cells)} cells) {mm(mask_c, pitch)} mm")
    print(f"  dumped G vs a double recomputation from the smoothed displacement: max |diff| {worst:.1e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder")
    ap.add_argument("frame", type=int)
    ap.add_argument("--radius", type=float, default=60.0, help="sensor px around the pad centre")
    a = ap.parse_args()
    index = os.path.join(a.folder, "index.json")
    if not os.path.isfile(index):
        sys.exit(f"{a.folder}: no index.json (not a --dump-fields folder)")
    with open(index) as f:
        meta = json.load(f)
    pitch = float(meta.get("pixel_pitch_mm", 0.1))
    for pad in meta.get("sensors", []):
        pad_report(a.folder, pad, a.frame, a.radius, pitch)


if __name__ == "__main__":
    main()
