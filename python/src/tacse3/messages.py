# SPDX-License-Identifier: Apache-2.0
"""Typed messages: a whole cycle, the status frames, commands and ACKs, and their encoders.

Field names are tacse3-canmon's JSON keys (``to_json()`` gives canmon's objects); each class maps
them to the table's signal names, so scaling, ranges and value names come from the table.
"""

import math
from dataclasses import asdict, dataclass, field
from typing import ClassVar

from . import codec, table
from .codec import IdLayout

CYCLE_PARTS = ("Timestamp", "TwistAngular", "TwistLinear", "PoseOrientation", "PosePosition")
_FD_BLOCK_BYTES = 7  # CycleFd: each classic payload without its CRC byte, back to back


class _Message:
    TYPE: ClassVar[str] = ""
    MESSAGE: ClassVar[str] = ""
    SIGNALS: ClassVar[dict] = {}  # key -> signal name

    @classmethod
    def from_decoded(cls, d):
        return cls(node=d.node, **{k: d.signals[s] for k, s in cls.SIGNALS.items()})

    def to_json(self):
        """canmon's JSON object of this message (``json.dumps`` it)."""
        return {"type": self.TYPE, **asdict(self)}

    def encode(self, layout=IdLayout(), fd=False):
        """The frame of this message from ``self.node``; out-of-range values are clamped."""
        return codec.encode(self.MESSAGE, {s: getattr(self, k) for k, s in self.SIGNALS.items()},
                            self.node, layout, fd)


@dataclass
class Status(_Message):
    TYPE: ClassVar[str] = "status"
    MESSAGE: ClassVar[str] = "Status"
    SIGNALS: ClassVar[dict] = {
        "counter": "Counter", "state": "State", "health_left": "HealthLeft",
        "health_right": "HealthRight", "contact_left": "ContactLeft",
        "contact_right": "ContactRight", "slip_left": "SlipLeft", "slip_right": "SlipRight",
        "stream_enabled": "StreamEnabled", "fusion": "FusionMethod",
        "velocity_mode": "VelocityMode", "confidence": "Confidence",
        "rate_divider": "RateDivider", "fault": "FaultCode",
        "rejected_commands": "RejectedCommands", "calibrated": "Calibrated"}
    node: int = 1
    counter: int = 0
    state: object = "BOOTING"
    health_left: object = "NOT_AVAILABLE"
    health_right: object = "NOT_AVAILABLE"
    contact_left: bool = False
    contact_right: bool = False
    slip_left: bool = False
    slip_right: bool = False
    stream_enabled: bool = True
    fusion: object = "JOINT"
    velocity_mode: object = "AUTO"
    confidence: object = 0.0  # 0..1, None = not available
    rate_divider: int = 1
    fault: object = "NONE"
    rejected_commands: int = 0  # mod 256
    calibrated: bool = False  # a fitted calibration runs (False: UNCALIBRATED)


@dataclass
class StatusContact(_Message):
    TYPE: ClassVar[str] = "status_contact"
    MESSAGE: ClassVar[str] = "StatusContact"
    SIGNALS: ClassVar[dict] = {"counter": "Counter", "area_left": "AreaLeft",
                               "area_right": "AreaRight", "confidence_left": "ConfidenceLeft",
                               "confidence_right": "ConfidenceRight"}
    node: int = 1
    counter: int = 0
    area_left: object = 0.0  # m^2, None = not available
    area_right: object = 0.0
    confidence_left: object = 0.0  # 0..1
    confidence_right: object = 0.0


@dataclass
class StatusTiming(_Message):
    TYPE: ClassVar[str] = "status_timing"
    MESSAGE: ClassVar[str] = "StatusTiming"
    SIGNALS: ClassVar[dict] = {"counter": "Counter", "dsp_time": "DspTime",
                               "latency_p50": "LatencyP50", "latency_p99": "LatencyP99"}
    node: int = 1
    counter: int = 0
    dsp_time: object = 0.0  # s, None = not available
    latency_p50: object = 0.0
    latency_p99: object = 0.0


@dataclass
class StatusCounters(_Message):
    TYPE: ClassVar[str] = "status_counters"
    MESSAGE: ClassVar[str] = "StatusCounters"
    SIGNALS: ClassVar[dict] = {"counter": "Counter", "dropped_left": "DroppedLeft",
                               "dropped_right": "DroppedRight", "can_tx_dropped": "CanTxDropped"}
    node: int = 1
    counter: int = 0
    dropped_left: int = 0  # mod 65536
    dropped_right: int = 0
    can_tx_dropped: int = 0


