# SPDX-License-Identifier: Apache-2.0
"""Codec unit tests: the worked example of docs/can-protocol.md (hand-written golden bytes, as
tests/protocol/test_golden.cpp), CRC, scaling rules, identifiers, command arguments."""

import math
import unittest

import can

import tacse3
from tacse3 import codec, messages, table

GOLDEN = {  # identifier -> payload, node 1, cycle counter 5, status counter 7
    0x021: "D2 02 96 49 00 00 59 48", 0x022: "D2 04 0C FE 30 75 50 89",
    0x023: "FF 7F E0 B1 00 80 51 A7", 0x024: "D0 07 FA C0 60 E8 53 B6",
    0x025: "F4 01 18 FC A8 61 50 87"}
GOLDEN_CYCLE = tacse3.Cycle(node=1, t_us=1234567890, valid=True, wx=1.234, wy=-0.5, wz=30.0,
                            vx=5.0, vy=-2.0, vz=None, qw=0.5, qx=0.5, qy=-0.5, qz=0.5, px=0.01,
                            py=-0.02, pz=0.5)


def frame(can_id, hexdata, extended=False, fd=False):
    data = bytes.fromhex(hexdata)
    return can.Message(arbitration_id=can_id, is_extended_id=extended, is_fd=fd, data=data,
                       dlc=len(data))


class Crc(unittest.TestCase):
    def test_catalogue_check_value(self):
        self.assertEqual(tacse3.crc8(b"123456789"), 0x4B)

    def test_covers_identifier_word(self):
        data = bytes.fromhex(GOLDEN[0x021])
        self.assertEqual(codec.frame_crc(0x021, False, data), 0x48)
        self.assertNotEqual(codec.frame_crc(0x041, False, data), 0x48)
        # 29-bit: bit 31 of the id word is set (docs: the Timestamp of node 2 ends in 0x12)
        self.assertEqual(codec.frame_crc(0x1ACE0041, True, data), 0x12)


