# SPDX-License-Identifier: Apache-2.0
"""tacse3.Client against a simulated gripper on python-can's virtual bus: ACK, NACK, sequence
numbers, replies to be ignored, and the timeout's explanation of what the bus carried."""

import itertools
import threading
import time
import unittest

import can

import tacse3
from tacse3 import messages

_channels = itertools.count()


class FakeGripper(threading.Thread):
    """Answers the commands addressed to ``node`` as docs/can-protocol.md says: the Ack echoes
    the code, the sequence and argument bytes 2..5; ``answer(cmd)`` may return another Ack or
    None (no answer); ``before(cmd)`` frames are sent first (other nodes, stale replies)."""

    def __init__(self, channel, node=1, answer=None, before=None, chatter=None):
        super().__init__(daemon=True)
        self.bus = can.Bus(interface="virtual", channel=channel)
        self.node, self.answer, self.before, self.chatter = node, answer, before, chatter
        self.commands = []
        self.stop = threading.Event()

    def run(self):
        while not self.stop.is_set():
            if self.chatter is not None:
                self.bus.send(self.chatter)
            msg = self.bus.recv(0.005)
            if msg is None:
                continue
            try:
                cmd = messages.decode(msg)
            except tacse3.FrameError:
                continue
            if not isinstance(cmd, tacse3.Command) or cmd.node != self.node:
                continue
            self.commands.append(cmd)
            for f in (self.before(cmd) if self.before else []):
                self.bus.send(f)
            ack = tacse3.Ack(self.node, cmd.command, "ACK", cmd.sequence, cmd.args)
            if self.answer is not None:
                ack = self.answer(cmd)
            if ack is not None:
                self.bus.send(tacse3.encode_ack(ack))

    def close(self):
        self.stop.set()
        self.join()
        self.bus.shutdown()


class ClientTest(unittest.TestCase):
    def start(self, timeout=2.0, **kw):
        """A client (timeout generous enough for a loaded machine; answers end the wait) and a
        gripper on a fresh virtual bus."""
        channel = f"tacse3-test-{next(_channels)}"
        bus = can.Bus(interface="virtual", channel=channel)
        gripper = FakeGripper(channel, **kw)
        gripper.start()
        self.addCleanup(bus.shutdown)
        self.addCleanup(gripper.close)
        return tacse3.Client(bus, node=1, timeout=timeout), gripper

    def test_ack_with_incrementing_sequence(self):
        client, gripper = self.start()
        acks = [client.tare(), client.set_finger_separation(0.085), client.set_rate_divider(2)]
        self.assertEqual([(a.command, a.result, a.sequence) for a in acks],
                         [("TARE", "ACK", 0), ("SET_FINGER_SEPARATION", "ACK", 1),
                          ("SET_RATE_DIVIDER", "ACK", 2)])
        self.assertEqual(acks[1].data, [0x34, 0x21, 0, 0])  # 8500 x 1e-5 m echoed
        self.assertEqual([c.sequence for c in gripper.commands], [0, 1, 2])
        self.assertEqual(gripper.commands[1].arguments, {"FingerSeparation": 8500 * 0.00001})

    def test_sequence_wraps_after_15(self):
        client, gripper = self.start()
        for _ in range(18):
            client.reset_pose()
        self.assertEqual([c.sequence for c in gripper.commands][-3:], [15, 0, 1])

    def test_nack_raises_with_the_reason(self):
        client, _ = self.start(answer=lambda c: tacse3.Ack(1, c.command, "BUSY", c.sequence))
        with self.assertRaisesRegex(tacse3.NackError, r"node 1 rejected TARE \(seq 0\): BUSY"):
            client.tare()

    def test_recording_commands(self):
        client, gripper = self.start()
        ack = client.start_recording(42)
        self.assertEqual((ack.command, ack.data), ("START_RECORDING", [42, 0, 0, 0]))
        self.assertEqual(client.stop_recording().command, "STOP_RECORDING")
        self.assertEqual([(c.command, c.arguments) for c in gripper.commands],
                         [("START_RECORDING", {"RecordingNumber": 42}), ("STOP_RECORDING", {})])

    def test_recording_nack_names_the_reason(self):
        client, _ = self.start(answer=lambda c: tacse3.Ack(1, c.command, "RECORDING_EXISTS",
                                                           c.sequence, c.args))
        with self.assertRaisesRegex(tacse3.NackError, "START_RECORDING .*RECORDING_EXISTS"):
            client.start_recording(3)

    def test_other_nodes_and_sequences_are_ignored(self):
        def before(cmd):
            stale = tacse3.Ack(1, cmd.command, "BUSY", (cmd.sequence - 1) & 15)
            other = tacse3.Ack(2, cmd.command, "BUSY", cmd.sequence)
            wrong_cmd = tacse3.Ack(1, "RESET_POSE", "BUSY", cmd.sequence)
            return [tacse3.encode_ack(a) for a in (stale, other, wrong_cmd)]

        client, _ = self.start(before=before)
        self.assertTrue(client.tare().ok)

    def test_query_reply(self):
        def answer(cmd):
            return tacse3.Ack(1, "QUERY", "ACK", cmd.sequence, [4, 1, 3, 0b10])

        client, gripper = self.start(answer=answer)
        self.assertEqual(client.query("STREAM"),
                         {"item": "STREAM", "stream_enabled": True, "rate_divider": 3,
                          "fd_mode": False, "extended_ids": True})
        self.assertEqual(gripper.commands[0].arguments, {"QueryItem": "STREAM"})

    def test_timeout_on_a_silent_bus(self):
        client, _ = self.start(0.3, answer=lambda c: None)
        t0 = time.monotonic()
        with self.assertRaisesRegex(tacse3.AckTimeout,
                                    r"no ACK from node 1 for TARE \(seq 0\) within 0.3 s: the bus "
                                    r"carried no frames at all"):
            client.tare()
        self.assertGreaterEqual(time.monotonic() - t0, 0.3)

    def test_timeout_when_the_node_talks_but_does_not_answer(self):
        status = tacse3.Status(node=1, state="TRACKING").encode()
        client, _ = self.start(0.3, answer=lambda c: None, chatter=status)
        with self.assertRaisesRegex(tacse3.AckTimeout, r"node 1 is sending \(\d+ frames\) but "
                                                       "did not answer"):
            client.tare()

    def test_timeout_when_only_other_nodes_talk(self):
        status = tacse3.Status(node=2, state="TRACKING").encode()
        client, _ = self.start(0.3, answer=lambda c: None, chatter=status)
        with self.assertRaisesRegex(tacse3.AckTimeout, r"\d+ frames arrived, none from node 1 "
                                                       r"\(check the node id"):
            client.tare()

    def test_bad_arguments_are_refused_before_sending(self):
        client, gripper = self.start()
        with self.assertRaisesRegex(ValueError, "rate_divider=0"):
            client.set_rate_divider(0)
        time.sleep(0.05)
        self.assertEqual(gripper.commands, [])


if __name__ == "__main__":
    unittest.main()
