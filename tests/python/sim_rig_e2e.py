#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""The simulated rig end to end on the host (docs/calibrate-a-rig.md, "Try it on a host"):
tacse3d with a [sim] plan of 3 short motions behind a Unix socket, examples/calibration-session
records them, tacse3-truth rebuilds each truth from the simulated robot's log and the session's
CAN log; the truth must match the simulator's own (robot/sim-truth.csv) and the clock offset the
robot's clock (CLOCK_REALTIME - CLOCK_MONOTONIC). Each recording starts from rest: replayed, it
shows no contact before the pads close. The full fit is not run (minutes): the 3
recordings are checked to be refused for the plan lines they lack. A 4th recording is refused.

    sim_rig_e2e.py TACSE3D CALIBRATE TRUTH REPLAY SIM_CALIBRATION SOURCE_DIR
"""

import csv
import math
import os
import pathlib
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest

TACSE3D, CALIBRATE, TRUTH, REPLAY, SIM_CALIBRATION, SOURCE = sys.argv[1:7]
SCRIPT = pathlib.Path(SOURCE) / "examples" / "calibration-session" / "calibration_session.py"

# The arm's noise (sim::ArmSpec, as docs/truth.md's simulated rig): rms 0.05 mm and 0.01 deg per
# logged pose. A truth row is the difference of two logged poses (now and the first frame), so its
# error is about sqrt(2) times that; the bounds allow 2 times that.
MAX_RMS_MM = 2 * math.sqrt(2) * 0.05
MAX_RMS_DEG = 2 * math.sqrt(2) * 0.01
# The CAN sync is as good as the daemon's latency is steady. It is within 1 ms on a quiet host; on
# a loaded one (a 2-core machine running builds) one recording's latency jumps by up to ~10 ms
# against the session's median that tacse3-truth subtracts. The bound catches a failed sync.
MAX_CAN_SYNC_ERROR_S = 20e-3
# The pads open for 0.05 s, then close on a 0.4 s minimum-jerk ramp from a 0.5 mm gap to 1 mm
# of indentation (docs/simulator.md): they touch a third of the way, 0.22 s from the start.
NO_CONTACT_S = 0.2
TCP_TO_GRASP = "[0.01, -0.005, 0.16, 0.98877, 0.02931, 0.14654, 0.0]"


def load_truth(path):
    with open(path, encoding="ascii") as f:
        return {int(r["t_ns"]): [float(r[k]) for k in ("qw", "qx", "qy", "qz", "px", "py", "pz")]
                for r in csv.DictReader(f)}


def angle_deg(a, b):
    return 2 * math.degrees(math.acos(min(1.0, abs(sum(x * y for x, y in zip(a[:4], b[:4]))))))


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values))


class SimRigTest(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory()
        self.tmp = pathlib.Path(self._tmp.name)
        self.err = open(self.tmp / "tacse3d.err", "w+", encoding="utf-8")
        self.daemon = None

    def tearDown(self):
        if self.daemon is not None:
            self.daemon.send_signal(signal.SIGTERM)
            try:
                self.daemon.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.daemon.kill()
                self.daemon.wait()
        self.err.close()
        self._tmp.cleanup()

    def write_plan(self, lines):
        """The plan's first lines, pads open 0.05 s and hold 0.2 s (as calibrate_test.sh)."""
        plan = subprocess.run([CALIBRATE, "--plan", "--format", "csv"], capture_output=True,
                              text=True, check=True).stdout.splitlines()
        rows = [plan[0]]
        for line in plan[1:1 + lines]:
            f = line.split(",", 7)
            f[5], f[6] = "0.05", "0.2"
            rows.append(",".join(f))
        (self.tmp / "plan.csv").write_text("\n".join(rows) + "\n")
        with open(self.tmp / "plan.csv", encoding="ascii") as f:
            self.plan = list(csv.DictReader(f))

    def write_board(self, plan="plan.csv"):
        (self.tmp / "rec").mkdir()
        (self.tmp / "board.toml").write_text(f"""version = 1
name = "sim-rig"
[sensors.left]
backend = "sim"
[sensors.right]
backend = "sim"
[sim]
plan = "{plan}"
[pipeline]
stale_ms = 1000
lost_ms = 2000
[record]
dir = "{self.tmp / 'rec'}"
[rig]
tcp_to_grasp = {TCP_TO_GRASP}
[realtime]
dsp_cpu = -1
dsp_priority = 0
""")

    def start_daemon(self):
        self.daemon = subprocess.Popen(
            [TACSE3D, "--board", str(self.tmp / "board.toml"), "--calibration", SIM_CALIBRATION,
             "--can-socket", str(self.tmp / "can.sock")], stderr=self.err)

    def run_session(self, log, *extra):
        env = dict(os.environ, PYTHONPATH=str(pathlib.Path(SOURCE) / "python" / "src"))
        return subprocess.run(
            [sys.executable, str(SCRIPT), "--socket", str(self.tmp / "can.sock"), "--sim",
             "--plan", str(self.tmp / "plan.csv"), "--log", str(self.tmp / log), *extra],
            capture_output=True, text=True, env=env, timeout=120, check=False)

    def test_three_motions_rebuild_their_truth(self):
        self.write_plan(3)
        self.write_board()
        self.start_daemon()
        start = time.monotonic()
        run = self.run_session("session.log")
        self.assertEqual(run.returncode, 0, run.stderr)
        print(f"session of 3 motions: {time.monotonic() - start:.1f} s", file=sys.stderr)
        offset = time.time() - time.monotonic()  # the robot's clock minus the board's
        for n in (1, 2, 3):
            rec = self.tmp / "rec" / f"rec-{n:05d}"
            # The robot's log against the simulator's truth, on the exact clock offset.
            self.rebuild(rec, "truth.csv", "--clock-offset", f"{offset:.9f}")
            rot, mm = self.compare(rec / "truth.csv", rec)
            self.assertLess(rot, MAX_RMS_DEG)
            self.assertLess(mm, MAX_RMS_MM)
            # The clock offset from the session's CAN log.
            said = self.rebuild(rec, "can-truth.csv", "--can-log", str(self.tmp / "session.log"))
            found = float(re.search(r"clock offset ([0-9.]+) s", said).group(1))
            crot, cmm = self.compare(rec / "can-truth.csv", rec)
            print(f"{rec.name}: rms {rot:.4f} deg {mm:.4f} mm; CAN sync: offset error "
                  f"{1e3 * (found - offset):+.3f} ms, rms {crot:.4f} deg {cmm:.4f} mm; "
                  f"{said.strip().splitlines()[1]}", file=sys.stderr)
            self.assertLess(abs(found - offset), MAX_CAN_SYNC_ERROR_S)
            self.check_from_rest(rec)
        # The three lines cover three of the plan's six: refused before any fit, naming the rest.
        recs = [str(p) for p in sorted((self.tmp / "rec").iterdir())]
        fit = subprocess.run([CALIBRATE, *recs, "-q", "--out", str(self.tmp / "rig.toml")],
                             capture_output=True, text=True, check=False)
        self.assertEqual(fit.returncode, 1, fit.stderr)
        self.assertIn("error: refused: the recordings do not determine", fit.stderr)
        self.assertIn("  record a translation along x of 1 mm", fit.stderr)
        self.assertFalse((self.tmp / "rig.toml").exists())
        # The plan is over: a 4th recording is refused, and says what to do.
        more = self.run_session("more.log", "--first", "4", "--limit", "1")
        self.assertEqual(more.returncode, 3, more.stderr)
        self.assertIn("OUT_OF_RANGE", more.stderr)
        self.assertIn("[sim] plan: restart tacse3d", more.stderr)
        self.assertFalse((self.tmp / "rec" / "rec-00004").exists())
        self.err.seek(0)
        self.assertIn("START_RECORDING 4 refused: every motion of the sim plan", self.err.read())

    def rebuild(self, rec, out, *sync):
        truth = subprocess.run(
            [TRUTH, "--recording", str(rec), "--gripper-log", str(rec / "robot/gripper.csv"),
             "--board", str(self.tmp / "board.toml"), "--out", str(rec / out), *sync],
            capture_output=True, text=True, check=False)
        self.assertEqual(truth.returncode, 0, truth.stderr)
        return truth.stdout + truth.stderr

    def compare(self, path, rec):
        """RMS rotation (deg) and translation (mm) error of a rebuilt truth, row by row."""
        got, want = load_truth(path), load_truth(rec / "robot/sim-truth.csv")
        self.assertGreater(len(got), 16)  # what calibration needs; ~150 frames on a quiet host
        self.assertTrue(set(got) <= set(want), "sim-truth.csv lacks frames of the recording")
        return (rms([angle_deg(got[t], want[t]) for t in got]),
                rms([1e3 * math.dist(got[t][4:], want[t][4:]) for t in got]))

    def check_from_rest(self, rec):
        """Replayed (the simulator's calibration), the first frames show no contact: the
        recording starts with the pads open, not in the previous motion's grasp."""
        out = self.tmp / "replay.csv"
        replay = subprocess.run([REPLAY, str(rec), "--calibration", SIM_CALIBRATION, "-q",
                                 "--out", str(out)], capture_output=True, text=True, check=False)
        self.assertEqual(replay.returncode, 0, replay.stderr)
        with open(out, encoding="ascii") as f:
            rows = list(csv.DictReader(f))
        t0 = int(rows[0]["t_ns"])
        early = [r["valid_left"] + r["valid_right"] for r in rows
                 if int(r["t_ns"]) - t0 < NO_CONTACT_S * 1e9]
        self.assertGreater(len(early), 1)  # the first frame is the reference: never in contact
        self.assertEqual(set(early), {"00"}, f"{rec.name}: contact in the first {NO_CONTACT_S} s")

    def test_missing_plan_stops_the_daemon(self):
        self.write_board(plan="none.csv")
        self.start_daemon()
        self.assertEqual(self.daemon.wait(timeout=30), 1)
        self.daemon = None
        self.err.seek(0)
        self.assertIn(f"[sim] plan {self.tmp / 'none.csv'}: no such file; write it with "
                      "tacse3-calibrate --plan --format csv", self.err.read())


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1] + sys.argv[7:], verbosity=2)