class Golden(unittest.TestCase):
    def test_classic_cycle_encodes_to_the_worked_example(self):
        frames, sent = tacse3.encode_cycle(GOLDEN_CYCLE, 5)
        self.assertEqual({f.arbitration_id: f.data.hex(" ").upper() for f in frames}, GOLDEN)
        self.assertTrue(sent.saturated)
        self.assertEqual(sent.sat_v, [True, False, False])
        self.assertEqual(sent.vx, 3.2767 * 1)  # clamped to +32767 LSB
        self.assertIsNone(sent.vz)

    def test_fd_cycle_is_the_five_prefixes(self):
        frames, _ = tacse3.encode_cycle(GOLDEN_CYCLE, 5, fd=True)
        self.assertEqual(len(frames), 1)
        data = bytes(frames[0].data)
        prefixes = b"".join(bytes.fromhex(GOLDEN[i])[:7] for i in sorted(GOLDEN))
        self.assertEqual(data[:35], prefixes)
        self.assertEqual(data[35:63], bytes(28))
        self.assertEqual(data[63], 0x08)
        self.assertTrue(frames[0].is_fd and frames[0].bitrate_switch)

    def test_cycle_decodes_from_the_worked_example(self):
        decoder = tacse3.BusDecoder()
        out = [o for i in sorted(GOLDEN) for o in decoder.feed(frame(i, GOLDEN[i]))]
        self.assertEqual(len(out), 1)
        c = out[0]
        self.assertEqual((c.node, c.counter, c.t_us, c.valid, c.saturated),
                         (1, 5, 1234567890, True, True))
        self.assertEqual((c.wx, c.wy, c.wz), (1234 * 0.001, -500 * 0.001, 30000 * 0.001))
        self.assertEqual((c.vx, c.vy, c.vz), (32767 * 0.0001, -20000 * 0.0001, None))
        self.assertEqual((c.qw, c.qx, c.qy, c.qz), (0.5, 0.5, -0.5, 0.5))
        self.assertEqual((c.px, c.py, c.pz), (500 * 0.00002, -1000 * 0.00002, 25000 * 0.00002))

    def test_status_frames(self):
        s = tacse3.decode(frame(0x028, "42 BB E1 02 00 03 70 72"))
        self.assertEqual((s.state, s.health_left, s.health_right), ("TRACKING", "OK", "STALE"))
        self.assertEqual((s.contact_left, s.contact_right, s.slip_left, s.slip_right),
                         (True, True, False, True))
        self.assertEqual((s.stream_enabled, s.fusion, s.velocity_mode),
                         (True, "PAPER", "DISPLACEMENT"))
        self.assertEqual((s.confidence, s.rate_divider, s.fault, s.rejected_commands, s.counter),
                         (225 * 0.004, 2, "NONE", 3, 7))
        self.assertEqual(s.encode().data.hex(" ").upper(), "42 BB E1 02 00 03 70 72")
        self.assertFalse(s.calibrated)
        cal = tacse3.decode(frame(0x028, "42 BB E1 02 00 03 71 6F"))  # Calibrated: bit 48
        self.assertTrue(cal.calibrated)
        self.assertEqual((cal.state, cal.rejected_commands, cal.counter), ("TRACKING", 3, 7))
        self.assertEqual(cal.encode().data.hex(" ").upper(), "42 BB E1 02 00 03 71 6F")
        c = tacse3.decode(frame(0x029, "D0 07 FF FF FA 7D 70 87"))
        self.assertEqual((c.area_left, c.area_right, c.confidence_left, c.confidence_right),
                         (2000 * 1e-7, None, 250 * 0.004, 125 * 0.004))
        t = tacse3.decode(frame(0x02A, "B2 0C 04 10 FE FF 70 DD"))
        self.assertEqual((t.dsp_time, t.latency_p50, t.latency_p99),
                         (3250 * 1e-6, 4100 * 1e-6, 65534 * 1e-6))
        n = tacse3.decode(frame(0x02B, "01 00 01 02 FF FF 70 EE"))
        self.assertEqual((n.dropped_left, n.dropped_right, n.can_tx_dropped), (1, 513, 65535))
        timing = tacse3.StatusTiming(node=1, counter=7, dsp_time=0.00325, latency_p50=0.0041,
                                     latency_p99=0.1)  # p99 clamps to 65.534 ms
        self.assertEqual(timing.encode().data.hex(" ").upper(), "B2 0C 04 10 FE FF 70 DD")

    def test_commands_and_acks(self):
        self.assertEqual(tacse3.encode_command(1, "TARE", 3).data.hex(" ").upper(),
                         "01 01 00 00 00 00 30 5E")
        f = tacse3.encode_command(1, "SET_FINGER_SEPARATION", 1, finger_separation=0.085)
        self.assertEqual((f.arbitration_id, f.data.hex(" ").upper()),
                         (0x030, "03 01 34 21 00 00 10 2E"))
        cmd = tacse3.decode(f)
        self.assertEqual((cmd.command, cmd.target_node, cmd.sequence), ("SET_FINGER_SEPARATION",
                                                                        1, 1))
        self.assertEqual(cmd.arguments, {"FingerSeparation": 8500 * 0.00001})
        ack = tacse3.decode(frame(0x031, "01 00 00 00 00 00 30 E6"))
        self.assertEqual((ack.command, ack.result, ack.sequence, ack.ok), ("TARE", "ACK", 3, True))
        nack = tacse3.Ack(1, "SET_RATE_DIVIDER", "OUT_OF_RANGE", 9, [200, 0, 0, 0])
        self.assertEqual(tacse3.encode_ack(nack).data.hex(" ").upper(), "05 05 C8 00 00 00 90 A6")
        self.assertEqual(tacse3.decode(tacse3.encode_ack(nack)), nack)
        rec = tacse3.encode_command(1, "START_RECORDING", 7, recording=12345)
        self.assertEqual(rec.data.hex(" ").upper(), "08 01 39 30 00 00 70 9F")
        self.assertEqual(tacse3.decode(rec).arguments, {"RecordingNumber": 12345})
        self.assertEqual(tacse3.encode_command(1, "STOP_RECORDING", 8).data.hex(" ").upper(),
                         "09 01 00 00 00 00 80 E0")
        busy = tacse3.decode(frame(0x031, "08 09 39 30 00 00 70 6B"))
        self.assertEqual((busy.command, busy.result, busy.data),
                         ("START_RECORDING", "ALREADY_RECORDING", [0x39, 0x30, 0, 0]))
        idle = tacse3.decode(frame(0x031, "09 0A 00 00 00 00 80 DE"))
        self.assertEqual((idle.command, idle.result), ("STOP_RECORDING", "NOT_RECORDING"))


class Scaling(unittest.TestCase):
    sig = table.BY_NAME["TwistLinear"].signal("LinVelX")  # LSB 1e-4, +-32767, invalid -32768

    def test_round_half_away_from_zero(self):
        self.assertEqual([codec._round_half_away(x) for x in (2.5, -2.5, 0.49999999999999994)],
                         [3, -3, 0])  # the last: std::round's answer, not floor(x + 0.5)'s
        self.assertEqual(codec.quantize(self.sig, 0.00025), (3, False))  # 0.00025/1e-4 = 2.5
        self.assertEqual(codec.quantize(self.sig, -0.00025), (-3, False))

    def test_saturates_to_the_valid_range_never_the_marker(self):
        self.assertEqual(codec.quantize(self.sig, -10.0), (-32767, True))
        self.assertEqual(codec.quantize(self.sig, 10.0), (32767, True))

    def test_invalid(self):
        for v in (None, math.nan, math.inf, -math.inf):
            self.assertEqual(codec.quantize(self.sig, v), (-32768, False))
        self.assertIsNone(codec.dequantize(self.sig, -32768))
        area = table.BY_NAME["StatusContact"].signal("AreaLeft")
        self.assertEqual(codec.quantize(area, None), (65535, False))

    def test_quaternion_normalised_with_w_non_negative(self):
        c = tacse3.Cycle(qw=-1.0, qx=0.0, qy=0.0, qz=-1.0)  # norm sqrt(2), w < 0
        _, sent = tacse3.encode_cycle(c, 0)
        self.assertEqual((sent.qw, sent.qz), (2828 * 0.00025, 2828 * 0.00025))
        _, sent = tacse3.encode_cycle(tacse3.Cycle(qw=3.0), 0)  # norm outside [0.5, 2]
        self.assertEqual((sent.qw, sent.qx), (None, None))


