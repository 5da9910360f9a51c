# SPDX-License-Identifier: Apache-2.0
"""A python-can bus over tacse3d's Unix socket (`tacse3d --can-socket PATH`, docs/hal-can.md
"Unix socket backend"): each frame is one candump -L line in each direction."""

import select
import socket
import time

import can

from .candump import CandumpError, format_line, parse_line


class SocketBus(can.BusABC):
    """Connects to the daemon's socket at ``path``. send() writes one candump -L line;
    recv() parses the lines the daemon writes (partial lines are kept until their newline).
    Received frames carry the host clock (time.time()) as timestamp, as a controller's
    socketcan bus would. A closed socket raises can.CanOperationError."""

    def __init__(self, path, channel="can0", connect_timeout=5.0, **kwargs):
        self.channel_info = f"tacse3d socket {path}"
        self._path = str(path)
        self._iface = channel
        self._buf = b""
        self._sock = self._connect(connect_timeout)
        super().__init__(channel=channel, **kwargs)

    def _connect(self, timeout):
        # The daemon creates the socket a moment after it starts: retry until the timeout.
        deadline = time.monotonic() + timeout
        while True:
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                sock.connect(self._path)
                sock.setblocking(False)
                return sock
            except OSError as e:
                sock.close()
                if time.monotonic() >= deadline:
                    raise can.CanInitializationError(
                        f"cannot connect to the tacse3d socket {self._path}: {e.strerror} "
                        "(is `tacse3d --can-socket` running with that path?)") from None
                time.sleep(0.05)

    def send(self, msg, timeout=None):
        line = (format_line(msg, self._iface) + "\n").encode("ascii")
        deadline = None if timeout is None else time.monotonic() + timeout
        while line:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not select.select([], [self._sock], [], left)[1]:
                raise can.CanOperationError(f"send to {self._path} timed out")
            try:
                line = line[self._sock.send(line):]
            except OSError as e:
                raise can.CanOperationError(f"tacse3d socket {self._path}: {e}") from e

    def _recv_internal(self, timeout):
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            msg = self._take_line()
            if msg is not None:
                return msg, False
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                return None, False
            if not select.select([self._sock], [], [], left)[0]:
                return None, False
            try:
                chunk = self._sock.recv(65536)
            except BlockingIOError:
                continue
            except OSError as e:
                raise can.CanOperationError(f"tacse3d socket {self._path}: {e}") from e
            if not chunk:
                raise can.CanOperationError(
                    f"tacse3d closed the socket {self._path} (the daemon stopped?)")
            self._buf += chunk

    def _take_line(self):
        # Lines that are not frames (malformed, remote, error) are skipped, as LogReader does.
        while (end := self._buf.find(b"\n")) >= 0:
            line, self._buf = self._buf[:end], self._buf[end + 1:]
            try:
                msg = parse_line(line.decode("ascii", errors="replace"))
            except CandumpError:
                continue
            if msg.is_remote_frame or msg.is_error_frame:
                continue
            msg.timestamp = time.time()
            msg.is_rx = True
            return msg
        return None

    def fileno(self):
        return self._sock.fileno()

    def shutdown(self):
        super().shutdown()
        self._sock.close()
