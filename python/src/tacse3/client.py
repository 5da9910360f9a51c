# SPDX-License-Identifier: Apache-2.0
"""A blocking command client: send a command, wait for its ACK/NACK (docs/can-protocol.md,
"Commands and ACK/NACK")."""

import time

import can

from . import codec, messages, table
from .codec import IdLayout

DEFAULT_TIMEOUT_S = 0.25  # the gripper answers within one cycle (<= 10 ms); as tacse3-ctl


class ClientError(RuntimeError):
    """The command could not be sent or was not answered."""


class NackError(ClientError):
    """The gripper rejected the command; ``ack.result`` names the reason."""

    def __init__(self, ack):
        super().__init__(f"node {ack.node} rejected {ack.command} (seq {ack.sequence}): "
                         f"{ack.result}")
        self.ack = ack


class AckTimeout(ClientError, TimeoutError):
    """No matching ACK/NACK before the timeout; the message says what the bus did carry."""


class Client:
    """Commands to one gripper on a python-can bus (e.g. ``can.Bus(interface="socketcan",
    channel="can0")``). Each call sends one command frame with the next sequence number
    (0..15, wrapping) and blocks until the Ack of that node, command and sequence arrives: it
    returns the Ack, raises NackError for a NACK and AckTimeout after ``timeout`` seconds.
    Every other frame received meanwhile is consumed and ignored. Not thread-safe: one Client
    per bus and thread."""

    def __init__(self, bus, node=1, layout=IdLayout(), timeout=DEFAULT_TIMEOUT_S, fd=False,
                 first_sequence=0):
        if not codec.MIN_NODE_ID <= node <= codec.MAX_NODE_ID:
            raise ValueError(f"node id {node} is outside {codec.MIN_NODE_ID}..{codec.MAX_NODE_ID}")
        self.bus = bus
        self.node = node
        self.layout = layout
        self.timeout = timeout
        self.fd = fd
        self._sequence = first_sequence & 0x0F

    def send(self, command, **arguments):
        """Send ``command`` (name or code; arguments as messages.encode_command) and wait."""
        seq = self._sequence
        self._sequence = (seq + 1) & 0x0F
        frame = messages.encode_command(self.node, command, seq, self.layout, self.fd, **arguments)
        name = table.COMMANDS.get(frame.data[0], frame.data[0])
        try:
            self.bus.send(frame, timeout=self.timeout)
        except can.CanError as e:
            raise ClientError(f"cannot send {name} to node {self.node}: {e}") from e
        return self._wait(name, seq)

    def _wait(self, name, seq):
        deadline = time.monotonic() + self.timeout
        frames = from_node = 0
        while (left := deadline - time.monotonic()) > 0:
            msg = self.bus.recv(timeout=left)
            if msg is None:
                break
            frames += 1
            ids = codec.split_id(self.layout, msg.arbitration_id, msg.is_extended_id)
            if ids is None or ids[0] != self.node or ids[1] == table.BY_NAME["Command"].id:
                continue
            from_node += 1
            try:
                ack = messages.decode(msg, self.layout)
            except codec.FrameError:
                continue
            if isinstance(ack, messages.Ack) and ack.command == name and ack.sequence == seq:
                if not ack.ok:
                    raise NackError(ack)
                return ack
        raise AckTimeout(self._timeout_text(name, seq, frames, from_node))

    def _timeout_text(self, name, seq, frames, from_node):
        head = f"no ACK from node {self.node} for {name} (seq {seq}) within {self.timeout:g} s: "
        if frames == 0:
            return head + ("the bus carried no frames at all (is the interface up at the "
                           "gripper's bit rate, and is tacse3d running?)")
        if from_node == 0:
            return head + (f"{frames} frames arrived, none from node {self.node} (check the node "
                           "id and the 11/29-bit identifier layout)")
        return head + (f"node {self.node} is sending ({from_node} frames) but did not answer "
                       "(is this controller's frame reaching the bus, e.g. not listen-only?)")

    # ---- one method per command -----------------------------------------------------------
    def tare(self):
        return self.send("TARE")

    def reset_pose(self):
        return self.send("RESET_POSE")

    def set_finger_separation(self, metres):
        return self.send("SET_FINGER_SEPARATION", finger_separation=metres)

    def set_fusion(self, fusion, velocity_mode="AUTO"):
        return self.send("SET_FUSION", fusion=fusion, velocity_mode=velocity_mode)

    def set_rate_divider(self, divider):
        return self.send("SET_RATE_DIVIDER", rate_divider=divider)

    def set_stream(self, enabled):
        return self.send("SET_STREAM", stream=int(bool(enabled)))

    def start_recording(self, number):
        """Record to rec-NNNNN (5 digits) under the gripper's record directory; NackError with
        ALREADY_RECORDING, NO_RECORD_DIR, RECORDING_EXISTS or DISK_ERROR."""
        return self.send("START_RECORDING", recording=number)

    def stop_recording(self):
        """Stop the recording; NackError NOT_RECORDING, or DISK_ERROR if a write had failed."""
        return self.send("STOP_RECORDING")

    def query(self, item):
        """The reply to QUERY ``item`` (PROTOCOL_VERSION, FIRMWARE_VERSION, FINGER_SEPARATION,
        FUSION, STREAM) as a dict, see messages.Ack.query_reply."""
        return self.send("QUERY", query=item).query_reply()
