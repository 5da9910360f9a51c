# SPDX-License-Identifier: Apache-2.0
"""tacse3: the tacse3 gripper's CAN protocol for controller code, on python-can.

    import can, tacse3
    bus = can.Bus(interface="socketcan", channel="can0")
    decoder = tacse3.BusDecoder()
    for msg in bus:
        for obj in decoder.feed(msg):   # Cycle, Status, StatusContact, ..., Ack
            ...
    tacse3.Client(bus, node=1).tare()

See docs/python.md.
"""

from .candump import CandumpError, LogReader, format_line, parse_line
from .client import AckTimeout, Client, ClientError, NackError
from .codec import FrameError, IdLayout, crc8
from .messages import (Ack, Command, Cycle, Status, StatusContact, StatusCounters, StatusTiming,
                       decode, encode_ack, encode_command, encode_cycle)
from .reassembler import BusDecoder, CycleReassembler
from .socketbus import SocketBus
from . import table
from .table import PROTOCOL_VERSION

__version__ = "0.1.0"

__all__ = [
    "Ack", "AckTimeout", "BusDecoder", "CandumpError", "Client", "ClientError", "Command",
    "Cycle", "CycleReassembler", "FrameError", "IdLayout", "LogReader", "NackError",
    "PROTOCOL_VERSION", "SocketBus", "Status", "StatusContact", "StatusCounters", "StatusTiming",
    "crc8",
    "decode", "encode_ack", "encode_command", "encode_cycle", "format_line", "parse_line",
    "table",
]
