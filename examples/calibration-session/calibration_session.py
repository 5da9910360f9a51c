#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 example: record a calibration plan, one recording per motion (docs/calibrate-a-rig.md).
"""Run a calibration session against a tacse3 gripper: TARE, START_RECORDING N, move, STOP.

    calibration_session.py --channel can0 --log can.log             # a robot: fill in move()
    calibration_session.py --socket /tmp/tacse3.sock --sim --log can.log

Writes the controller-side candump -L log of the whole session (every frame received, host
clock) for `tacse3-truth --can-log`, and prints which recording number is which motion.
Exit status: 0 done, 1 bus or plan error, 2 bad arguments, 3 NACK, 4 no ACK in time.
"""

import argparse
import csv
import io
import os
import queue
import subprocess
import sys
import threading
import time

import can

import tacse3

PLAN_COLUMNS = ("axis", "magnitude", "unit", "regime", "duration_s", "pads_open_s", "hold_s")

# What to do about each NACK reason (docs/can-protocol.md lists them).
ADVICE = {
    "NO_RECORD_DIR": 'set [record] dir = "/abs/path" in the board file and restart tacse3d',
    "RECORDING_EXISTS": "that rec-NNNNN is already in the record dir: choose another --first "
                        "or move the old recordings away",
    "ALREADY_RECORDING": "a recording is running (tacse3d --record, or another session): stop "
                         "it with `tacse3-ctl ... record-stop`",
    "NOT_RECORDING": "the recording had already ended: see tacse3d's log (disk full?)",
    "DISK_ERROR": "the record dir is not writable or the disk is full: see tacse3d's log",
    "BUSY": "the gripper is busy: retry",
    "OUT_OF_RANGE": "a simulated rig has played every motion of its [sim] plan: restart tacse3d "
                    "(see its log)",
}


# ---------------------------------------------------------------------------------------------
# FILL IN FOR YOUR ROBOT. Called once the recording runs. Do, for `motion` (a dict of the plan's
# columns, numbers as float): pads open for pads_open_s, close them on the object and let the
# grasp settle, run the motion (axis, magnitude in unit, over duration_s), hold still for hold_s,
# and log the robot's pose for tacse3-truth (docs/truth.md). Return when the hold is over.
def move(motion):
    raise NotImplementedError("move() is yours to write: see the comment above it in "
                              f"{os.path.basename(__file__)}, or run with --sim")
# ---------------------------------------------------------------------------------------------


# The simulator closes the pads in 0.4 s and lets the grasp settle for 0.1 s (docs/simulator.md).
SIM_GRASP_S = 0.5
# A simulated rig opens the pads when the recording stops; the next tare must see them open,
# and the frames reach the pipeline tens of milliseconds after they are taken.
SIM_OPEN_S = 0.2


def sim_move(scale):
    """The simulator board plays the motion itself ([sim] plan: the plan's next line; else its
    own scenario): only wait for it, pads open, grasp, motion and hold."""
    def wait(motion):
        time.sleep(scale * (motion["pads_open_s"] + SIM_GRASP_S + motion["duration_s"] +
                            motion["hold_s"]))
    return wait


class LoggedBus:
    """One reader thread owns the bus: it writes every received frame to the log and queues it
    for the Client, so frames keep being read (and logged) while move() runs."""

    def __init__(self, bus, log, iface):
        self.bus, self.log, self.iface = bus, log, iface
        self.frames = queue.Queue()
        self.error = None
        self.count = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        try:
            while not self._stop.is_set():
                msg = self.bus.recv(timeout=0.1)
                if msg is not None:
                    if not msg.timestamp:
                        msg.timestamp = time.time()
                    self.log.write(tacse3.format_line(msg, self.iface) + "\n")
                    self.count += 1
                    self.frames.put(msg)
        except can.CanError as e:
            self.error = e
            self.frames.put(None)

    def check(self):
        if self.error is not None:
            raise self.error

    # The two methods tacse3.Client uses.
    def send(self, msg, timeout=None):
        self.check()
        self.frames = queue.Queue()   # what the Client waits for comes after this
        self.bus.send(msg, timeout=timeout)

    def recv(self, timeout=None):
        try:
            msg = self.frames.get(timeout=timeout)
        except queue.Empty:
            return None
        if msg is None:
            self.check()
        return msg

    def close(self):
        self._stop.set()
        self._thread.join()


