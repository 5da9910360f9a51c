#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: how much of a simulated slide no reading of the gel's shear can see (docs/accuracy.md item 2).
"""Reads a tacse3-sim recording (recording.json's "sim" block and truth.csv) and replays the
simulator's slide law at each pad's contact centre (docs/simulator.md §6):

    tau dU/dt = c v_s - U,   |U| <= mu kappa d

with v_s the in-plane velocity of the object's surface over the pad centre (from the truth pose),
c = drag_time_s, tau = lag_time_s, mu = the object's friction, kappa = shear_compliance and d the
indentation. While the shear is held at the cap it reads as if the surface moved at cap / c, so
the motion beyond that speed leaves no trace in the shear: the script sums it (mm), and for a
rotation turns it into degrees with the lever W/2 (the pad centre's distance from the grasp
centre).

The pad centre has the deepest indentation and so the highest cap of the patch; in an in-plane
rotation or a translation every cell of the patch slides at about the same speed, so the figure
is a lower bound on what any estimator reading the shear misses (without a prior on the motion).
In a torsion (rz) the centre does not slide and the bound is 0: it says nothing there.

Usage: friction_cap_bound.py REC_DIR [--substeps 20]
"""
import argparse
import csv
import json
import math
import sys


def quat_mul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def spatial_rate(q0, q1, dt):
    """Angular velocity (rad/s, in G) taking q0 to q1 in dt: q1 q0^-1 = exp(w dt / 2)."""
    d = quat_mul(q1, (q0[0], -q0[1], -q0[2], -q0[3]))
    if d[0] < 0:
        d = tuple(-x for x in d)
    s = math.sqrt(d[1] ** 2 + d[2] ** 2 + d[3] ** 2)
    if s < 1e-15:
        return (0.0, 0.0, 0.0)
    angle = 2.0 * math.atan2(s, d[0])
    return tuple(angle / dt * x / s for x in d[1:])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def load(rec):
    try:
        meta = json.load(open(f"{rec}/recording.json"))
    except (OSError, ValueError) as e:
        sys.exit(f"{rec}: cannot read recording.json ({e})")
    sim = meta.get("sim")
    if not isinstance(sim, dict) or "gel" not in sim:
        sys.exit(f"{rec}: recording.json has no simulator block (not a tacse3-sim recording)")
    try:
        rows = list(csv.DictReader(open(f"{rec}/truth.csv")))
        truth = [(int(r["t_ns"]) * 1e-9,
                  (float(r["qw"]), float(r["qx"]), float(r["qy"]), float(r["qz"])),
                  (float(r["px"]) * 1e3, float(r["py"]) * 1e3, float(r["pz"]) * 1e3))
                 for r in rows]
    except (OSError, KeyError, ValueError) as e:
        sys.exit(f"{rec}: cannot read truth.csv ({e})")
    if len(truth) < 2:
        sys.exit(f"{rec}: truth.csv has fewer than two rows")
    return meta, sim, truth


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rec")
    ap.add_argument("--substeps", type=int, default=20, help="ODE steps per frame interval")
    a = ap.parse_args()
    meta, sim, truth = load(a.rec)
    gel = sim["gel"]
    c, tau = gel["drag_time_s"], gel["lag_time_s"]
    cap = sim["friction"] * gel["shear_compliance"] * sim["indentation_mm"]
    half_w = meta["rig"]["finger_separation_mm"] / 2.0
    motion = sim.get("motion", {})
    rotation = motion.get("unit") == "deg"
    print(f"{a.rec}: {sim.get('object')} {motion.get('axis')} {motion.get('magnitude')} "
          f"{motion.get('unit')}, friction {sim['friction']}, cap mu*kappa*d = {cap:.3f} mm at the "
          f"pad centre, shear at the cap for a surface speed of {cap / c:.2f} mm/s")
    for name, z in (("left", half_w), ("right", -half_w)):
        u = [0.0, 0.0]
        unseen = peak = capped_s = 0.0
        for (t0, q0, p0), (t1, q1, p1) in zip(truth, truth[1:]):
            dt = t1 - t0
            w = spatial_rate(q0, q1, dt)
            pm = tuple((x0 + x1) / 2 for x0, x1 in zip(p0, p1))
            pdot = tuple((x1 - x0) / dt for x0, x1 in zip(p0, p1))
            # Velocity of the object's material point over the pad centre (0, 0, z) in G.
            r = (-pm[0], -pm[1], z - pm[2])
            v = tuple(pd + wr for pd, wr in zip(pdot, cross(w, r)))
            speed = math.hypot(v[0], v[1])
            peak = max(peak, speed)
            h = dt / a.substeps
            decay = math.exp(-h / tau)
            for _ in range(a.substeps):
                u = [c * v[i] + (u[i] - c * v[i]) * decay for i in range(2)]
                mag = math.hypot(u[0], u[1])
                if mag > cap:
                    u = [x * cap / mag for x in u]
                    unseen += max(0.0, speed - cap / c) * h
                    capped_s += h
        line = (f"  {name} pad centre: peak surface speed {peak:.2f} mm/s, at the cap for "
                f"{capped_s:.3f} s, motion beyond the cap speed {unseen:.3f} mm")
        if rotation:
            line += f" = {math.degrees(unseen / half_w):.2f} deg of rotation (lever {half_w:g} mm)"
        print(line)


if __name__ == "__main__":
    main()
