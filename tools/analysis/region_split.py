#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: replay readings split by how much of the anchored patch the contact mask holds.
"""Reads a `tacse3-replay --out OUT.csv --slip-log SLIP.csv` pair and the recording's truth.csv
(standard library only) and splits the frames of a time window by how much of the anchored
patch the contact mask still holds, the quantity the velocity proxy's overlap test compares
(dsp::kVelocityAnchorMinOverlap, docs/dsp.md §4.2d):

    overlap = |Ω ∩ anchor| / min(|anchor|, |Ω|)

per pad, |anchor| being `points` in the pad's last earlier row with `anchor_set` = 1 (a row
without contact drops it, as the pipeline does; the pipeline also drops it when a frame gap
restarts a pad that was slipping, which the slip log does not show, so a recording with frame
gaps can be binned against a stale anchor). A frame takes the smaller overlap of the pads in
contact and falls in the first bin whose lower edge it reaches (--edges, strictly descending;
default 0.5 0.3 0), or in "no anchor" (no pad in contact with an anchor).
Per bin it prints the frame count, how many of those frames every pad in contact read the
anchored region (`velocity_anchored`), and the rotation about the chosen G axis that the
replay's twist and the truth each carry over those frames (degrees: the sum of the rate about
the axis times the frame interval). Replay with --mode velocity, so that every frame's twist is
the velocity proxy's. A slide's shear follows the speed through the simulator's lag (its
recording.json "lag_time_s") and the replay averages the last few frames (the calibration's
moving_average_length), so a bin in the accelerating part of a motion reads low and one in the
decelerating part high against the truth itself; --lag-s and --average-frames pass the truth's
rate through the same two filters first, which makes the bins' ratios comparable.

The window defaults to the simulator's motion start (recording.json "sim" block,
motion_start_ns) up to the recording's end, so that the lagged reading after the motion counts;
a recording without that block needs --start and --end.

Usage: region_split.py OUT_CSV RECORDING_DIR SLIP_CSV [--axis x|y|z] [--start S] [--end S]
                       [--edges 0.5 0.3 0] [--lag-s TAU] [--average-frames N]
"""
import argparse
import collections
import csv
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from friction_cap_bound import spatial_rate  # noqa: E402


def fail(message):
    sys.exit(f"region_split: {message}")


def read_rows(path, needed):
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = [k for k in needed if k not in (reader.fieldnames or [])]
            if missing:
                fail(f"{path}: no column {', '.join(missing)}")
            rows = list(reader)
    except OSError as e:
        fail(f"cannot read {path} ({e.strerror})")
    except (UnicodeDecodeError, csv.Error) as e:
        fail(f"{path}: not a readable CSV file ({e})")
    return rows


def motion_start_ns(recording):
    """The sim block's motion_start_ns, or None without a sim block."""
    path = os.path.join(recording, "recording.json")
    if not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            sim = json.load(f).get("sim")
    except (OSError, UnicodeDecodeError, ValueError, AttributeError) as e:
        fail(f"cannot read {path} ({e})")
    if sim is None:
        return None
    start = sim.get("motion_start_ns") if isinstance(sim, dict) else None
    if not isinstance(start, int) or start < 0:
        fail(f"{path}: sim.motion_start_ns is missing or not a time in ns")
    return start


