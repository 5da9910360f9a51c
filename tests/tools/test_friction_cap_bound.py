#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tools tests: tools/analysis/friction_cap_bound.py against the slide law's closed form.
"""The deepest point of each pad (the object's surface at z = +-(W/2 + d)) sliding at a constant
speed v from rest of the shear: U(t) = c v (1 - exp(-t/tau)) reaches the cap m = mu kappa d at
t* = -tau ln(1 - m/(c v)) and is held there, so the motion beyond the cap speed is
(v - m/c)(T - t*), and for a rotation that over the lever W/2 + d in degrees. Three motions give
v = 30 mm/s: a rotation about G x, a translation along G y (truth in metres), and a torsion about
an axis parallel to the grasp axis G z, 5 mm off it (v = 5 mm * w; it catches a wrong sign or
unit of the truth's position). Only the rotation about x is also given in degrees. Also: a
rotation slow enough to stay below the cap (0), a torsion about the centre (the deepest point
does not slide: 0), and clear errors (exit 1) for a folder that is not a simulator recording, a
stick recording, a missing key, a non-finite truth value and a truth whose time does not
increase.

Usage: test_friction_cap_bound.py SCRIPT
"""
import json
import math
import os
import re
import subprocess
import sys
import tempfile

FPS, W, C, TAU, MU, KAPPA, D = 120, 38.0, 0.05, 0.06, 0.6, 1.5, 1.0
LEVER = W / 2 + D


def axis_rotation(axis, angle):
    q = [math.cos(angle / 2), 0.0, 0.0, 0.0]
    q[1 + axis] = math.sin(angle / 2)
    return q


def write_recording(path, pose_at, seconds, regime="slide", axis="rx"):
    """pose_at(t) -> (quaternion [w, x, y, z], position in metres)."""
    os.makedirs(path)
    sim = {"object": "sphere", "friction": MU, "indentation_mm": D, "regime": regime,
           "motion": {"axis": axis, "magnitude": 1.0, "unit": "deg" if axis[0] == "r" else "mm"},
           "gel": {"drag_time_s": C, "lag_time_s": TAU, "shear_compliance": KAPPA}}
    meta = {"format": "tacse3-recording", "version": 1, "width": 320, "height": 240, "fps": FPS,
            "sensors": ["left", "right"],
            "rig": {"pixel_pitch_mm": 0.1, "finger_separation_mm": W, "layout": "mirrored"},
            "sim": sim}
    with open(f"{path}/recording.json", "w") as f:
        json.dump(meta, f)
    with open(f"{path}/truth.csv", "w") as f:
        f.write("t_ns,qw,qx,qy,qz,px,py,pz\n")
        for k in range(int(seconds * FPS) + 1):
            t = k / FPS
            q, p = pose_at(t)
            f.write(f"{round(t * 1e9)}," + ",".join(repr(x) for x in q + p) + "\n")


def run(script, path):
    return subprocess.run([sys.executable, script, path], capture_output=True, text=True)


def read_pads(script, path):
    """[(pad, mm, deg or None)] from the script's per-pad lines."""
    out = run(script, path)
    if out.returncode != 0:
        sys.exit(f"FAIL: {path}: exit {out.returncode}: {out.stderr}")
    found = re.findall(r"(left|right) pad.*motion beyond the cap speed ([0-9.]+) mm"
                       r"(?: = ([0-9.]+) deg)?", out.stdout)
    if len(found) != 2:
        sys.exit(f"FAIL: {path}: unexpected output:\n{out.stdout}")
    return [(pad, float(mm), float(deg) if deg else None) for pad, mm, deg in found]