@dataclass
class Command:
    """A command frame as decoded (not validated): ``arguments`` holds the signals the command
    code selects, by signal name; ``args`` the raw payload bytes 2..5."""

    TYPE: ClassVar[str] = "command"
    node: int
    command: object  # name, or the code if it has none
    target_node: int
    sequence: int
    arguments: dict = field(default_factory=dict)
    args: list = field(default_factory=list)

    def to_json(self):
        return {"type": self.TYPE, **asdict(self)}


@dataclass
class Ack:
    """An ACK (``result == "ACK"``) or NACK (``result`` names the reason)."""

    TYPE: ClassVar[str] = "ack"
    node: int
    command: object  # name of the answered command, or its code
    result: object  # "ACK" or the NACK reason (its number if it has no name)
    sequence: int
    data: list = field(default_factory=lambda: [0, 0, 0, 0])  # payload bytes 2..5

    @property
    def ok(self):
        return self.result == "ACK"

    def to_json(self):
        return {"type": self.TYPE, **asdict(self)}

    def query_reply(self):
        """The data of an ACK to QUERY as a dict (see docs/can-protocol.md, QUERY items)."""
        if self.command != "QUERY" or not self.ok:
            raise ValueError(f"not an ACK to QUERY: {self.command} {self.result}")
        d = self.data
        item = table.QUERY_ITEMS.get(d[0], d[0])
        if item in ("PROTOCOL_VERSION", "FIRMWARE_VERSION"):
            return {"item": item, "version": (d[1], d[2], d[3])}
        if item == "FINGER_SEPARATION":
            sig = table.BY_NAME["Command"].signal("FingerSeparation")
            return {"item": item, "finger_separation": codec.dequantize(sig, d[1] | d[2] << 8)}
        if item == "FUSION":
            return {"item": item,
                    "fusion": _name(table.BY_NAME["Command"].signal("FusionMethod"), d[1]),
                    "velocity_mode": _name(table.BY_NAME["Command"].signal("VelocityMode"), d[2])}
        if item == "STREAM":
            return {"item": item, "stream_enabled": d[1] != 0, "rate_divider": d[2],
                    "fd_mode": bool(d[3] & 1), "extended_ids": bool(d[3] & 2)}
        raise ValueError(f"QUERY reply with unknown item {item}")


def _name(sig, raw):
    return sig.values.get(raw, raw)


@dataclass
class Cycle:
    """One pipeline cycle: twist and pose of the object in the gripper frame G (SI units).
    None means "not available"; the ``sat_*`` flags say a component was clamped to its range."""

    TYPE: ClassVar[str] = "cycle"
    node: int = 1
    counter: int = 0
    t_us: object = 0  # sample time on the board's monotonic clock, None = not available
    valid: bool = False
    single_sensor: bool = False
    pose_reset: bool = False
    saturated: bool = False
    wx: object = 0.0  # rad/s
    wy: object = 0.0
    wz: object = 0.0
    vx: object = 0.0  # m/s
    vy: object = 0.0
    vz: object = 0.0
    qw: object = 1.0  # unit quaternion, w >= 0
    qx: object = 0.0
    qy: object = 0.0
    qz: object = 0.0
    px: object = 0.0  # m
    py: object = 0.0
    pz: object = 0.0
    sat_w: list = field(default_factory=lambda: [False] * 3)
    sat_v: list = field(default_factory=lambda: [False] * 3)
    sat_p: list = field(default_factory=lambda: [False] * 3)

    def to_json(self):
        return {"type": self.TYPE, **asdict(self)}


# Cycle key -> signal name, per part (the CycleFd frame carries the same names).
_CYCLE_SIGNALS = {
    "Timestamp": {"t_us": "SampleTime", "valid": "EstimateValid", "single_sensor": "SingleSensor",
                  "pose_reset": "PoseReset", "saturated": "Saturated"},
    "TwistAngular": {"wx": "AngVelX", "wy": "AngVelY", "wz": "AngVelZ"},
    "TwistLinear": {"vx": "LinVelX", "vy": "LinVelY", "vz": "LinVelZ"},
    "PoseOrientation": {"qw": "QuatW", "qx": "QuatX", "qy": "QuatY", "qz": "QuatZ"},
    "PosePosition": {"px": "PosX", "py": "PosY", "pz": "PosZ"},
}
_CYCLE_SATURATION = {"TwistAngular": ("sat_w", ("AngVelXSat", "AngVelYSat", "AngVelZSat")),
                     "TwistLinear": ("sat_v", ("LinVelXSat", "LinVelYSat", "LinVelZSat")),
                     "PosePosition": ("sat_p", ("PosXSat", "PosYSat", "PosZSat"))}


def cycle_from_parts(node, counter, parts):
    """A Cycle from the signals of its five parts (part name -> signal dict)."""
    c = Cycle(node=node, counter=counter)
    for part, keys in _CYCLE_SIGNALS.items():
        for key, sig in keys.items():
            setattr(c, key, parts[part][sig])
    for part, (key, sigs) in _CYCLE_SATURATION.items():
        setattr(c, key, [parts[part][s] for s in sigs])
    return c


