#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 example: decode tacse3 gripper CAN frames with python-can (live bus or candump -L log).
"""Decode the tacse3 gripper CAN protocol with python-can.

The scaling below is written out from docs/can-protocol.md (it is what protocol/tacse3.dbc
says), so this file needs nothing but Debian's python3-can:

    apt-get install python3-can
    /usr/bin/python3 tacse3_decode.py --log run.log            # candump -L log
    candump -L can0 | /usr/bin/python3 tacse3_decode.py --log -
    /usr/bin/python3 tacse3_decode.py --channel can0           # live SocketCAN

Output: one JSON object per line (the same keys as `tacse3-canmon --format json`) for every
complete cycle, status frame and ACK; a summary of counter gaps / CRC errors on stderr.
Use Debian's /usr/bin/python3: a python3 from pyenv/venv does not see python3-can.
"""

import argparse
import json
import sys

import can

# ---- identifiers (docs: "Identifiers") ----------------------------------------------------------
MSG_TIMESTAMP, MSG_ANGULAR, MSG_LINEAR, MSG_ORIENTATION, MSG_POSITION = 0x01, 0x02, 0x03, 0x04, 0x05
MSG_CYCLE_FD = 0x06
MSG_STATUS, MSG_CONTACT, MSG_TIMING, MSG_COUNTERS = 0x08, 0x09, 0x0A, 0x0B
MSG_COMMAND, MSG_ACK = 0x10, 0x11
LENGTH = {MSG_TIMESTAMP: 8, MSG_ANGULAR: 8, MSG_LINEAR: 8, MSG_ORIENTATION: 8, MSG_POSITION: 8,
          MSG_CYCLE_FD: 64, MSG_STATUS: 8, MSG_CONTACT: 8, MSG_TIMING: 8, MSG_COUNTERS: 8,
          MSG_COMMAND: 8, MSG_ACK: 8}
DEFAULT_EXTENDED_BASE = 0x1ACE0000

STATE = {0: "BOOTING", 1: "NO_CONTACT", 2: "TRACKING", 3: "DEGRADED_SINGLE_SENSOR", 4: "FAULT"}
HEALTH = {0: "OK", 1: "STALE", 2: "LOST", 3: "NOT_AVAILABLE"}
FUSION = {0: "JOINT", 1: "PAPER"}
VELOCITY_MODE = {0: "AUTO", 1: "VELOCITY", 2: "DISPLACEMENT"}
FAULT = {0: "NONE", 1: "LEFT_SENSOR_LOST", 2: "RIGHT_SENSOR_LOST", 3: "BOTH_SENSORS_LOST",
         4: "CALIBRATION_INVALID", 5: "DSP_OVERRUN", 6: "CAN_ERROR_PASSIVE",
         7: "CAN_BUS_OFF_RECOVERED"}
COMMAND = {1: "TARE", 2: "RESET_POSE", 3: "SET_FINGER_SEPARATION", 4: "SET_FUSION",
           5: "SET_RATE_DIVIDER", 6: "SET_STREAM", 7: "QUERY"}
ACK_RESULT = {0: "ACK", 1: "UNKNOWN_COMMAND", 2: "BAD_LENGTH", 3: "BAD_CRC", 4: "WRONG_NODE",
              5: "OUT_OF_RANGE", 6: "RESERVED_NOT_ZERO", 7: "BUSY", 8: "INTERNAL_ERROR"}

# ---- field tables: (name, start bit, bits, signed, LSB, decimals) ------------------------------
# Signed fields: the most negative value means "not available" (None); unsigned scaled fields:
# all ones means "not available".
ANGULAR = [("wx", 0, 16, True, 0.001, 3), ("wy", 16, 16, True, 0.001, 3),
           ("wz", 32, 16, True, 0.001, 3)]
LINEAR = [("vx", 0, 16, True, 0.0001, 4), ("vy", 16, 16, True, 0.0001, 4),
          ("vz", 32, 16, True, 0.0001, 4)]
ORIENTATION = [("qw", 0, 13, True, 0.00025, 5), ("qx", 13, 13, True, 0.00025, 5),
               ("qy", 26, 13, True, 0.00025, 5), ("qz", 39, 13, True, 0.00025, 5)]
POSITION = [("px", 0, 16, True, 0.00002, 5), ("py", 16, 16, True, 0.00002, 5),
            ("pz", 32, 16, True, 0.00002, 5)]


