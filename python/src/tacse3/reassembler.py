# SPDX-License-Identifier: Apache-2.0
"""Cycle reassembly and a bus decoder that routes every frame (docs/can-protocol.md, "Cycle
reassembly"); the rule is the C++ CycleReassembler's."""

from dataclasses import dataclass, field

from . import codec, messages
from .codec import IdLayout


@dataclass
class NodeStats:
    cycles: int = 0
    gaps: int = 0  # skipped counter values
    repeated: int = 0  # frames of a part or cycle already seen, late frames of the last cycle
    incomplete: int = 0  # cycles cut short by a newer counter
    stale: int = 0  # complete cycles whose SampleTime is not newer than the last one's


@dataclass
class CycleReassembler:
    """One node's cycles: parts with one counter value -> a Cycle once all five are there."""

    node: int
    stats: NodeStats = field(default_factory=NodeStats)
    _counter: object = None
    _complete: bool = False
    _parts: dict = field(default_factory=dict)
    _last_t: object = None

    def add(self, counter, parts):
        """Add parts (part name -> signals) with one counter value; returns a Cycle or None."""
        st = self.stats
        if self._counter == counter:
            if self._complete or any(p in self._parts for p in parts):
                st.repeated += 1
                return None
        elif self._counter is not None:
            delta = (counter - self._counter) & 15
            if delta == 15:  # a late frame of the previous cycle
                st.repeated += 1
                return None
            if not self._complete:
                st.incomplete += 1
            st.gaps += delta - 1
            self._counter = None
        if self._counter is None:
            self._counter, self._complete, self._parts = counter, False, {}
        self._parts.update(parts)
        if len(self._parts) < len(messages.CYCLE_PARTS):
            return None
        self._complete = True
        cycle = messages.cycle_from_parts(self.node, counter, self._parts)
        if cycle.t_us is not None and self._last_t is not None and cycle.t_us <= self._last_t:
            st.stale += 1
            return None
        if cycle.t_us is not None:
            self._last_t = cycle.t_us
        st.cycles += 1
        return cycle


class BusDecoder:
    """Decodes a stream of frames (a live bus or a log): complete cycles, status frames,
    commands and ACKs. Frames of other layouts or nodes (``node`` != 0) are ignored; bad CRCs
    and lengths are counted."""

    def __init__(self, layout=IdLayout(), node=0):
        self.layout = layout
        self.node_filter = node
        self.nodes = {}  # node id -> CycleReassembler
        self.crc_errors = 0
        self.length_errors = 0

    def feed(self, msg):
        """A list of the decoded objects of this frame (Cycle, Status, ..., Command, Ack)."""
        ids = codec.split_id(self.layout, msg.arbitration_id, msg.is_extended_id)
        if ids is None or (self.node_filter and ids[0] != self.node_filter):
            return []
        try:
            node, mdef = codec.check_frame(msg, self.layout)
            if mdef.name not in messages.CYCLE_PARTS and mdef.name != "CycleFd":
                return [messages.decode(msg, self.layout)]
            d = codec.decode(msg, self.layout)
            if mdef.name == "CycleFd":
                counter = messages.cycle_from_fd(d).counter
                parts = {p: d.signals for p in messages.CYCLE_PARTS}
            else:
                counter, parts = d.signals["Counter"], {d.message: d.signals}
        except codec.FrameError as e:
            if e.reason == "crc":
                self.crc_errors += 1
            elif e.reason in ("length", "counter"):
                self.length_errors += 1
            return []
        cycle = self._node(node).add(counter, parts)
        return [] if cycle is None else [cycle]

    def _node(self, node):
        return self.nodes.setdefault(node, CycleReassembler(node))
