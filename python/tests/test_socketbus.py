# SPDX-License-Identifier: Apache-2.0
"""tacse3.SocketBus against a fake daemon (a listening Unix socket in a temp dir): line
framing both ways, partial lines, timeouts, the daemon closing the socket; and, when
TACSE3D_BIN is set (ctest), a TARE and a decoded cycle from the real `tacse3d --board sim`."""

import os
import pathlib
import signal
import socket
import subprocess
import tempfile
import time
import unittest

import can

import tacse3


class FakeDaemon:
    """A listening socket; accept() returns the connected peer."""

    def __init__(self, path):
        self.server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.server.bind(path)
        self.server.listen(1)

    def accept(self):
        self.server.settimeout(5)
        peer, _ = self.server.accept()
        peer.settimeout(5)
        return peer


class SocketBusTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.dir.name, "can.sock")
        self.daemon = FakeDaemon(self.path)
        self.bus = tacse3.SocketBus(self.path)
        self.peer = self.daemon.accept()

    def tearDown(self):
        self.bus.shutdown()
        self.peer.close()
        self.daemon.server.close()
        self.dir.cleanup()

    def test_send_writes_one_candump_line(self):
        self.bus.send(can.Message(arbitration_id=0x123, is_extended_id=False,
                                  data=b"\x01\xab", timestamp=1.5))
        self.assertEqual(self.peer.recv(100), b"(0000000001.500000) can0 123#01AB\n")

    def test_recv_joins_partial_lines_and_skips_malformed_ones(self):
        self.peer.sendall(b"garbage\n(0000000002.000000) can0 1ABCDE")
        self.assertIsNone(self.bus.recv(timeout=0.05))
        self.peer.sendall(b"F0#DEAD\n")
        before = time.time()
        msg = self.bus.recv(timeout=1)
        self.assertEqual(msg.arbitration_id, 0x1ABCDEF0)
        self.assertTrue(msg.is_extended_id)
        self.assertEqual(bytes(msg.data), b"\xde\xad")
        self.assertGreaterEqual(msg.timestamp, before)  # the host clock, not the line's

    def test_recv_times_out(self):
        start = time.monotonic()
        self.assertIsNone(self.bus.recv(timeout=0.1))
        self.assertGreaterEqual(time.monotonic() - start, 0.1)

    def test_two_frames_in_one_chunk(self):
        self.peer.sendall(b"(1.0) can0 001#01\n(1.0) can0 002#02\n")
        self.assertEqual(self.bus.recv(timeout=1).arbitration_id, 1)
        self.assertEqual(self.bus.recv(timeout=0).arbitration_id, 2)

    def test_daemon_closing_raises(self):
        self.peer.close()
        with self.assertRaisesRegex(can.CanOperationError, "closed the socket"):
            self.bus.recv(timeout=1)


class ConnectErrorTest(unittest.TestCase):
    def test_missing_socket_names_the_path(self):
        with self.assertRaisesRegex(can.CanInitializationError, "nope.sock"):
            tacse3.SocketBus("/nonexistent/nope.sock", connect_timeout=0.1)


def sim_board(dir_path, record_dir=None):
    """boards/sim/board.toml, looping, optionally with [record] dir: a path in dir_path."""
    source = pathlib.Path(__file__).resolve().parents[2] / "boards" / "sim" / "board.toml"
    text = source.read_text().replace("repeat = false", "repeat = true")
    text = text.replace("stale_ms = 50", "stale_ms = 1000")
    text = text.replace("lost_ms = 500", "lost_ms = 2000")
    if record_dir:
        text += f'\n[record]\ndir = "{record_dir}"\n'
    board = pathlib.Path(dir_path) / "board.toml"
    board.write_text(text)
    return board


@unittest.skipUnless(os.environ.get("TACSE3D_BIN"), "TACSE3D_BIN (the tacse3d binary) not set")
class DaemonTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.sock = os.path.join(self.dir.name, "can.sock")
        self.err = open(os.path.join(self.dir.name, "tacse3d.err"), "w+")
        cmd = [os.environ["TACSE3D_BIN"], "--board", str(sim_board(self.dir.name)),
               "--can-socket", self.sock]
        if os.environ.get("TACSE3_SIM_CALIBRATION"):
            cmd += ["--calibration", os.environ["TACSE3_SIM_CALIBRATION"]]
        self.daemon = subprocess.Popen(cmd, stderr=self.err)

    def tearDown(self):
        self.daemon.send_signal(signal.SIGTERM)
        try:
            self.daemon.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.daemon.kill()
            self.daemon.wait()
        self.err.close()
        self.dir.cleanup()

    def test_tare_ack_and_a_decoded_cycle(self):
        with tacse3.SocketBus(self.sock, connect_timeout=10) as bus:
            ack = tacse3.Client(bus, node=1, timeout=5).tare()
            self.assertTrue(ack.ok)
            self.assertEqual(ack.command, "TARE")
            decoder = tacse3.BusDecoder()
            deadline = time.monotonic() + 10
            cycles = []
            while not cycles and time.monotonic() < deadline:
                msg = bus.recv(timeout=1)
                if msg is not None:
                    cycles += [o for o in decoder.feed(msg) if isinstance(o, tacse3.Cycle)]
            self.assertTrue(cycles, "no complete cycle from tacse3d in 10 s")
            self.assertEqual(cycles[0].node, 1)


if __name__ == "__main__":
    unittest.main()
