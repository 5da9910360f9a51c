#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: summary of robustness_sweep.sh output, and the change between two sweeps (docs/accuracy.md item 8).
"""Reads the lines robustness_sweep.sh prints (`name estimated_deg rotation_error_deg
estimated_mm translation_error_mm`, or `name FAILED reason`) and prints: the stick recordings
(rotations up to 5 deg, translations up to 1 mm, as `--regime auto` renders them) with their
worst rotation error, their sum and how many are under 0.2 deg; the slide recordings' summed
rotation error and summed translation error; and the failures. Given a second file (the same
sweep after a change), it prints both summaries and every recording whose rotation error moved by
more than --min-change deg, largest change first.

Usage: sweep_summary.py SWEEP_OUT [SWEEP_OUT_AFTER] [--min-change 0.5]
"""
import argparse
import re
import sys

STICK_DEG, STICK_MM = 5.0, 1.0


def read(path):
    rows, failed = {}, []
    try:
        f = open(path)
    except OSError as e:
        sys.exit(f"{path}: cannot read ({e.strerror})")
    with f:
        for line in f:
            parts = line.split()
            if not parts or parts[0] in ("real", "user", "sys"):
                continue
            if len(parts) >= 2 and parts[1] == "FAILED":
                failed.append(parts[0])
                continue
            if len(parts) != 5:
                continue  # not a sweep line (a shell's timing, a blank)
            m = re.search(r"_(rx|ry|rz|tx|ty)([0-9.]+)", parts[0])
            if not m:
                sys.exit(f"{path}: cannot tell the motion of '{parts[0]}'")
            axis, magnitude = m.group(1), float(m.group(2))
            stick = magnitude <= (STICK_DEG if axis[0] == "r" else STICK_MM)
            rows[parts[0]] = (stick, float(parts[2]), float(parts[4]))
    if not rows and not failed:
        sys.exit(f"{path}: no sweep lines")
    return rows, failed


def summary(label, rows, failed):
    sticks = [(e, n) for n, (s, e, _) in rows.items() if s]
    slides = [(e, t, n) for n, (s, e, t) in rows.items() if not s]
    worst = max(sticks) if sticks else (float("nan"), "-")
    print(f"{label}: {len(rows)} recordings, {len(failed)} failed {failed if failed else ''}")
    under = sum(1 for e, _ in sticks if e < 0.2)
    print(f"  sticks {len(sticks)}: worst {worst[0]:.2f} deg ({worst[1]}), sum "
          f"{sum(e for e, _ in sticks):.2f} deg, {under} under 0.2 deg")
    print(f"  slides {len(slides)}: rotation errors summed {sum(e for e, _, _ in slides):.2f} deg, "
          f"translation errors summed {sum(t for _, t, _ in slides):.2f} mm")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before")
    ap.add_argument("after", nargs="?")
    ap.add_argument("--min-change", type=float, default=0.5)
    a = ap.parse_args()
    rows, failed = read(a.before)
    summary(a.before, rows, failed)
    if a.after is None:
        return
    rows2, failed2 = read(a.after)
    summary(a.after, rows2, failed2)
    changes = [(rows2[n][1] - rows[n][1], n) for n in rows if n in rows2]
    changes = [c for c in changes if abs(c[0]) > a.min_change]
    for d, n in sorted(changes, key=lambda c: -abs(c[0])):
        print(f"  {n:28s} {rows[n][1]:7.2f} -> {rows2[n][1]:7.2f} deg ({d:+.2f})")


if __name__ == "__main__":
    main()