class Identifiers(unittest.TestCase):
    def test_layouts(self):
        ext = tacse3.IdLayout(extended=True)
        self.assertEqual(codec.compose_id(tacse3.IdLayout(), 1, 1), 0x021)
        self.assertEqual(codec.compose_id(ext, 2, 1), 0x1ACE0041)
        self.assertEqual(codec.split_id(ext, 0x1ACE0041, True), (2, 1))
        self.assertIsNone(codec.split_id(ext, 0x1ACF0041, True))  # other base
        self.assertIsNone(codec.split_id(tacse3.IdLayout(), 0x021, True))
        self.assertIsNone(codec.split_id(tacse3.IdLayout(), 0x001, False))  # node 0
        with self.assertRaisesRegex(ValueError, "bits 0..10"):
            tacse3.IdLayout(extended=True, extended_base=0x1ACE0001)
        with self.assertRaisesRegex(ValueError, "node id 64"):
            tacse3.encode_command(64, "TARE", 0)

    def test_frame_errors_name_the_reason(self):
        good = frame(0x021, GOLDEN[0x021])
        cases = {"crc": frame(0x021, "D2 02 96 49 00 00 59 49"),
                 "length": frame(0x021, "D2 02 96 49 00 00 59"),
                 "unknown_id": frame(0x027, GOLDEN[0x021])}
        tacse3.decode(good)
        for reason, f in cases.items():
            with self.assertRaises(tacse3.FrameError) as e:
                tacse3.decode(f)
            self.assertEqual(e.exception.reason, reason)
        fd = tacse3.encode_cycle(GOLDEN_CYCLE, 5, fd=True)[0][0]
        fd.is_fd = False
        with self.assertRaisesRegex(tacse3.FrameError, "CAN FD"):
            tacse3.decode(fd)


class CommandArguments(unittest.TestCase):
    def test_ranges_come_from_the_table(self):
        for kw in ({"finger_separation": 0.0009}, {"finger_separation": 0.2501},
                   {"finger_separation": math.nan}):
            with self.assertRaisesRegex(ValueError, "finger_separation"):
                tacse3.encode_command(1, "SET_FINGER_SEPARATION", 0, **kw)
        tacse3.encode_command(1, "SET_FINGER_SEPARATION", 0, finger_separation=0.25)
        with self.assertRaisesRegex(ValueError, "rate_divider=121"):
            tacse3.encode_command(1, "SET_RATE_DIVIDER", 0, rate_divider=121)
        with self.assertRaisesRegex(ValueError, "JOINT, PAPER"):
            tacse3.encode_command(1, "SET_FUSION", 0, fusion="BEST", velocity_mode="AUTO")
        with self.assertRaisesRegex(ValueError, "QUERY takes query, got none"):
            tacse3.encode_command(1, "QUERY", 0)
        with self.assertRaisesRegex(ValueError, "TARE takes no arguments"):
            tacse3.encode_command(1, "TARE", 0, stream=1)
        with self.assertRaisesRegex(ValueError, "unknown command"):
            tacse3.encode_command(1, 10, 0)
        with self.assertRaisesRegex(ValueError, "recording=65536 is outside 0 .. 65535"):
            tacse3.encode_command(1, "START_RECORDING", 0, recording=65536)

    def test_every_command_encodes(self):
        args = {"TARE": {}, "RESET_POSE": {}, "SET_FINGER_SEPARATION": {"finger_separation": 0.1},
                "SET_FUSION": {"fusion": "PAPER", "velocity_mode": "VELOCITY"},
                "SET_RATE_DIVIDER": {"rate_divider": 4}, "SET_STREAM": {"stream": 0},
                "QUERY": {"query": "STREAM"}, "START_RECORDING": {"recording": 65535},
                "STOP_RECORDING": {}}
        self.assertEqual(set(args), set(table.COMMANDS.values()))
        for name, kw in args.items():
            cmd = tacse3.decode(tacse3.encode_command(7, name, 9, **kw))
            self.assertEqual((cmd.command, cmd.target_node, cmd.sequence), (name, 7, 9))
            want = {messages.COMMAND_ARGUMENTS[k]: v for k, v in kw.items()}
            if "FingerSeparation" in want:
                want["FingerSeparation"] = 10000 * 0.00001
            self.assertEqual(cmd.arguments, want)


if __name__ == "__main__":
    unittest.main()
