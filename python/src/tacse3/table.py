# SPDX-License-Identifier: Apache-2.0
"""The CAN message table: ids, bit positions, scaling, ranges and value names.

``message_table.json`` is written by ``tacse3-dbcgen --format json`` from the C++ table
(protocol/include/tacse3/protocol/message_table.hpp); ctest's ``python_table_committed`` fails when
the committed copy differs, so this module never restates a number of the protocol.
"""

import json
from dataclasses import dataclass
from importlib import resources


@dataclass(frozen=True)
class SignalDef:
    name: str
    start: int  # first (least significant) bit, Intel byte order
    length: int  # bits
    signed: bool
    factor: float  # physical = raw * factor
    raw_min: int  # valid raw range; the encoder saturates into it
    raw_max: int
    unit: str
    invalid: str  # "none" | "most_negative" | "all_ones"
    role: str  # value | flag | enum | count | counter | crc | multiplexor
    mux: int  # >= 0: present only when the message's multiplexor equals mux
    values: dict  # raw -> name (enumerations, invalid markers)

    @property
    def invalid_raw(self):
        """The raw "not available" marker, or None if every raw value is a value."""
        if self.invalid == "most_negative":
            return -(1 << (self.length - 1))
        if self.invalid == "all_ones":
            return (1 << self.length) - 1
        return None

    def raw_of_name(self, name):
        for raw, n in self.values.items():
            if n == name:
                return raw
        raise ValueError(f"{self.name}: unknown value {name!r} "
                         f"(one of {', '.join(self.values.values())})")


@dataclass(frozen=True)
class MessageDef:
    id: int  # the low 5 bits of the identifier
    name: str
    length: int  # payload bytes
    fd_only: bool
    sender: str  # "gripper" | "controller"
    comment: str
    signals: tuple

    def signal(self, name):
        for s in self.signals:
            if s.name == name:
                return s
        raise KeyError(f"{self.name} has no signal {name!r}")

    @property
    def multiplexor(self):
        return next((s for s in self.signals if s.role == "multiplexor"), None)


def _load():
    text = resources.files(__package__).joinpath("message_table.json").read_text("utf-8")
    doc = json.loads(text)
    messages = []
    for m in doc["messages"]:
        sigs = tuple(SignalDef(name=s["name"], start=s["start"], length=s["length"],
                               signed=s["signed"], factor=s["factor"], raw_min=s["raw_min"],
                               raw_max=s["raw_max"], unit=s["unit"], invalid=s["invalid"],
                               role=s["role"], mux=s["mux"],
                               values={raw: name for raw, name in s["values"]})
                     for s in m["signals"])
        messages.append(MessageDef(id=m["id"], name=m["name"], length=m["length"],
                                   fd_only=m["fd_only"], sender=m["sender"],
                                   comment=m["comment"], signals=sigs))
    return doc, tuple(messages)


_DOC, MESSAGES = _load()
BY_ID = {m.id: m for m in MESSAGES}
BY_NAME = {m.name: m for m in MESSAGES}

PROTOCOL_VERSION = tuple(_DOC["protocol_version"])
MESSAGE_ID_BITS = _DOC["message_id_bits"]
NODE_ID_BITS = _DOC["node_id_bits"]
DEFAULT_EXTENDED_BASE = _DOC["default_extended_base"]

# Value tables shared by several signals, by the names the protocol documents.
COMMANDS = BY_NAME["Command"].signal("CommandCode").values  # 1 -> "TARE", ...
ACK_RESULTS = BY_NAME["Ack"].signal("AckResult").values  # 0 -> "ACK", 7 -> "BUSY", ...
QUERY_ITEMS = BY_NAME["Command"].signal("QueryItem").values  # 0 -> "PROTOCOL_VERSION", ...
