#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: how much of a simulated slide the gel's shear cannot show (the observability bound).
"""Reads a tacse3-sim slide recording (recording.json's "sim" block and truth.csv) and replays
the simulator's slide law at each pad's deepest contact point (docs/simulator.md §6):

    tau dU/dt = c v_s - U,   |U| <= mu kappa d

with v_s the in-plane velocity of the object's surface there (from the truth pose), c =
drag_time_s, tau = lag_time_s, mu = the object's friction, kappa = shear_compliance and d the
indentation. The pads are force-controlled, so the deepest point is the object's surface at
z = +-(W/2 + d) on the grasp axis: W/2 + d is the lever of a rotation about the grasp centre
(exact for a centred sphere; for shapes whose height changes as they turn, an approximation).
While the shear is held at the cap it reads as if the surface moved at cap / c, so the motion
beyond that speed leaves no trace in the shear: the script sums it (mm) and, for a rotation
about an in-plane axis (rx, ry), turns it into degrees with the lever.

Why this bounds what the shear of the whole patch cannot show, in an in-plane rotation (rx, ry)
or a translation (tx, ty): a cell where the object is d' deep slides at v - omega (d - d') (the
same v in a translation) and its cap is mu kappa d', so the speed it cannot show exceeds the
deepest point's by (d - d') (mu kappa / c - omega) >= 0 while omega < mu kappa / c (18 rad/s at
the preset); and it is capped whenever the deepest point is (its shear plus mu kappa (d - d')
follows the same capped law with a drive of at least c v). No estimator that reads the shear,
without a prior on the motion, recovers it. (The pipeline reads a slide's translation from the
mask centroid, not from the shear.) In a
torsion (rz) the deepest point of a centred object does not slide and the figure is 0: it says
nothing there. The ODE is solved exactly per sub-step for the frame interval's mean velocity,
with the cap applied after each sub-step (--substeps per frame interval; the simulator takes
sub-steps of at most tau/4 with the twist at their midpoint, one per frame at 120 fps).

Usage: friction_cap_bound.py REC_DIR [--substeps 20]
"""
import argparse
import csv
import json
import math
import sys


def fail(message):
    sys.exit(f"friction_cap_bound: {message}")


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


def positive(value, name):
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a positive number, got {value!r}")
    return float(value)


def load(rec):
    """Returns (parameters, truth rows as (t_s, q, p_mm))."""
    try:
        with open(f"{rec}/recording.json") as f:
            meta = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{rec}: cannot read recording.json ({e})")
    sim = meta.get("sim") if isinstance(meta, dict) else None
    if not isinstance(sim, dict) or not isinstance(sim.get("gel"), dict):
        fail(f"{rec}: recording.json has no simulator block (not a tacse3-sim recording)")
    if sim.get("regime") != "slide":
        fail(f"{rec}: recording.json's sim.regime is {sim.get('regime', 'missing')!r}: only the "
             f"slide regime has a friction cap")
    try:
        gel = sim["gel"]
        prm = {"c": positive(gel["drag_time_s"], "gel.drag_time_s"),
               "tau": positive(gel["lag_time_s"], "gel.lag_time_s"),
               "kappa": positive(gel["shear_compliance"], "gel.shear_compliance"),
               "mu": positive(sim["friction"], "friction"),
               "d": positive(sim["indentation_mm"], "indentation_mm"),
               "w": positive(meta["rig"]["finger_separation_mm"], "rig.finger_separation_mm")}
    except (KeyError, TypeError) as e:
        fail(f"{rec}: recording.json: missing or malformed key {e}")
    except ValueError as e:
        fail(f"{rec}: recording.json: {e}")
    prm["motion"] = sim.get("motion") if isinstance(sim.get("motion"), dict) else {}
    prm["object"] = sim.get("object", "?")
    truth = []
    try:
        with open(f"{rec}/truth.csv") as f:
            for n, r in enumerate(csv.DictReader(f), start=2):
                t = int(r["t_ns"]) * 1e-9
                q = tuple(float(r[k]) for k in ("qw", "qx", "qy", "qz"))
                p = tuple(float(r[k]) * 1e3 for k in ("px", "py", "pz"))
                if not all(math.isfinite(x) for x in q + p):
                    fail(f"{rec}/truth.csv:{n}: a value is not finite")
                if abs(math.sqrt(sum(x * x for x in q)) - 1.0) > 1e-3:
                    fail(f"{rec}/truth.csv:{n}: the quaternion is not a unit quaternion")
                if truth and t <= truth[-1][0]:
                    fail(f"{rec}/truth.csv:{n}: t_ns does not increase")
                truth.append((t, q, p))
    except OSError as e:
        fail(f"{rec}: cannot read truth.csv ({e.strerror})")
    except (KeyError, TypeError, ValueError) as e:
        fail(f"{rec}/truth.csv: missing or malformed column ({e})")
    if len(truth) < 2:
        fail(f"{rec}: truth.csv has fewer than two rows")
    return prm, truth


