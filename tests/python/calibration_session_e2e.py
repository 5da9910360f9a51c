#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""examples/calibration-session end to end on the host: tacse3d on the sim board (with a
[record] dir) behind a Unix socket, the script in --sim mode on the first 2 motions of
`tacse3-calibrate --plan`; then the recordings exist and replay, and the session's candump log
parses and holds Timestamp frames and the ACK of every command.

    calibration_session_e2e.py TACSE3D CALIBRATE REPLAY SIM_CALIBRATION SOURCE_DIR
"""

import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import unittest

import tacse3

TACSE3D, CALIBRATE, REPLAY, SIM_CALIBRATION, SOURCE = sys.argv[1:6]
SCRIPT = pathlib.Path(SOURCE) / "examples" / "calibration-session" / "calibration_session.py"


def board(tmp, record_dir):
    """boards/sim, looping, stale/lost raised for a loaded machine, [record] dir if given."""
    text = (pathlib.Path(SOURCE) / "boards" / "sim" / "board.toml").read_text()
    text = text.replace("repeat = false", "repeat = true")
    text = text.replace("stale_ms = 50", "stale_ms = 1000")
    text = text.replace("lost_ms = 500", "lost_ms = 2000")
    if record_dir:
        text += f'\n[record]\ndir = "{record_dir}"\n'
    path = tmp / "board.toml"
    path.write_text(text)
    return path


class CalibrationSessionTest(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory()
        self.tmp = pathlib.Path(self._tmp.name)
        self.rec = self.tmp / "rec"
        self.rec.mkdir()
        self.sock = self.tmp / "can.sock"
        self.err = open(self.tmp / "tacse3d.err", "w+")
        self.daemon = None

    def start_daemon(self, record_dir):
        self.daemon = subprocess.Popen(
            [TACSE3D, "--board", str(board(self.tmp, record_dir)), "--calibration",
             SIM_CALIBRATION, "--can-socket", str(self.sock)], stderr=self.err)

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

    def run_script(self, *extra):
        env = dict(os.environ, PYTHONPATH=str(pathlib.Path(SOURCE) / "python" / "src"))
        return subprocess.run(
            [sys.executable, str(SCRIPT), "--socket", str(self.sock), "--sim", "--calibrate",
             CALIBRATE, "--log", str(self.tmp / "can.log"), *extra],
            capture_output=True, text=True, env=env, timeout=60, check=False)

    def test_two_motions(self):
        self.start_daemon(self.rec)
        run = self.run_script("--limit", "2", "--first", "7", "--duration-scale", "0.2")
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual([ln.split(",")[0] for ln in run.stdout.splitlines()],
                         ["rec-00007", "rec-00008"])
        for name in ("rec-00007", "rec-00008"):
            rec = self.rec / name
            self.assertTrue((rec / "recording.json").is_file(), name)
            rows = (rec / "frames.csv").read_text().splitlines()
            self.assertGreater(len(rows), 1, f"{name}/frames.csv has no rows")
            replay = subprocess.run([REPLAY, str(rec), "--out", "-"], capture_output=True,
                                    text=True, timeout=60, check=False)
            self.assertEqual(replay.returncode, 0, replay.stderr)
        self.check_log(self.tmp / "can.log")

    def check_log(self, path):
        decoder = tacse3.BusDecoder()
        acks, timestamps = [], 0
        for msg in tacse3.LogReader(str(path), strict=True):
            ids = tacse3.codec.split_id(tacse3.IdLayout(), msg.arbitration_id, msg.is_extended_id)
            if ids and ids[1] == tacse3.table.BY_NAME["Timestamp"].id:
                timestamps += 1
            acks += [o for o in decoder.feed(msg) if isinstance(o, tacse3.Ack)]
        self.assertGreater(timestamps, 0)
        self.assertEqual([(a.command, a.result) for a in acks],
                         [("TARE", "ACK"), ("START_RECORDING", "ACK"), ("STOP_RECORDING", "ACK")]
                         * 2)

    def test_no_record_dir_nack_says_what_to_do(self):
        self.start_daemon(None)
        run = self.run_script("--limit", "1", "--duration-scale", "0.1")
        self.assertEqual(run.returncode, 3, run.stderr)
        self.assertIn("NO_RECORD_DIR", run.stderr)
        self.assertIn("[record] dir", run.stderr)
        self.assertFalse((self.tmp / "can.log").exists())


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1] + sys.argv[6:], verbosity=2)