def main():
    script = sys.argv[1]
    failures = 0

    def check(ok, what):
        nonlocal failures
        failures += not ok
        print(f"{'ok' if ok else 'FAIL'}: {what}")

    with tempfile.TemporaryDirectory() as tmp:
        cap, v = MU * KAPPA * D, 30.0
        t_star = -TAU * math.log(1.0 - cap / (C * v))
        expected = (v - cap / C) * (1.0 - t_star)
        w_x = v / LEVER
        w_off, off_mm = v / 5.0, 5.0

        def offset_torsion(t):
            # A turn about the axis through (5, 0, 0) mm parallel to G z: p = (I - R) a, in metres.
            a = w_off * t
            return (axis_rotation(2, a),
                    [off_mm * (1 - math.cos(a)) * 1e-3, -off_mm * math.sin(a) * 1e-3, 0.0])

        cases = {"rotation about x": (lambda t: (axis_rotation(0, w_x * t), [0.0, 0.0, 0.0]),
                                      "rx", LEVER),
                 "translation along y": (lambda t: ([1.0, 0.0, 0.0, 0.0], [0.0, v * t * 1e-3, 0.0]),
                                         "ty", None),
                 "torsion about an axis 5 mm off the centre": (offset_torsion, "rz", None)}
        for i, (name, (pose_at, axis, lever)) in enumerate(cases.items()):
            write_recording(f"{tmp}/c{i}", pose_at, 1.0, axis=axis)
            for pad, mm, deg in read_pads(script, f"{tmp}/c{i}"):
                check(abs(mm - expected) < 0.02,
                      f"{name}, {pad} pad: {mm:.3f} mm, closed form {expected:.3f}")
                if lever:
                    want = math.degrees(mm / lever)
                    check(deg is not None and abs(deg - want) < 0.01,
                          f"{name}, {pad} pad: {deg} deg, {mm:.3f} mm over {lever:g} mm "
                          f"= {want:.2f}")
                else:
                    check(deg is None, f"{name}, {pad} pad: no figure in degrees ({deg})")
        slow = (lambda t: (axis_rotation(1, 15.0 / LEVER * t), [0.0, 0.0, 0.0]))  # c v = 0.75 mm
        centred = (lambda t: (axis_rotation(2, 3.0 * t), [0.0, 0.0, 0.0]))
        for name, pose_at in (("slow rotation about y", slow),
                              ("torsion about the centre", centred)):
            path = f"{tmp}/{name.replace(' ', '_')}"
            write_recording(path, pose_at, 1.0)
            for pad, mm, _ in read_pads(script, path):
                check(mm == 0.0, f"{name}, {pad} pad: {mm:.3f} mm, expected 0")

        # Clear errors.
        os.makedirs(f"{tmp}/plain")
        with open(f"{tmp}/plain/recording.json", "w") as f:
            json.dump({"format": "tacse3-recording"}, f)
        write_recording(f"{tmp}/stick", slow, 1.0, regime="stick")
        write_recording(f"{tmp}/nan", lambda t: (axis_rotation(0, t), [0.0, float("nan"), 0.0]),
                        1.0)
        write_recording(f"{tmp}/nofriction", slow, 1.0)
        with open(f"{tmp}/nofriction/recording.json") as f:
            meta = json.load(f)
        del meta["sim"]["friction"]
        with open(f"{tmp}/nofriction/recording.json", "w") as f:
            json.dump(meta, f)
        write_recording(f"{tmp}/backwards", slow, 1.0)
        with open(f"{tmp}/backwards/truth.csv") as f:
            lines = f.readlines()
        with open(f"{tmp}/backwards/truth.csv", "w") as f:
            f.writelines(lines[:3] + [lines[2]] + lines[3:])
        for path, message in ((f"{tmp}/plain", "not a tacse3-sim recording"),
                              (f"{tmp}/stick", "only the slide regime has a friction cap"),
                              (f"{tmp}/nan", "truth.csv:2: a value is not finite"),
                              (f"{tmp}/nofriction", "missing or malformed key 'friction'"),
                              (f"{tmp}/backwards", "truth.csv:4: t_ns does not increase")):
            out = run(script, path)
            check(out.returncode == 1 and message in out.stderr,
                  f"{os.path.basename(path)}: exit {out.returncode}, {out.stderr.strip()}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
