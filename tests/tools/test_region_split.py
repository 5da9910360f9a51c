#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tools tests: tools/analysis/region_split.py on a constructed replay, slip log and truth.
"""A truth turning about G x at 0.5 rad/s for 2 s at 120 fps (a quaternion per frame), and a
replay that reads 0.5 rad/s while both pads hold at least half of their anchor, 0.25 rad/s while
the smaller overlap is in 0.3 .. 0.5, 0.1 rad/s below 0.3, and 0.2 rad/s while no pad has an
anchor. The slip log: no contact for the first 12 frames, anchors of 100 (left) and 80 (right)
cells set at frame 12 (a contact's first frame: no anchor yet), then overlaps that walk through
the bins, with velocity_anchored set where the overlap is at least half; then the left pad's
overlap exactly at the edge over a mask smaller than its anchor (30 of 60 cells: 0.5, where
dividing by the anchor would give 0.3), a frame without left contact, and a new left contact
whose first frame has no anchor (the old one must not count) and sets one of 90 cells.
Checks every bin's frame count, anchored count and both sums (degrees: rate x frame interval),
the window, the truth through a lag and a moving average (closed form from rest), another axis
(no truth rotation: ratio "-"), and clear errors (exit 1, message on stderr) for a missing
column, a non-number, a non-unit quaternion, a truth time that does not increase, a replay
without a truth frame's row, edges that do not descend and a bad lag or average.

Usage: test_region_split.py SCRIPT
"""
import json
import math
import os
import re
import subprocess
import sys
import tempfile

FPS, RATE, FRAMES = 120, 0.5, 241
SCRIPT = sys.argv[1]
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def pads_of(i):
    """Per pad (contact, anchor_set, points, held) at frame i."""
    if i < 12:
        return (0, 0, 0, 0), (0, 0, 0, 0)
    if i == 12:
        return (1, 1, 100, 0), (1, 1, 80, 0)
    if i < 60:    # 90/100 = 0.9; 40 / min(80, 90) = 0.5 exactly (40/90 would be 0.44)
        return (1, 0, 120, 90), (1, 0, 90, 40)
    if i < 120:   # 50/100 = 0.5; 24/80 = 0.3 exactly
        return (1, 0, 120, 50), (1, 0, 90, 24)
    if i < 180:   # 0.2; 0.125
        return (1, 0, 120, 20), (1, 0, 90, 10)
    if i < 210:   # 30 / min(100, 60) = 0.5 exactly (30/100 would be 0.3); 79/80
        return (1, 0, 60, 30), (1, 0, 80, 79)
    if i == 210:  # left contact lost: its anchor goes
        return (0, 0, 0, 0), (1, 0, 80, 79)
    if i == 211:  # a new left contact, first frame: no anchor; sets one of 90 cells
        return (1, 1, 90, 0), (1, 0, 80, 79)
    if i < 225:   # 85/90; 79/80
        return (1, 0, 90, 85), (1, 0, 80, 79)
    if i == 225:  # the right pad re-anchors mid-contact (59/60 of the old 80), to 60 cells
        return (1, 0, 90, 85), (1, 1, 60, 59)
    return (1, 0, 90, 85), (1, 0, 80, 35)  # 35 / min(60, 80) = 0.58 (35/80 would be 0.44)


def bin_of(i):
    """The bin frame i falls in (what the script must find)."""
    if i <= 12:
        return "no anchor"
    if 60 <= i < 120:
        return "overlap >= 0.3"
    if 120 <= i < 180:
        return "overlap >= 0"
    return "overlap >= 0.5"


def region_rate(i):
    return {"no anchor": 0.2, "overlap >= 0.5": 0.5, "overlap >= 0.3": 0.25,
            "overlap >= 0": 0.1}[bin_of(i)]


def velocity_anchored(pad, anchor):
    contact, _, points, held = pad
    return int(contact == 1 and anchor > 0 and held >= 0.5 * min(anchor, points))


