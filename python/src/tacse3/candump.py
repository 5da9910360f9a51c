# SPDX-License-Identifier: Apache-2.0
"""candump -L logs ("(sec.usec) iface id#data"): read and write, the C++ parser's rules
(protocol/src/candump.cpp). python-can's CanutilsLogReader stops at the first malformed line;
this reader counts and skips such lines, or raises with the line number when strict."""

import io
import re
import sys

import can

_CAN_ERR_FLAG = 0x20000000
_FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)
_LINE = re.compile(
    r"\s*\((\d+)\.(\d{1,9})\)\s+([!-~]{1,16})\s+([0-9A-Fa-f]+)#(.*?)(?:\s+[RT])?\s*$")
_DATA = re.compile(r"(?:#([0-9A-Fa-f]))?([0-9A-Fa-f]*)(?:_([0-9A-Fa-f]))?")


class CandumpError(ValueError):
    pass


def parse_line(line):
    """One candump -L line -> can.Message (timestamp in seconds, channel = interface).
    CandumpError if it is malformed."""
    m = _LINE.fullmatch(line.rstrip("\r\n"))
    if not m:
        raise CandumpError("not a candump -L line")
    sec, frac, iface, ident, payload = m.groups()
    if len(ident) not in (3, 8):
        raise CandumpError("the identifier must have 3 (11-bit) or 8 (29-bit) hex digits")
    can_id = int(ident, 16)
    extended = len(ident) == 8
    error = extended and bool(can_id & _CAN_ERR_FLAG)
    if (not extended and can_id > 0x7FF) or (extended and not error and can_id > 0x1FFFFFFF):
        raise CandumpError(f"identifier {ident} out of range")
    stamp = int(sec) + int(frac.ljust(9, "0")[:6]) / 1e6
    fields = dict(timestamp=stamp, channel=iface, arbitration_id=can_id & 0x1FFFFFFF,
                  is_extended_id=extended, is_error_frame=error)
    if payload[:1] in ("R", "r"):
        length = payload[1:]
        if len(length) > 1 or (length and int(length, 16) > 8):
            raise CandumpError("bad remote frame length")
        return can.Message(is_remote_frame=True, dlc=int(length or "0", 16), **fields)
    d = _DATA.fullmatch(payload)
    if not d or len(d.group(2)) % 2:
        raise CandumpError("bad payload")
    flags, hexdata, len8_dlc = d.groups()
    data = bytes.fromhex(hexdata)
    fd = flags is not None
    if (fd and len(data) not in _FD_LENGTHS) or (not fd and len(data) > 8):
        raise CandumpError(f"{len(data)} payload bytes is not a valid "
                           f"{'CAN FD' if fd else 'classic CAN'} length")
    if len8_dlc is not None and (fd or len(data) != 8 or int(len8_dlc, 16) < 9):
        raise CandumpError("bad len8_dlc suffix")
    return can.Message(is_fd=fd, bitrate_switch=fd and bool(int(flags, 16) & 1), data=data,
                       dlc=len(data), **fields)


def format_line(msg, iface=None):
    """A can.Message as one candump -L line (without newline)."""
    t = msg.timestamp or 0.0
    us = round(t * 1e6)
    chan = iface or (msg.channel if isinstance(msg.channel, str) and msg.channel else "can0")
    if msg.is_extended_id or msg.is_error_frame:
        ident = f"{msg.arbitration_id | (_CAN_ERR_FLAG if msg.is_error_frame else 0):08X}"
    else:
        ident = f"{msg.arbitration_id:03X}"
    if msg.is_remote_frame and not msg.is_fd:
        body = "R" + (f"{msg.dlc:X}" if msg.dlc else "")
    else:
        flags = f"#{1 if msg.bitrate_switch else 0}" if msg.is_fd else ""
        body = flags + bytes(msg.data).hex().upper()
    return f"({us // 1000000:010d}.{us % 1000000:06d}) {chan} {ident}#{body}"


class LogReader:
    """Iterates over the frames of a candump -L log (a path, "-" for stdin, or a text file).
    Malformed lines are counted in ``bad_lines`` and skipped, or raise CandumpError naming the
    file and line when ``strict``. Remote and error frames are skipped and counted."""

    def __init__(self, source, strict=False):
        self.source = source
        self.strict = strict
        self.lines = 0
        self.bad_lines = 0
        self.skipped = 0

    def __iter__(self):
        if self.source == "-":
            yield from self._read(sys.stdin, "<stdin>")
        elif isinstance(self.source, io.IOBase) or hasattr(self.source, "readline"):
            yield from self._read(self.source, getattr(self.source, "name", "<log>"))
        else:
            with open(self.source, encoding="ascii", errors="replace") as f:
                yield from self._read(f, str(self.source))

    def _read(self, f, name):
        for line in f:
            self.lines += 1
            if not line.strip():
                continue
            try:
                msg = parse_line(line)
            except CandumpError as e:
                if self.strict:
                    raise CandumpError(f"{name}:{self.lines}: {e}: {line.strip()!r}") from None
                self.bad_lines += 1
                continue
            if msg.is_remote_frame or msg.is_error_frame:
                self.skipped += 1
                continue
            yield msg
