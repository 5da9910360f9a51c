# SPDX-License-Identifier: Apache-2.0
"""Round trips against the C++ codec: every case of tests/python/cxx_vectors.cpp (the worked
example, random cycles, status groups, commands, ACKs, query replies, random and corrupted
frames) must encode to the C++ encoder's bytes and decode to the C++ decoder's values, exactly.

ctest (python_unit) passes the C++ program's output in TACSE3_CXX_VECTORS; outside ctest the
tests are skipped, unless TACSE3_REQUIRE_CXX_VECTORS=1."""

import json
import os
import unittest

import can

import tacse3
from tacse3 import codec, messages

PATH = os.environ.get("TACSE3_CXX_VECTORS")


def load():
    if not PATH:
        if os.environ.get("TACSE3_REQUIRE_CXX_VECTORS") == "1":
            raise RuntimeError("TACSE3_CXX_VECTORS is not set")
        return None
    with open(PATH) as f:
        return [json.loads(line) for line in f]


CASES = load()


def to_message(f):
    data = bytes.fromhex(f["data"])
    return can.Message(arbitration_id=f["id"], is_extended_id=f["extended"], is_fd=f["fd"],
                       bitrate_switch=f["brs"], data=data, dlc=len(data))


def frame_dict(m):
    return {"id": m.arbitration_id, "extended": m.is_extended_id, "fd": m.is_fd,
            "brs": m.bitrate_switch, "data": bytes(m.data).hex().upper()}


def layout_of(case):
    return tacse3.IdLayout(case["extended"], case["extended_base"])


def vec(x, y, z):
    return [x, y, z]


def cycle_dict(c):
    return {"t_us": c.t_us, "valid": c.valid, "single_sensor": c.single_sensor,
            "pose_reset": c.pose_reset, "saturated": c.saturated, "counter": c.counter,
            "w": vec(c.wx, c.wy, c.wz), "v": vec(c.vx, c.vy, c.vz),
            "q": [c.qw, c.qx, c.qy, c.qz], "p": vec(c.px, c.py, c.pz), "sat_w": c.sat_w,
            "sat_v": c.sat_v, "sat_p": c.sat_p}


def part_dict(d):
    """A classic cycle part in the shape of the C++ program's typed message."""
    s = d.signals
    if d.message == "Timestamp":
        return {"t_us": 0xFFFFFFFFFFFF if s["SampleTime"] is None else s["SampleTime"],
                "valid": s["EstimateValid"], "single_sensor": s["SingleSensor"],
                "pose_reset": s["PoseReset"], "saturated": s["Saturated"],
                "counter": s["Counter"]}
    if d.message == "PoseOrientation":
        return {"q": [s["QuatW"], s["QuatX"], s["QuatY"], s["QuatZ"]], "counter": s["Counter"]}
    keys = messages._CYCLE_SIGNALS[d.message].values()
    return {"v": [s[k] for k in keys], "sat": [s[k + "Sat"] for k in keys],
            "counter": s["Counter"]}


def py_decoded(msg, layout):
    """Python's reading of one frame, in the shape of the C++ program's."""
    try:
        obj = messages.decode(msg, layout)
    except codec.FrameError as e:
        return {"status": e.reason}
    if isinstance(obj, codec.Decoded):
        value, name = part_dict(obj), obj.message
    elif isinstance(obj, tacse3.Cycle):
        value, name = cycle_dict(obj), "CycleFd"
        value["t_us"] = 0xFFFFFFFFFFFF if value["t_us"] is None else value["t_us"]
    elif isinstance(obj, tacse3.Ack):
        value, name = obj.to_json(), "Ack"
        value["data"] = bytes(obj.data).hex().upper()
        try:
            reply = obj.query_reply()
        except ValueError:
            reply = None
        if reply is not None:
            # The C++ QueryReply has every field; the ones the item does not set are defaults.
            full = {"item": reply["item"], "version": [0, 0, 0], "finger_separation": 0.0,
                    "fusion": "JOINT", "velocity_mode": "AUTO", "stream_enabled": False,
                    "rate_divider": 1, "fd_mode": False, "extended_ids": False}
            full.update({k: list(v) if k == "version" else v for k, v in reply.items()})
            reply = full
        value["query_reply"] = reply
    elif isinstance(obj, tacse3.Command):
        value, name = obj.to_json(), "Command"
        value["args"] = bytes(obj.args).hex().upper()
    else:
        value, name = obj.to_json(), obj.MESSAGE
    for k in ("type", "node"):
        value.pop(k, None)
    return {"status": "ok", "node": obj.node, "message": name, "value": value}


