# SPDX-License-Identifier: Apache-2.0
"""Frame layer: CRC-8, identifiers, the table-driven raw layer, scaling, decode and encode.

Frames are python-can ``can.Message`` objects. Every rule here is the C++ codec's
(protocol/src/codec.cpp); docs/can-protocol.md specifies them.
"""

import math
from dataclasses import dataclass

import can

from . import table

_MESSAGE_MASK = (1 << table.MESSAGE_ID_BITS) - 1
_NODE_MASK = (1 << table.NODE_ID_BITS) - 1
_STANDARD_MASK = 0x7FF
_EXTENDED_MASK = 0x1FFFFFFF
_CRC_EXTENDED_FLAG = 0x80000000
MIN_NODE_ID, MAX_NODE_ID = 1, _NODE_MASK


class FrameError(ValueError):
    """A frame that is not a valid tacse3 frame. ``reason``: unknown_id, length, crc, counter."""

    def __init__(self, reason, text):
        super().__init__(text)
        self.reason = reason


# ---- CRC-8/SAE-J1850 ------------------------------------------------------------------------
def _crc_table():
    out = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        out.append(crc)
    return bytes(out)


_CRC_TABLE = _crc_table()


def crc8(data):
    """CRC-8/SAE-J1850: polynomial 0x1D, init 0xFF, no reflection, final XOR 0xFF."""
    crc = 0xFF
    for byte in data:
        crc = _CRC_TABLE[crc ^ byte]
    return crc ^ 0xFF


def frame_crc(can_id, extended, data):
    """The CRC of a frame: over the 4-byte little-endian identifier word (bit 31 set for a
    29-bit identifier) and every payload byte but the last."""
    word = (can_id & _EXTENDED_MASK) | _CRC_EXTENDED_FLAG if extended else can_id & _STANDARD_MASK
    return crc8(word.to_bytes(4, "little") + bytes(data[:-1]))


# ---- identifiers ----------------------------------------------------------------------------
@dataclass(frozen=True)
class IdLayout:
    """11-bit identifiers (``node << 5 | message``), or 29-bit ones with ``extended_base``."""

    extended: bool = False
    extended_base: int = table.DEFAULT_EXTENDED_BASE

    def __post_init__(self):
        if self.extended_base & ~_EXTENDED_MASK or self.extended_base & _STANDARD_MASK:
            raise ValueError(f"extended_base 0x{self.extended_base:X}: bits 0..10 must be clear "
                             "and it must fit in 29 bits")


def compose_id(layout, node, message_id):
    if not MIN_NODE_ID <= node <= MAX_NODE_ID:
        raise ValueError(f"node id {node} is outside {MIN_NODE_ID}..{MAX_NODE_ID}")
    low = (node & _NODE_MASK) << table.MESSAGE_ID_BITS | (message_id & _MESSAGE_MASK)
    return layout.extended_base | low if layout.extended else low


def split_id(layout, can_id, extended):
    """(node, message id) of an identifier under ``layout``, or None if it is not ours."""
    if not layout.extended:
        if extended or can_id > _STANDARD_MASK:
            return None
    elif (not extended or can_id > _EXTENDED_MASK
          or can_id & ~_STANDARD_MASK != layout.extended_base):
        return None
    node = (can_id >> table.MESSAGE_ID_BITS) & _NODE_MASK
    if node == 0:
        return None
    return node, can_id & _MESSAGE_MASK


# ---- raw layer ------------------------------------------------------------------------------
def get_bits(data, start, length, signed=False):
    value = (int.from_bytes(bytes(data), "little") >> start) & ((1 << length) - 1)
    if signed and value >> (length - 1):
        value -= 1 << length
    return value


def unpack_raw(mdef, data):
    """Raw integer of every present signal (multiplexed ones only when selected), by name."""
    mux_sig = mdef.multiplexor
    mux = get_bits(data, mux_sig.start, mux_sig.length) if mux_sig else -1
    return {s.name: get_bits(data, s.start, s.length, s.signed)
            for s in mdef.signals if s.mux < 0 or s.mux == mux}


def pack_raw(mdef, raw):
    """The payload (``mdef.length`` bytes) holding ``raw`` (name -> raw integer); absent signals
    and reserved bits are 0, values are truncated to their width, the CRC byte is as given."""
    value = 0
    for s in mdef.signals:
        if s.name in raw:
            value |= (raw[s.name] & ((1 << s.length) - 1)) << s.start
    return bytearray(value.to_bytes(mdef.length, "little"))