def write(folder, truth_rows=None, out_rows=None, slip_rows=None, sim=True):
    os.makedirs(os.path.join(folder, "rec"), exist_ok=True)
    if sim:  # the simulator's block: the motion starts at 0.6 s
        with open(os.path.join(folder, "rec", "recording.json"), "w") as f:
            json.dump({"format": "tacse3-recording", "version": 1,
                       "sim": {"motion_start_ns": 600000000}}, f)
    if truth_rows is None:
        truth_rows = ["t_ns,qw,qx,qy,qz,px,py,pz"]
        for i in range(FRAMES):
            a = RATE * i / FPS
            q = f"{math.cos(a / 2)!r},{math.sin(a / 2)!r},0,0"
            truth_rows.append(f"{i * 10**9 // FPS},{q},0,0,0")
    if out_rows is None:
        out_rows = ["t_ns,wx,wy,wz,vx,vy,vz,qw,qx,qy,qz,px,py,pz,valid_left,valid_right"]
        for i in range(FRAMES):
            out_rows.append(f"{i * 10**9 // FPS},{region_rate(i)!r},0,0,0,0,0,1,0,0,0,0,0,0,1,1")
    if slip_rows is None:
        slip_rows = ["t_ns,sensor,contact,anchor_set,velocity_anchored,points,"
                     "anchor_overlap_points"]
        anchors = {"left": 0, "right": 0}
        for i in range(FRAMES):
            t = i * 10**9 // FPS
            for name, pad in zip(("left", "right"), pads_of(i)):
                contact, anchor_set, points, held = pad
                if contact == 0:
                    anchors[name] = 0
                a = velocity_anchored(pad, anchors[name])
                slip_rows.append(f"{t},{name},{contact},{anchor_set},{a},{points},{held}")
                if anchor_set:
                    anchors[name] = points
    for name, rows in (("rec/truth.csv", truth_rows), ("out.csv", out_rows),
                       ("slip.csv", slip_rows)):
        with open(os.path.join(folder, name), "w") as f:
            f.write("\n".join(rows) + "\n")


def run(folder, *extra):
    return subprocess.run([sys.executable, SCRIPT, os.path.join(folder, "out.csv"),
                           os.path.join(folder, "rec"), os.path.join(folder, "slip.csv"),
                           *extra], capture_output=True, text=True)


def parse(stdout):
    bins = {}
    for m in re.finditer(r"(overlap >= [0-9.]+|no anchor): +(\d+) frames \((\d+) read the "
                         r"anchored region\), estimated +(-?[0-9.]+), truth +(-?[0-9.]+), "
                         r"ratio (\S+)", stdout):
        bins[m.group(1)] = (int(m.group(2)), int(m.group(3)), float(m.group(4)),
                            float(m.group(5)), m.group(6))
    return bins