def cycle_from_fd(d):
    """A Cycle from a decoded CycleFd frame; FrameError if its five counters differ."""
    counters = {d.signals[n] for n in d.signals if n.startswith("Counter")}
    if len(counters) != 1:
        raise codec.FrameError("counter", f"CycleFd of node {d.node}: the five counters differ")
    return cycle_from_parts(d.node, counters.pop(), {p: d.signals for p in CYCLE_PARTS})


def from_decoded(d):
    """The typed message of a decoded frame; a classic cycle part stays a codec.Decoded (the
    reassembler combines the five)."""
    if d.message in CYCLE_PARTS:
        return d
    if d.message == "CycleFd":
        return cycle_from_fd(d)
    for cls in (Status, StatusContact, StatusTiming, StatusCounters):
        if d.message == cls.MESSAGE:
            return cls.from_decoded(d)
    raise AssertionError(f"no typed message for {d.message}")  # Command, Ack: see decode()


def decode(msg, layout=IdLayout()):
    """Decode one frame into Cycle (CAN FD), Status..., Command, Ack, or a codec.Decoded cycle
    part. Raises codec.FrameError for a frame that is not a valid tacse3 frame."""
    node, mdef = codec.check_frame(msg, layout)
    data = bytes(msg.data)
    if mdef.name == "Ack":
        # Bytes 2..5 are an argument echo or query data: opaque here, as in the C++ decoder.
        return Ack(node, table.COMMANDS.get(data[0], data[0]),
                   table.ACK_RESULTS.get(data[1], data[1]), data[6] >> 4, list(data[2:6]))
    d = codec.decode(msg, layout)
    if mdef.name == "Command":
        s = d.signals
        args = {k: v for k, v in s.items()
                if k not in ("CommandCode", "TargetNode", "Sequence", "Crc")}
        return Command(node, s["CommandCode"], s["TargetNode"], s["Sequence"], args,
                       list(data[2:6]))
    return from_decoded(d)


# ---- encoders -------------------------------------------------------------------------------
def _vec3_raw(part, values, counter):
    mdef = table.BY_NAME[part]
    names = list(_CYCLE_SIGNALS[part].values())
    sat_names = _CYCLE_SATURATION[part][1]
    raw = {"Counter": counter}
    for name, sat_name, v in zip(names, sat_names, values):
        raw[name], sat = codec.quantize(mdef.signal(name), v)
        raw[sat_name] = int(sat)
    return raw


def _orientation_raw(q, counter):
    mdef = table.BY_NAME["PoseOrientation"]
    sigs = [mdef.signal(n) for n in ("QuatW", "QuatX", "QuatY", "QuatZ")]
    finite = all(v is not None and math.isfinite(v) for v in q)
    n2 = sum(v * v for v in q) if finite else math.nan
    raw = {"Counter": counter}
    if not (finite and 0.25 <= n2 <= 4.0):
        raw.update({s.name: s.invalid_raw for s in sigs})
    else:
        # q and -q are the same rotation; send the one with w >= 0.
        k = (-1.0 if q[0] < 0.0 else 1.0) / math.sqrt(n2)
        raw.update({s.name: codec.quantize(s, v * k)[0] for s, v in zip(sigs, q)})
    return raw


def encode_cycle(cycle, counter, layout=IdLayout(), fd=False, brs=True):
    """Frames of one cycle from ``cycle.node``: five classic frames (Timestamp, TwistAngular,
    TwistLinear, PoseOrientation, PosePosition) or one CycleFd frame. Out-of-range values are
    clamped and flagged, None/NaN sent as invalid, the quaternion normalised with w >= 0 (invalid
    if its norm is outside [0.5, 2]). Returns (frames, the cycle as a receiver decodes it)."""
    counter &= 0x0F
    raw = {"TwistAngular": _vec3_raw("TwistAngular", (cycle.wx, cycle.wy, cycle.wz), counter),
           "TwistLinear": _vec3_raw("TwistLinear", (cycle.vx, cycle.vy, cycle.vz), counter),
           "PoseOrientation": _orientation_raw((cycle.qw, cycle.qx, cycle.qy, cycle.qz), counter),
           "PosePosition": _vec3_raw("PosePosition", (cycle.px, cycle.py, cycle.pz), counter)}
    saturated = any(v for r in raw.values() for k, v in r.items() if k.endswith("Sat"))
    t_sig = table.BY_NAME["Timestamp"].signal("SampleTime")
    t = cycle.t_us
    raw["Timestamp"] = {
        "SampleTime": t if t is not None and 0 <= t <= t_sig.raw_max else t_sig.invalid_raw,
        "EstimateValid": int(cycle.valid), "SingleSensor": int(cycle.single_sensor),
        "PoseReset": int(cycle.pose_reset), "Saturated": int(saturated), "Counter": counter}
    payloads = [codec.pack_raw(table.BY_NAME[p], raw[p]) for p in CYCLE_PARTS]
    if fd:
        data = bytearray(table.BY_NAME["CycleFd"].length)
        for i, p in enumerate(payloads):
            data[i * _FD_BLOCK_BYTES:(i + 1) * _FD_BLOCK_BYTES] = p[:_FD_BLOCK_BYTES]
        frames = [codec.make_message("CycleFd", cycle.node, data, layout, True, brs)]
        sent = cycle_from_fd(codec.decode(frames[0], layout))
    else:
        frames = [codec.make_message(p, cycle.node, d, layout) for p, d in zip(CYCLE_PARTS,
                                                                                payloads)]
        sent = cycle_from_parts(cycle.node, counter,
                                {p: codec.decode(f, layout).signals
                                 for p, f in zip(CYCLE_PARTS, frames)})
    return frames, sent