def read_plan(a):
    if a.plan:
        try:
            with open(a.plan, encoding="utf-8") as f:
                text, source = f.read(), a.plan
        except OSError as e:
            raise SystemExit(f"error: --plan {a.plan}: {e.strerror}") from None
    else:
        cmd = [a.calibrate, "--plan", "--format", "csv"]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, check=False)
        except OSError as e:
            raise SystemExit(f"error: cannot run {a.calibrate} ({e.strerror}): give --calibrate "
                             "PATH or --plan CSV") from None
        if run.returncode != 0:
            raise SystemExit(f"error: {' '.join(cmd)} failed: {run.stderr.strip()}")
        text, source = run.stdout, " ".join(cmd)
    rows = list(csv.DictReader(io.StringIO(text)))
    missing = [c for c in PLAN_COLUMNS if rows and c not in rows[0]]
    if not rows or missing:
        raise SystemExit(f"error: {source}: not a plan (no rows, or no column "
                         f"{', '.join(missing)})")
    for row in rows:
        for col in ("magnitude", "duration_s", "pads_open_s", "hold_s"):
            row[col] = float(row[col])
    return rows[:a.limit] if a.limit else rows


def open_bus(a):
    if a.socket:
        return tacse3.SocketBus(a.socket)
    return can.Bus(interface="socketcan", channel=a.channel)


def session(client, plan, first, do_move, pause_s=0.0):
    """pause_s: the wait after each stop, for the pads to be open before the next tare."""
    for i, motion in enumerate(plan):
        n = first + i
        client.tare()
        client.start_recording(n)
        print(f"rec-{n:05d},{motion['axis']},{motion['magnitude']:g},{motion['unit']},"
              f"{motion['regime']}", flush=True)
        try:
            do_move(motion)
        except BaseException:
            client.stop_recording()
            raise
        client.stop_recording()
        time.sleep(pause_s)


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    bus = ap.add_mutually_exclusive_group(required=True)
    bus.add_argument("--channel", help="SocketCAN interface, e.g. can0")
    bus.add_argument("--socket", help="tacse3d's --can-socket PATH (a daemon on this host)")
    ap.add_argument("--node", type=int, default=1, help="node id of the gripper (1..63)")
    ap.add_argument("--log", required=True, help="candump -L log of the session to write")
    ap.add_argument("--plan", help="plan CSV (default: run `tacse3-calibrate --plan --format csv`)")
    ap.add_argument("--calibrate", default="tacse3-calibrate", help="the tacse3-calibrate to run")
    ap.add_argument("--first", type=int, default=1, help="recording number of the first motion")
    ap.add_argument("--limit", type=int, default=0, help="record only the first N motions")
    ap.add_argument("--sim", action="store_true",
                    help="simulator board: move() only waits the motion's time")
    ap.add_argument("--duration-scale", type=float, default=1.0,
                    help="with --sim: multiply the waits by this (e.g. 0.2 for a quick test)")
    ap.add_argument("--timeout", type=float, default=1.0, help="seconds to wait for each ACK")
    a = ap.parse_args()
    if a.duration_scale <= 0 or a.limit < 0 or not 0 <= a.first <= 99999:
        ap.error("--duration-scale must be > 0, --limit >= 0, --first 0..99999")
    if a.duration_scale != 1.0 and not a.sim:
        ap.error("--duration-scale is --sim's")
    return a


def main():
    a = parse_args()
    plan = read_plan(a)
    if a.first + len(plan) - 1 > 99999:
        raise SystemExit("error: --first + the plan's length passes recording number 99999")
    partial = a.log + ".partial"
    try:
        bus = open_bus(a)
    except (can.CanError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    log = open(partial, "w", encoding="ascii")
    logged = LoggedBus(bus, log, a.channel or "can0")
    client = tacse3.Client(logged, node=a.node, timeout=a.timeout)
    status = 0
    try:
        if a.sim:
            session(client, plan, a.first, sim_move(a.duration_scale), SIM_OPEN_S)
        else:
            session(client, plan, a.first, move)
    except tacse3.NackError as e:
        print(f"error: {e}: {ADVICE.get(e.ack.result, 'see docs/can-protocol.md')}",
              file=sys.stderr)
        status = 3
    except tacse3.AckTimeout as e:
        print(f"error: {e}", file=sys.stderr)
        status = 4
    except (tacse3.ClientError, can.CanError) as e:
        print(f"error: {e}", file=sys.stderr)
        status = 1
    finally:
        logged.close()
        bus.shutdown()
        log.close()
    if status:
        print(f"the log so far ({logged.count} frames) is in {partial}", file=sys.stderr)
        return status
    os.replace(partial, a.log)
    print(f"{len(plan)} recordings, {logged.count} frames logged to {a.log}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