def number(path, row, key, cast=float):
    try:
        value = cast(row[key])
    except (TypeError, ValueError):
        fail(f"{path}: {key} = {row[key]!r} is not a number")
    if cast is float and not math.isfinite(value):
        fail(f"{path}: {key} = {row[key]!r} is not finite")
    return value


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out_csv")
    parser.add_argument("recording")
    parser.add_argument("slip_csv")
    parser.add_argument("--axis", choices=["x", "y", "z"], default="x")
    parser.add_argument("--start", type=float,
                        help="window start, s (default: the simulator's motion start)")
    parser.add_argument("--end", type=float, help="window end, s (default: the recording's end)")
    parser.add_argument("--edges", type=float, nargs="+", default=[0.5, 0.3, 0.0])
    parser.add_argument("--lag-s", type=float, default=0.0,
                        help="pass the truth's rate through a first-order lag of this time "
                             "constant (s) first (default 0: none)")
    parser.add_argument("--average-frames", type=int, default=1,
                        help="then through a moving average of this many frames (default 1)")
    args = parser.parse_args()
    if not (math.isfinite(args.lag_s) and 0.0 <= args.lag_s <= 10.0):
        fail("--lag-s must be in 0 .. 10 s")
    if not 1 <= args.average_frames <= 1000:
        fail("--average-frames must be in 1 .. 1000")
    if any(not 0.0 <= e <= 1.0 for e in args.edges) or \
            any(b >= a for a, b in zip(args.edges, args.edges[1:])):
        fail("--edges must be strictly descending fractions in 0 .. 1")
    if args.edges[-1] != 0.0:
        args.edges.append(0.0)
    axis = "xyz".index(args.axis)

    out_path = args.out_csv
    out = read_rows(out_path, ["t_ns", "wx", "wy", "wz"])
    estimate = {}
    for row in out:
        t = number(out_path, row, "t_ns", int)
        estimate[t] = number(out_path, row, "w" + args.axis)

    truth_path = args.recording.rstrip("/") + "/truth.csv"
    truth = []
    for row in read_rows(truth_path, ["t_ns", "qw", "qx", "qy", "qz"]):
        q = tuple(number(truth_path, row, k) for k in ("qw", "qx", "qy", "qz"))
        norm = math.sqrt(sum(x * x for x in q))
        if abs(norm - 1.0) > 1e-3:
            fail(f"{truth_path}: quaternion at t_ns {row['t_ns']} is not unit (|q| = {norm:.6f})")
        truth.append((number(truth_path, row, "t_ns", int), q))
    for (t0, _), (t1, _) in zip(truth, truth[1:]):
        if t1 <= t0:
            fail(f"{truth_path}: t_ns {t1} does not increase")
    if len(truth) < 2:
        fail(f"{truth_path}: fewer than two rows")
    # The window in ns, [start, end): times given in seconds round to the nanosecond.
    for name in ("start", "end"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and abs(value) < 1e6):
            fail(f"--{name} must be a time in seconds")
    if args.start is not None:
        start_ns = round(args.start * 1e9)
    else:
        start_ns = motion_start_ns(args.recording)
        if start_ns is None:
            fail(f"{args.recording} has no simulator block: give --start and --end")
    end_ns = round(args.end * 1e9) if args.end is not None else truth[-1][0] + 1
    if not end_ns > start_ns:
        fail("--end must be after --start")

    slip_path = args.slip_csv
    columns = ["t_ns", "sensor", "contact", "anchor_set", "velocity_anchored", "points",
               "anchor_overlap_points"]
    pads = {}  # t_ns -> list of (overlap fraction or None, velocity_anchored)
    anchor = {}
    seen = set()  # t_ns with a row
    for row in read_rows(slip_path, columns):
        t = number(slip_path, row, "t_ns", int)
        sensor = row["sensor"]
        if sensor not in ("left", "right"):
            fail(f"{slip_path}: t_ns {t}: sensor {sensor!r} is neither left nor right")
        points = number(slip_path, row, "points", int)
        held = number(slip_path, row, "anchor_overlap_points", int)
        if not 0 <= held <= points:
            fail(f"{slip_path}: t_ns {t} {sensor}: anchor_overlap_points {held} is not in "
                 f"0 .. points ({points})")
        seen.add(t)
        if number(slip_path, row, "contact", int) != 1:
            anchor.pop(sensor, None)  # a contact's loss drops its anchor
            continue
        # The overlap is against the anchor held before this frame: one set this frame applies
        # from the next (a contact's first frame has none).
        fraction = None
        if anchor.get(sensor, 0) > 0 and points > 0:
            fraction = held / min(anchor[sensor], points)
        pads.setdefault(t, []).append(
            (fraction, number(slip_path, row, "velocity_anchored", int) == 1))
        if number(slip_path, row, "anchor_set", int) == 1:
            anchor[sensor] = points

    labels = [f"overlap >= {e:g}" for e in args.edges] + ["no anchor"]
    bins = {label: [0, 0, 0.0, 0.0] for label in labels}  # frames, anchored, estimate, truth
    frames = 0
    lagged = 0.0  # the truth's rate about the axis through the lag, rad/s
    recent = collections.deque(maxlen=args.average_frames)  # and its last values
    for (t0, q0), (t1, q1) in zip(truth, truth[1:]):
        dt = (t1 - t0) * 1e-9
        rate = spatial_rate(q0, q1, dt)[axis]
        lagged += (1.0 - math.exp(-dt / args.lag_s) if args.lag_s > 0 else 1.0) * (rate - lagged)
        recent.append(lagged)
        if not start_ns <= t1 < end_ns:
            continue
        if t1 not in estimate:
            fail(f"{out_path}: no row at truth t_ns {t1}")
        if t1 not in seen:
            fail(f"{slip_path}: no row at truth t_ns {t1} (a slip log of another run?)")
        frames += 1
        readings = pads.get(t1, [])
        fractions = [f for f, _ in readings if f is not None]
        if not fractions:
            label = "no anchor"
        else:
            smallest = min(fractions)
            label = next(labels[i] for i, e in enumerate(args.edges) if smallest >= e)
        entry = bins[label]
        entry[0] += 1
        entry[1] += 1 if readings and all(a for _, a in readings) else 0
        entry[2] += math.degrees(estimate[t1] * dt)
        entry[3] += math.degrees(sum(recent) / len(recent) * dt)
    window = f"{start_ns * 1e-9:g} .. {(end_ns - 1) * 1e-9:g} s"
    if frames == 0:
        fail(f"no truth frame in {window}")

    filtered = ""
    if args.lag_s > 0 or args.average_frames > 1:
        filtered = (f"; the truth through a {args.lag_s:g} s lag and a {args.average_frames}-frame"
                    " average")
    print(f"{frames} frames in {window}; rotation about G {args.axis}, degrees{filtered}")
    for label in labels:
        n, anchored, est, tru = bins[label]
        if n == 0:
            continue
        ratio = f"{est / tru:.3f}" if abs(tru) > 1e-9 else "-"
        print(f"  {label:>15}: {n:4d} frames ({anchored} read the anchored region), "
              f"estimated {est:8.2f}, truth {tru:8.2f}, ratio {ratio}")


if __name__ == "__main__":
    main()