@unittest.skipIf(CASES is None, "TACSE3_CXX_VECTORS not set (run through ctest)")
class CxxVectors(unittest.TestCase):
    def cases(self, kind):
        out = [c for c in CASES if c["kind"] == kind]
        self.assertGreater(len(out), 0, f"no '{kind}' cases")
        return out

    def check_decoded(self, case):
        layout = layout_of(case)
        for f, want in zip(case["frames"], case["decoded"]):
            self.assertEqual(py_decoded(to_message(f), layout), want, f)

    def test_cycles(self):
        for case in self.cases("cycle"):
            c = case["input"]["cycle"]
            cycle = tacse3.Cycle(case["node"], 0, c["t_us"], c["valid"], c["single_sensor"],
                                 c["pose_reset"], False, *c["w"], *c["v"], *c["q"], *c["p"])
            frames, sent = tacse3.encode_cycle(cycle, case["input"]["counter"], layout_of(case),
                                               case["fd"], case["brs"])
            self.assertEqual([frame_dict(m) for m in frames], case["frames"], case["input"])
            want = dict(case["input"]["sent"])
            want["t_us"] = None if want["t_us"] == 0xFFFFFFFFFFFF else want["t_us"]
            self.assertEqual(cycle_dict(sent), want)
            self.check_decoded(case)

    def test_status_groups(self):
        for case in self.cases("status"):
            inp, counter = case["input"], case["input"]["counter"] & 0x0F
            frames = []
            for key, cls in (("status", tacse3.Status), ("contact", tacse3.StatusContact),
                             ("timing", tacse3.StatusTiming),
                             ("counters", tacse3.StatusCounters)):
                fields = dict(inp[key], counter=counter)
                frames.append(frame_dict(cls(node=case["node"], **fields).encode(
                    layout_of(case))))
            self.assertEqual(frames, case["frames"], inp)
            self.check_decoded(case)

    def test_commands(self):
        for case in self.cases("command"):
            inp = case["input"]
            if inp["rejected"]:
                with self.assertRaises(ValueError, msg=inp):
                    tacse3.encode_command(case["node"], inp["command"], inp["sequence"],
                                          layout_of(case), **inp["arguments"])
                continue
            m = tacse3.encode_command(case["node"], inp["command"], inp["sequence"],
                                      layout_of(case), **inp["arguments"])
            self.assertEqual([frame_dict(m)], case["frames"], inp)
            self.check_decoded(case)
        self.assertTrue(any(c["input"]["rejected"] for c in CASES if c["kind"] == "command"))

    def test_acks(self):
        for case in self.cases("ack"):
            inp = case["input"]
            ack = tacse3.Ack(case["node"], inp["command"], inp["result"], inp["sequence"],
                             list(bytes.fromhex(inp["data"])))
            self.assertEqual([frame_dict(tacse3.encode_ack(ack, layout_of(case)))],
                             case["frames"], inp)
            self.check_decoded(case)

    def test_random_and_corrupted_frames(self):
        statuses = set()
        for case in self.cases("raw"):
            self.check_decoded(case)
            statuses.update(d["status"] for d in case["decoded"])
        self.assertTrue({"ok", "crc", "length", "counter"} <= statuses, statuses)


if __name__ == "__main__":
    unittest.main()