# Keyword argument of encode_command -> the Command signal it sets.
COMMAND_ARGUMENTS = {"finger_separation": "FingerSeparation", "fusion": "FusionMethod",
                     "velocity_mode": "VelocityMode", "rate_divider": "RateDivider",
                     "stream": "StreamEnable", "query": "QueryItem",
                     "recording": "RecordingNumber"}


def _command_code(command):
    sig = table.BY_NAME["Command"].signal("CommandCode")
    code = sig.raw_of_name(command) if isinstance(command, str) else int(command)
    if code not in sig.values:
        raise ValueError(f"unknown command {command!r} (one of {', '.join(sig.values.values())})")
    return code


def _argument_raw(sig, key, value):
    if sig.role == "value":
        raw, sat = codec.quantize(sig, value)
        if sat or value is None or not math.isfinite(value):
            lo, hi = sig.raw_min * sig.factor, sig.raw_max * sig.factor
            raise ValueError(f"{key}={value!r} is outside {lo:g} .. {hi:g} {sig.unit}".rstrip())
        return raw
    if sig.role == "enum":
        raw = sig.raw_of_name(value) if isinstance(value, str) else int(value)
        if raw not in sig.values:
            raise ValueError(f"{key}={value!r}: one of {', '.join(sig.values.values())}")
        return raw
    raw = int(value)
    if not sig.raw_min <= raw <= sig.raw_max:
        raise ValueError(f"{key}={value!r} is outside {sig.raw_min} .. {sig.raw_max}")
    return raw


def encode_command(node, command, sequence, layout=IdLayout(), fd=False, **arguments):
    """The command frame addressed to ``node`` (identifier and TargetNode). ``command`` is a name
    (TARE, RESET_POSE, SET_FINGER_SEPARATION, SET_FUSION, SET_RATE_DIVIDER, SET_STREAM, QUERY,
    START_RECORDING, STOP_RECORDING) or code; its arguments are keywords (see
    COMMAND_ARGUMENTS): SET_FINGER_SEPARATION finger_separation [m]; SET_FUSION fusion,
    velocity_mode; SET_RATE_DIVIDER rate_divider; SET_STREAM stream; QUERY query;
    START_RECORDING recording (0..65535). ValueError if one is missing, extra or out of range."""
    mdef = table.BY_NAME["Command"]
    code = _command_code(command)
    wanted = {k for k, s in COMMAND_ARGUMENTS.items() if mdef.signal(s).mux == code}
    if set(arguments) != wanted:
        name = table.COMMANDS[code]
        raise ValueError(f"{name} takes {', '.join(sorted(wanted)) or 'no arguments'}, "
                         f"got {', '.join(sorted(arguments)) or 'none'}")
    raw = {"CommandCode": code, "TargetNode": node, "Sequence": sequence & 0x0F}
    for key, value in arguments.items():
        sig = mdef.signal(COMMAND_ARGUMENTS[key])
        raw[sig.name] = _argument_raw(sig, key, value)
    return codec.make_message("Command", node, codec.pack_raw(mdef, raw), layout, fd)


def encode_ack(ack, layout=IdLayout(), fd=False):
    """The gripper's ACK/NACK frame (for tests and simulated grippers): bytes 2..5 copied."""
    cmd = table.BY_NAME["Ack"].signal("AckCommand")
    res = table.BY_NAME["Ack"].signal("AckResult")
    data = bytearray(8)
    data[0] = cmd.raw_of_name(ack.command) if isinstance(ack.command, str) else ack.command
    data[1] = res.raw_of_name(ack.result) if isinstance(ack.result, str) else ack.result
    data[2:6] = bytes(ack.data)
    data[6] = (ack.sequence & 0x0F) << 4
    return codec.make_message("Ack", ack.node, data, layout, fd)
