#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tools tests: tools/analysis/friction_cap_bound.py against the slide law's closed-form solution.
"""A rotation about G x at a constant rate from rest of the shear: the pad centre slides at
v = w W/2, the shear U(t) = c v (1 - exp(-t/tau)) reaches the cap m at t* = -tau ln(1 - m/(c v))
and is held there, so the motion beyond the cap speed is (v - m/c)(T - t*). Also: a rotation
slow enough to stay below the cap (0), a torsion (the centre does not slide: 0) and a folder that
is not a simulator recording (a clear error, exit status 1).

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


def write_recording(path, axis, rate, seconds):
    os.makedirs(path)
    sim = {"object": "sphere", "friction": MU, "indentation_mm": D,
           "motion": {"axis": "r" + "xyz"[axis], "magnitude": 1.0, "unit": "deg"},
           "gel": {"drag_time_s": C, "lag_time_s": TAU, "shear_compliance": KAPPA}}
    meta = {"format": "tacse3-recording", "version": 1, "width": 320, "height": 240, "fps": FPS,
            "sensors": ["left", "right"],
            "rig": {"pixel_pitch_mm": 0.1, "finger_separation_mm": W, "layout": "mirrored"},
            "sim": sim}
    json.dump(meta, open(f"{path}/recording.json", "w"))
    with open(f"{path}/truth.csv", "w") as f:
        f.write("t_ns,qw,qx,qy,qz,px,py,pz\n")
        for k in range(int(seconds * FPS) + 1):
            t = k / FPS
            h = rate * t / 2
            q = [math.cos(h), 0.0, 0.0, 0.0]
            q[1 + axis] = math.sin(h)
            f.write(f"{round(t * 1e9)},{q[0]!r},{q[1]!r},{q[2]!r},{q[3]!r},0,0,0\n")


def unseen_mm(script, path):
    out = subprocess.run([sys.executable, script, path], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"FAIL: {path}: exit {out.returncode}: {out.stderr}")
    found = re.findall(r"motion beyond the cap speed ([0-9.]+) mm", out.stdout)
    if len(found) != 2:
        sys.exit(f"FAIL: {path}: unexpected output:\n{out.stdout}")
    return [float(x) for x in found]


def main():
    script = sys.argv[1]
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        cap = MU * KAPPA * D
        v = 30.0  # mm/s at the pad centre
        write_recording(f"{tmp}/fast", 0, v / (W / 2), 1.0)
        t_star = -TAU * math.log(1.0 - cap / (C * v))
        expected = (v - cap / C) * (1.0 - t_star)
        for got in unseen_mm(script, f"{tmp}/fast"):
            ok = abs(got - expected) < 0.02
            failures += not ok
            print(f"{'ok' if ok else 'FAIL'}: rx at {v} mm/s: {got:.3f} mm, closed form {expected:.3f}")
        write_recording(f"{tmp}/slow", 1, 15.0 / (W / 2), 1.0)  # c v = 0.75 mm < 0.9 mm
        write_recording(f"{tmp}/torsion", 2, 3.0, 1.0)
        for name in ("slow", "torsion"):
            for got in unseen_mm(script, f"{tmp}/{name}"):
                ok = got == 0.0
                failures += not ok
                print(f"{'ok' if ok else 'FAIL'}: {name}: {got:.3f} mm, expected 0")
        os.makedirs(f"{tmp}/plain")
        json.dump({"format": "tacse3-recording"}, open(f"{tmp}/plain/recording.json", "w"))
        out = subprocess.run([sys.executable, script, f"{tmp}/plain"], capture_output=True,
                             text=True)
        ok = out.returncode == 1 and "not a tacse3-sim recording" in out.stderr
        failures += not ok
        print(f"{'ok' if ok else 'FAIL'}: a recording without the simulator block: "
              f"exit {out.returncode}, {out.stderr.strip()}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