def crc8(data):
    """CRC-8/SAE-J1850: poly 0x1D, init 0xFF, no reflection, xorout 0xFF."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def frame_crc_ok(can_id, extended, data):
    """The CRC covers the 4-byte little-endian id word (bit 31 set for 29-bit ids) + data[:-1]."""
    word = (can_id | 0x80000000) if extended else can_id
    return crc8(word.to_bytes(4, "little") + bytes(data[:-1])) == data[-1]


def bits(data, start, length, signed=False):
    value = int.from_bytes(bytes(data), "little") >> start & ((1 << length) - 1)
    if signed and value >> (length - 1):
        value -= 1 << length
    return value


def scaled(data, start, length, is_signed, lsb, decimals, offset=0):
    raw = bits(data, start + offset, length, is_signed)
    if is_signed and raw == -(1 << (length - 1)):
        return None
    if not is_signed and raw == (1 << length) - 1:
        return None
    return round(raw * lsb, decimals)


def fields(table, data, offset=0):
    return {name: scaled(data, start, length, s, lsb, dec, offset)
            for name, start, length, s, lsb, dec in table}


class Decoder:
    """Reassembles cycles per node (all frames of one counter value, valid CRCs)."""

    PARTS = (MSG_TIMESTAMP, MSG_ANGULAR, MSG_LINEAR, MSG_ORIENTATION, MSG_POSITION)

    def __init__(self, extended=False, extended_base=DEFAULT_EXTENDED_BASE, node=0):
        self.extended = extended
        self.base = extended_base
        self.node_filter = node
        self.nodes = {}
        self.crc_errors = 0
        self.length_errors = 0

    def split_id(self, msg):
        if msg.is_extended_id != self.extended:
            return None
        can_id = msg.arbitration_id
        if self.extended:
            if can_id & ~0x7FF != self.base:
                return None
        elif can_id > 0x7FF:
            return None
        node, message = (can_id >> 5) & 0x3F, can_id & 0x1F
        if node == 0 or message not in LENGTH:
            return None
        return node, message

    def node_state(self, node):
        return self.nodes.setdefault(node, {"counter": None, "complete": False, "parts": {},
                                            "last_t": None, "cycles": 0, "gaps": 0,
                                            "repeated": 0, "incomplete": 0, "stale": 0})

    def feed(self, msg):
        """Returns a list of decoded objects (dicts) for this frame."""
        ids = self.split_id(msg)
        if ids is None or msg.is_remote_frame or msg.is_error_frame:
            return []
        node, message = ids
        if self.node_filter and node != self.node_filter:
            return []
        data = bytes(msg.data)
        fd_only = message == MSG_CYCLE_FD
        if len(data) != LENGTH[message] or (fd_only and not msg.is_fd):
            self.length_errors += 1
            return []
        if not frame_crc_ok(msg.arbitration_id, msg.is_extended_id, data):
            self.crc_errors += 1
            return []
        if message in self.PARTS:
            return self.cycle_part(node, {message: data})
        if message == MSG_CYCLE_FD:
            blocks = {part: data[7 * i:7 * i + 7] + b"\0" for i, part in enumerate(self.PARTS)}
            if len({bits(b, 52, 4) for b in blocks.values()}) != 1:
                self.length_errors += 1
                return []
            return self.cycle_part(node, blocks)
        return [self.other(node, message, data)]

    def cycle_part(self, node, parts):
        st = self.node_state(node)
        counter = bits(next(iter(parts.values())), 52, 4)
        if st["counter"] == counter:
            if st["complete"] or any(p in st["parts"] for p in parts):
                st["repeated"] += 1
                return []
        elif st["counter"] is not None:
            delta = (counter - st["counter"]) & 15
            if delta == 15:
                st["repeated"] += 1
                return []
            if not st["complete"]:
                st["incomplete"] += 1
            st["gaps"] += delta - 1
            st["counter"] = None
        if st["counter"] is None:
            st.update(counter=counter, complete=False, parts={})
        st["parts"].update(parts)
        if len(st["parts"]) < len(self.PARTS):
            return []
        st["complete"] = True
        cycle = self.cycle(node, counter, st["parts"])
        t = cycle["t_us"]
        if t is not None and st["last_t"] is not None and t <= st["last_t"]:
            st["stale"] += 1
            return []
        if t is not None:
            st["last_t"] = t
        st["cycles"] += 1
        return [cycle]

    @staticmethod
    def cycle(node, counter, parts):
        ts = parts[MSG_TIMESTAMP]
        t = bits(ts, 0, 48)
        out = {"type": "cycle", "node": node, "counter": counter,
               "t_us": None if t == (1 << 48) - 1 else t,
               "valid": bool(bits(ts, 48, 1)), "single_sensor": bool(bits(ts, 49, 1)),
               "pose_reset": bool(bits(ts, 50, 1)), "saturated": bool(bits(ts, 51, 1))}
        out.update(fields(ANGULAR, parts[MSG_ANGULAR]))
        out.update(fields(LINEAR, parts[MSG_LINEAR]))
        out.update(fields(ORIENTATION, parts[MSG_ORIENTATION]))
        out.update(fields(POSITION, parts[MSG_POSITION]))
        out["sat_w"] = [bool(bits(parts[MSG_ANGULAR], 48 + i, 1)) for i in range(3)]
        out["sat_v"] = [bool(bits(parts[MSG_LINEAR], 48 + i, 1)) for i in range(3)]
        out["sat_p"] = [bool(bits(parts[MSG_POSITION], 48 + i, 1)) for i in range(3)]
        return out

    @staticmethod
    def other(node, message, d):
        counter = bits(d, 52, 4)
        if message == MSG_STATUS:
            conf = bits(d, 16, 8)
            return {"type": "status", "node": node, "counter": counter,
                    "state": STATE.get(bits(d, 0, 4), bits(d, 0, 4)),
                    "health_left": HEALTH[bits(d, 4, 2)], "health_right": HEALTH[bits(d, 6, 2)],
                    "contact_left": bool(bits(d, 8, 1)), "contact_right": bool(bits(d, 9, 1)),
                    "slip_left": bool(bits(d, 10, 1)), "slip_right": bool(bits(d, 11, 1)),
                    "stream_enabled": bool(bits(d, 12, 1)), "fusion": FUSION[bits(d, 13, 1)],
                    "velocity_mode": VELOCITY_MODE.get(bits(d, 14, 2), bits(d, 14, 2)),
                    "confidence": None if conf == 255 else round(conf * 0.004, 3),
                    "rate_divider": bits(d, 24, 8),
                    "fault": FAULT.get(bits(d, 32, 8), bits(d, 32, 8)),
                    "rejected_commands": bits(d, 40, 8)}
        if message == MSG_CONTACT:
            return {"type": "status_contact", "node": node, "counter": counter,
                    "area_left": scaled(d, 0, 16, False, 1e-7, 7),
                    "area_right": scaled(d, 16, 16, False, 1e-7, 7),
                    "confidence_left": scaled(d, 32, 8, False, 0.004, 3),
                    "confidence_right": scaled(d, 40, 8, False, 0.004, 3)}
        if message == MSG_TIMING:
            return {"type": "status_timing", "node": node, "counter": counter,
                    "dsp_time": scaled(d, 0, 16, False, 1e-6, 6),
                    "latency_p50": scaled(d, 16, 16, False, 1e-6, 6),
                    "latency_p99": scaled(d, 32, 16, False, 1e-6, 6)}
        if message == MSG_COUNTERS:
            return {"type": "status_counters", "node": node, "counter": counter,
                    "dropped_left": bits(d, 0, 16), "dropped_right": bits(d, 16, 16),
                    "can_tx_dropped": bits(d, 32, 16)}
        if message == MSG_ACK:
            return {"type": "ack", "node": node, "command": COMMAND.get(d[0], d[0]),
                    "result": ACK_RESULT.get(d[1], d[1]), "sequence": counter,
                    "data": list(d[2:6])}
        return {"type": "command", "node": node, "command": COMMAND.get(d[0], d[0]),
                "target_node": d[1], "sequence": counter, "args": list(d[2:6])}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--log", help="candump -L log file, - for stdin")
    src.add_argument("--channel", help="live SocketCAN interface, e.g. can0")
    ap.add_argument("--node", type=int, default=0, help="only this node id")
    ap.add_argument("--extended", action="store_true", help="29-bit identifiers")
    ap.add_argument("--extended-base", type=lambda s: int(s, 0), default=DEFAULT_EXTENDED_BASE)
    args = ap.parse_args()

    decoder = Decoder(args.extended, args.extended_base, args.node)
    if args.log is not None:
        source = can.CanutilsLogReader(sys.stdin if args.log == "-" else args.log)
    else:
        source = can.Bus(interface="socketcan", channel=args.channel, fd=True)
    try:
        for msg in source:
            for obj in decoder.feed(msg):
                print(json.dumps(obj, separators=(",", ":")), flush=args.log is None)
    except KeyboardInterrupt:
        pass
    for node, st in sorted(decoder.nodes.items()):
        print(f"tacse3_decode: node {node}: {st['cycles']} cycles, counter gaps {st['gaps']}, "
              f"repeated {st['repeated']}, incomplete {st['incomplete']}, stale {st['stale']}",
              file=sys.stderr)
    print(f"tacse3_decode: {decoder.crc_errors} CRC errors, {decoder.length_errors} length errors",
          file=sys.stderr)


if __name__ == "__main__":
    main()