def _round_half_away(x):
    r = math.floor(abs(x))
    if abs(x) - r >= 0.5:
        r += 1
    return int(math.copysign(r, x))


def quantize(sig, value):
    """physical -> (raw, saturated): round half away from zero, clamp into [raw_min, raw_max];
    None, NaN or +-inf -> the invalid marker (raw_min if the signal has none)."""
    if value is None or not math.isfinite(value):
        marker = sig.invalid_raw
        return (sig.raw_min if marker is None else marker), False
    r = _round_half_away(value / sig.factor)
    if r < sig.raw_min:
        return sig.raw_min, True
    if r > sig.raw_max:
        return sig.raw_max, True
    return r, False


def dequantize(sig, raw):
    """raw -> physical (float); the invalid marker -> None."""
    if sig.invalid_raw is not None and raw == sig.invalid_raw:
        return None
    return float(raw) * sig.factor


def to_physical(sig, raw):
    """A raw value as an application sees it: scaled float or None, bool, enum name (the number
    if it has no name), or int."""
    if sig.role == "flag":
        return bool(raw)
    if sig.role in ("enum", "multiplexor"):
        return sig.values.get(raw, raw)
    if sig.role == "value":
        if sig.invalid_raw is not None and raw == sig.invalid_raw:
            return None
        return raw if sig.factor == 1 else float(raw) * sig.factor
    return raw


def from_physical(sig, value):
    """The inverse of to_physical for the encoder: (raw, saturated)."""
    if sig.role == "flag":
        return int(bool(value)), False
    if sig.role in ("enum", "multiplexor") and isinstance(value, str):
        return sig.raw_of_name(value), False
    if sig.role == "value":
        return quantize(sig, value)
    return int(value), False


# ---- frames ---------------------------------------------------------------------------------
@dataclass
class Decoded:
    """One checked frame: message name, node id, and every present signal in physical units."""

    message: str
    node: int
    signals: dict


def check_frame(msg, layout=IdLayout()):
    """(node, MessageDef) of a valid tacse3 frame; FrameError for anything else."""
    ids = None
    if not (msg.is_remote_frame or msg.is_error_frame):
        ids = split_id(layout, msg.arbitration_id, msg.is_extended_id)
    mdef = table.BY_ID.get(ids[1]) if ids else None
    if mdef is None:
        raise FrameError("unknown_id", f"identifier 0x{msg.arbitration_id:X} is not a tacse3 "
                                       "frame under this identifier layout")
    data = bytes(msg.data)
    if len(data) != mdef.length or (mdef.fd_only and not msg.is_fd):
        raise FrameError("length", f"{mdef.name} of node {ids[0]}: {len(data)} bytes"
                                   f"{'' if msg.is_fd else ' (classic)'}, expected "
                                   f"{mdef.length}{' (CAN FD)' if mdef.fd_only else ''}")
    if frame_crc(msg.arbitration_id, msg.is_extended_id, data) != data[-1]:
        raise FrameError("crc", f"{mdef.name} of node {ids[0]}: CRC-8 mismatch")
    return ids[0], mdef


def decode(msg, layout=IdLayout()):
    """Decode any tacse3 frame of any node. Raises FrameError (see check_frame)."""
    node, mdef = check_frame(msg, layout)
    raw = unpack_raw(mdef, msg.data)
    return Decoded(mdef.name, node,
                   {s.name: to_physical(s, raw[s.name]) for s in mdef.signals if s.name in raw})


def make_message(message, node, payload, layout=IdLayout(), fd=False, brs=True):
    """A can.Message of ``message`` (name) from ``node`` with ``payload``; the CRC is written."""
    mdef = table.BY_NAME[message]
    if mdef.fd_only and not fd:
        raise ValueError(f"{message} exists only as a CAN FD frame")
    can_id = compose_id(layout, node, mdef.id)
    data = bytearray(payload)
    data[-1] = frame_crc(can_id, layout.extended, data)
    return can.Message(arbitration_id=can_id, is_extended_id=layout.extended, is_fd=fd,
                       bitrate_switch=fd and brs, data=data, dlc=len(data))


def encode(message, signals, node, layout=IdLayout(), fd=False, brs=True):
    """Encode ``message`` (name) from physical ``signals`` (name -> value). Values outside a
    field's range are clamped (like the C++ encoder); use the typed encoders for the flags."""
    mdef = table.BY_NAME[message]
    raw = {name: from_physical(mdef.signal(name), v)[0] for name, v in signals.items()}
    return make_message(message, node, pack_raw(mdef, raw), layout, fd, brs)