def unseen_at(z, prm, truth, substeps):
    """Slides the law at the object's surface point over (0, 0, z) in G; returns
    (peak speed mm/s, seconds at the cap, motion beyond the cap speed in mm)."""
    cap = prm["mu"] * prm["kappa"] * prm["d"]
    c, tau = prm["c"], prm["tau"]
    u = [0.0, 0.0]
    unseen = peak = capped_s = 0.0
    for (t0, q0, p0), (t1, q1, p1) in zip(truth, truth[1:]):
        dt = t1 - t0
        w = spatial_rate(q0, q1, dt)
        mid = tuple((a + b) / 2 for a, b in zip(p0, p1))
        pdot = tuple((b - a) / dt for a, b in zip(p0, p1))
        # The velocity of the object's material point at x is pdot + w x (x - p).
        v = tuple(pd + wr for pd, wr in zip(pdot, cross(w, (-mid[0], -mid[1], z - mid[2]))))
        speed = math.hypot(v[0], v[1])
        peak = max(peak, speed)
        h = dt / substeps
        decay = math.exp(-h / tau)
        for _ in range(substeps):
            u = [c * v[i] + (u[i] - c * v[i]) * decay for i in range(2)]
            mag = math.hypot(u[0], u[1])
            if mag > cap:
                u = [x * cap / mag for x in u]
                unseen += max(0.0, speed - cap / c) * h
                capped_s += h
    return peak, capped_s, unseen


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rec", help="a tacse3-sim recording directory (slide regime)")
    ap.add_argument("--substeps", type=int, default=20,
                    help="exact ODE steps per frame interval (default 20)")
    args = ap.parse_args()
    if args.substeps < 1:
        fail("--substeps must be at least 1")
    prm, truth = load(args.rec)
    cap = prm["mu"] * prm["kappa"] * prm["d"]
    lever = prm["w"] / 2.0 + prm["d"]
    motion = prm["motion"]
    in_plane_rotation = motion.get("axis") in ("rx", "ry")
    print(f"{args.rec}: {prm['object']} {motion.get('axis')} {motion.get('magnitude')} "
          f"{motion.get('unit')}, friction {prm['mu']:g}, cap mu*kappa*d = {cap:.3f} mm at the "
          f"deepest point, shear at the cap for a surface speed of {cap / prm['c']:.2f} mm/s")
    for name, z in (("left", lever), ("right", -lever)):
        peak, capped_s, unseen = unseen_at(z, prm, truth, args.substeps)
        line = (f"  {name} pad, deepest point: peak surface speed {peak:.2f} mm/s, at the cap "
                f"for {capped_s:.3f} s, motion beyond the cap speed {unseen:.3f} mm")
        if in_plane_rotation:
            line += (f" = {math.degrees(unseen / lever):.2f} deg of rotation "
                     f"(lever {lever:g} mm)")
        print(line)


if __name__ == "__main__":
    main()
