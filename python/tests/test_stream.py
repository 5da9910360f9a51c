# SPDX-License-Identifier: Apache-2.0
"""candump -L reading/writing and the BusDecoder's cycle reassembly and fault counting."""

import os
import unittest

import tacse3
from tacse3 import candump

REPO = os.path.join(os.path.dirname(__file__), "..", "..")
REPLIES = os.path.join(REPO, "tests", "protocol", "data", "gripper_replies.log")


class Candump(unittest.TestCase):
    def test_gripper_replies_log(self):
        reader = tacse3.LogReader(REPLIES)
        acks = [tacse3.decode(m) for m in reader if m.arbitration_id & 0x1F == 0x11]
        self.assertEqual((reader.lines, reader.bad_lines), (9, 2))  # lines 2, 3 are malformed
        self.assertEqual([(a.node, a.command, a.result, a.sequence) for a in acks],
                         [(2, "TARE", "ACK", 3), (1, "TARE", "ACK", 2), (1, "TARE", "ACK", 3),
                          (1, "TARE", "BUSY", 4), (1, "QUERY", "ACK", 2),
                          (1, "SET_FINGER_SEPARATION", "ACK", 1)])
        self.assertEqual(acks[4].query_reply(), {"item": "PROTOCOL_VERSION",
                                                 "version": (1, 0, 0)})
        self.assertEqual(acks[5].data, [0x34, 0x21, 0, 0])

    def test_strict_names_file_and_line(self):
        with self.assertRaisesRegex(tacse3.CandumpError, r"gripper_replies.log:2: "):
            list(tacse3.LogReader(REPLIES, strict=True))

    def test_line_forms(self):
        fd = candump.parse_line("(1700000000.5) can1 1ACE0026##1" + "AB" * 64)
        self.assertEqual((fd.arbitration_id, fd.is_extended_id, fd.is_fd, fd.bitrate_switch,
                          len(fd.data), fd.channel, fd.timestamp),
                         (0x1ACE0026, True, True, True, 64, "can1", 1700000000.5))
        rtr = candump.parse_line("(1.000001) can0 021#R3")
        self.assertTrue(rtr.is_remote_frame and rtr.dlc == 3)
        err = candump.parse_line("(1.000001) can0 20000004#0000000000000000")
        self.assertTrue(err.is_error_frame)
        self.assertEqual(candump.parse_line("(1.0) can0 021#0102030405060708_C T").dlc, 8)
        for bad in ("(1.0) can0 0021#00", "(1.0) can0 800#00", "(1.0) can0 021#0", "1.0 can0 021#",
                    "(1.0) can0 021#000000000000000000", "(1.0) can0 021##1000000000000000000",
                    "(1.0) can0 021#01 02", "(1.0) can0 021#R9"):
            with self.assertRaises(tacse3.CandumpError, msg=bad):
                candump.parse_line(bad)

    def test_format_parse_round_trip(self):
        frames, _ = tacse3.encode_cycle(tacse3.Cycle(node=3, t_us=10), 1, fd=True)
        lines = ["(1700000000.000100) can0 021#D202964900005948",
                 "(0000000012.345678) vcan0 1ACE0041#D202964900005912",
                 candump.format_line(frames[0])]
        for line in lines:
            self.assertEqual(candump.format_line(candump.parse_line(line)), line)
        self.assertRegex(lines[2], r"^\(0000000000\.000000\) can0 066##1[0-9A-F]{128}$")


def cycle_frames(node, counter, t_us, fd=False):
    return tacse3.encode_cycle(tacse3.Cycle(node=node, t_us=t_us, valid=True), counter, fd=fd)[0]


class BusDecoderTest(unittest.TestCase):
    def feed(self, decoder, frames):
        return [o for f in frames for o in decoder.feed(f)]

    def test_faults_are_counted(self):
        c = {k: cycle_frames(1, k, 1000 + k) for k in (0, 1, 2, 3, 4, 7)}
        c[4][0].data[0] ^= 1  # cycle 4: Timestamp with a bad CRC -> crc error, incomplete
        frames = (c[0] + c[1] + c[2][:4]  # cycle 2 lacks PosePosition -> incomplete
                  + c[3] + c[4] + c[3][:1]  # a late Timestamp of cycle 3 -> repeated
                  + c[7]  # counters 5, 6 skipped -> 2 gaps
                  + cycle_frames(1, 8, 1002))  # SampleTime not newer -> stale
        d = tacse3.BusDecoder()
        self.assertEqual([c.counter for c in self.feed(d, frames)], [0, 1, 3, 7])
        s = d.nodes[1].stats
        self.assertEqual((s.cycles, s.incomplete, s.gaps, s.repeated, s.stale, d.crc_errors),
                         (4, 2, 2, 1, 1, 1))

    def test_fd_nodes_and_filter(self):
        frames = cycle_frames(2, 0, 5, fd=True) + cycle_frames(1, 0, 5)
        self.assertEqual([(c.node, c.counter) for c in self.feed(tacse3.BusDecoder(), frames)],
                         [(2, 0), (1, 0)])
        self.assertEqual([c.node for c in self.feed(tacse3.BusDecoder(node=1), frames)], [1])
        mixed = cycle_frames(2, 0, 5, fd=True)[0]
        mixed.data[7 + 6] ^= 0x10  # the TwistAngular counter nibble differs
        mixed.data[63] = tacse3.codec.frame_crc(mixed.arbitration_id, False, mixed.data)
        d = tacse3.BusDecoder()
        self.assertEqual((self.feed(d, [mixed]), d.length_errors), ([], 1))

    def test_decode_example_reads_stdin(self):
        import subprocess
        import sys
        text = "".join(candump.format_line(f) + "\n" for f in cycle_frames(1, 0, 7))
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
        r = subprocess.run([sys.executable, os.path.join(REPO, "examples", "python",
                                                         "tacse3_decode.py"), "--log", "-"],
                           input=text, capture_output=True, text=True, env=env, timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r'^\{"type":"cycle","node":1,"counter":0,"t_us":7,')
        self.assertIn("node 1: 1 cycles", r.stderr)


if __name__ == "__main__":
    unittest.main()