with tempfile.TemporaryDirectory() as tmp:
    base = os.path.join(tmp, "ok")
    write(base)
    # Window 0 .. 2 s: frames 1 .. 239 (t1 < 2 s; frame 240 is at 2 s exactly).
    r = run(base, "--start", "0", "--end", "2")
    check(r.returncode == 0, f"ok run exit {r.returncode}: {r.stderr}")
    bins = parse(r.stdout)
    # Frames 1 .. 12 have no anchor; frame 211 reads the anchored region on the right pad only.
    want = {
        "no anchor": (12, 0, range(1, 13)),
        "overlap >= 0.5": (47 + 60, 47 + 59, list(range(13, 60)) + list(range(180, 240))),
        "overlap >= 0.3": (60, 0, range(60, 120)),
        "overlap >= 0": (60, 0, range(120, 180)),
    }
    check(all(bin_of(i) == label for label, (_, _, frames) in want.items() for i in frames),
          "the test's own bins disagree")
    for label, (n, anchored, frames) in want.items():
        got = bins.get(label)
        if got is None:
            failures.append(f"bin {label} missing from:\n{r.stdout}")
            continue
        est = math.degrees(sum(region_rate(i) for i in frames) / FPS)
        tru = math.degrees(RATE * len(frames) / FPS)
        check(got[0] == n, f"{label}: {got[0]} frames, want {n}")
        check(got[1] == anchored, f"{label}: {got[1]} anchored, want {anchored}")
        check(abs(got[2] - est) < 0.011, f"{label}: estimated {got[2]}, want {est:.3f}")
        check(abs(got[3] - tru) < 0.011, f"{label}: truth {got[3]}, want {tru:.3f}")
        check(abs(float(got[4]) - est / tru) < 0.001, f"{label}: ratio {got[4]}, want {est / tru}")
    check(r.stdout.startswith("239 frames in 0 .. 2 s; rotation about G x"), r.stdout)

    # The default window (the sim block's motion start, 0.6 s, to the recording's end) holds
    # frames 72 .. 240.
    r = run(base)
    bins = parse(r.stdout)
    check(r.returncode == 0 and bins.get("overlap >= 0.3", (0,))[0] == 48,
          f"default window, 0.3 bin: {r.stdout}")
    check(bins.get("overlap >= 0.5", (0,))[0] == 61, f"default window, 0.5 bin: {r.stdout}")

    # The truth through a 0.05 s lag and a 3-frame average: the lagged rate is
    # RATE (1 - exp(-k dt / tau)) at frame k (from rest at frame 0), averaged over frames
    # max(1, k - 2) .. k.
    tau, n_avg = 0.05, 3
    lagged = lambda k: RATE * (1.0 - math.exp(-k / FPS / tau))  # noqa: E731
    r = run(base, "--start", "0", "--end", "2", "--lag-s", str(tau), "--average-frames", str(n_avg))
    bins = parse(r.stdout)
    check(r.returncode == 0 and "through a 0.05 s lag and a 3-frame average" in r.stdout,
          f"lag: {r.returncode} {r.stdout} {r.stderr}")
    for label, (n, anchored, frames) in want.items():
        got = bins.get(label)
        if got is None:
            failures.append(f"lag: bin {label} missing")
            continue
        tru = math.degrees(sum(sum(lagged(j) for j in range(max(1, k - n_avg + 1), k + 1)) /
                               (k - max(1, k - n_avg + 1) + 1) for k in frames) / FPS)
        check(abs(got[3] - tru) < 0.011, f"lag: {label}: truth {got[3]}, want {tru:.3f}")
        check(got[0] == n and got[1] == anchored, f"lag: {label}: counts {got[:2]}")

    # About G y there is no truth rotation and no estimate: ratios are "-".
    r = run(base, "--axis", "y", "--start", "0", "--end", "2")
    bins = parse(r.stdout)
    check(r.returncode == 0 and bins and all(b[4] == "-" and b[2] == 0.0 for b in bins.values()),
          f"axis y: {r.stdout}")

    # Two bins only: 0.5 and 0 (0 appended).
    r = run(base, "--start", "0", "--end", "2", "--edges", "0.5")
    bins = parse(r.stdout)
    check(r.returncode == 0 and bins.get("overlap >= 0", (0,))[0] == 120, f"edges 0.5: {r.stdout}")

    def bad(name, message, **files):
        folder = os.path.join(tmp, name)
        write(folder, **files)
        r = run(folder)
        check(r.returncode == 1 and message in r.stderr and r.stdout == "",
              f"{name}: exit {r.returncode}, stderr {r.stderr!r}, want {message!r}")

    header = "t_ns,wx,wy,wz,vx,vy,vz,qw,qx,qy,qz,px,py,pz,valid_left,valid_right"
    bad("no_column", "no column anchor_overlap_points",
        slip_rows=["t_ns,sensor,contact,anchor_set,velocity_anchored,points", "0,left,0,0,0,0"])
    bad("not_number", "wx = 'fast' is not a number", out_rows=[header, "0,fast,0,0"])
    bad("not_unit", "is not unit", truth_rows=["t_ns,qw,qx,qy,qz", "0,1,0,0,0", "8333333,1,1,0,0"])
    bad("time", "t_ns 0 does not increase",
        truth_rows=["t_ns,qw,qx,qy,qz", "700000000,1,0,0,0", "0,1,0,0,0"])
    bad("no_row", "no row at truth t_ns",
        out_rows=[header] + [f"{i * 10**9 // FPS},0,0,0" for i in range(60)])
    slip_header = ("t_ns,sensor,contact,anchor_set,velocity_anchored,points,"
                   "anchor_overlap_points")
    bad("held_over_points", "anchor_overlap_points 9 is not in 0 .. points (5)",
        slip_rows=[slip_header, "0,left,1,1,0,5,9"])
    bad("sensor", "sensor 'middle' is neither left nor right",
        slip_rows=[slip_header, "0,middle,1,1,0,5,0"])
    bad("other_run", "no row at truth t_ns", slip_rows=[slip_header, "1,left,1,1,0,5,0"])
    bad("same_time", "does not increase",
        truth_rows=["t_ns,qw,qx,qy,qz", "0,1,0,0,0", "700000000,1,0,0,0", "700000000,1,0,0,0"])
    folder = os.path.join(tmp, "binary")
    write(folder)
    with open(os.path.join(folder, "slip.csv"), "wb") as f:
        f.write(b"t_ns,sensor\n\xff\xfe,\x80\n")
    r = run(folder)
    check(r.returncode == 1 and "not a readable CSV file" in r.stderr, f"binary: {r.stderr!r}")
    folder = os.path.join(tmp, "no_sim")
    write(folder, sim=False)
    r = run(folder)
    check(r.returncode == 1 and "give --start and --end" in r.stderr, f"no sim: {r.stderr!r}")
    r = run(folder, "--start", "0", "--end", "2")
    check(r.returncode == 0, f"no sim, window given: {r.stderr!r}")
    for option, values, message in (("--edges", ["0.3", "0.5"], "strictly descending"),
                                    ("--edges", ["0.5", "0.5"], "strictly descending"),
                                    ("--edges", ["1.5"], "strictly descending"),
                                    ("--lag-s", ["-1"], "--lag-s must be"),
                                    ("--lag-s", ["nan"], "--lag-s must be"),
                                    ("--lag-s", ["11"], "--lag-s must be"),
                                    ("--average-frames", ["0"], "--average-frames must be"),
                                    ("--end", ["0.5"], "--end must be after --start")):
        r = run(base, option, *values)
        check(r.returncode == 1 and message in r.stderr, f"{option} {values}: {r.stderr!r}")

if failures:
    print("\n".join(failures))
    sys.exit(1)
print("region_split.py: all checks passed")
