#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The daemon under the unit's system-call filter (SystemCallFilter= of tacse3d.service).

seccomp_exec applies the allow list that unit_syscalls.sh expands from the unit, with SIGSYS for
anything else, then runs the sim board with a CAN log, a recording, sd_notify (READY=1, the
watchdog), a SIGHUP reload and, when tacse3d is built with it, the live view (--http, one
GET /api/state). The run must finish cleanly; the same run without mlockall on the
list must be killed by SIGSYS, which shows the filter is in force.

usage: test_daemon_seccomp.py SECCOMP_EXEC TACSE3D SOURCE_DIR
"""
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request


def viewer_built(tacse3d):
    """The build tree's tacse3d finds its page in <exe_dir>/../share/tacse3/viewer."""
    return os.path.exists(os.path.join(os.path.dirname(os.path.abspath(tacse3d)), "..", "share",
                                       "tacse3", "viewer", "index.html"))


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def get_state(port):
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=5) as r:
            return r.status
    except OSError as e:
        return str(e)


def run_daemon(seccomp_exec, tacse3d, src, allow, tmp, tag):
    sock_path = os.path.join(tmp, f"notify-{tag}")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(sock_path)
    sock.settimeout(0.2)
    env = dict(os.environ, NOTIFY_SOCKET=sock_path, WATCHDOG_USEC="2000000")
    cmd = [seccomp_exec, allow, "--", tacse3d, "--board", "sim",
           "--calibration", os.path.join(src, "packaging", "calibration.toml"),
           "--seconds", "3", "--can-log", os.path.join(tmp, f"can-{tag}.log"),
           "--record", os.path.join(tmp, f"rec-{tag}")]
    port = free_port() if viewer_built(tacse3d) else None
    if port is not None:
        cmd += ["--http", f"127.0.0.1:{port}"]
    http = None
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    messages = []
    hup_sent = False
    deadline = time.monotonic() + 60
    while proc.poll() is None and time.monotonic() < deadline:
        try:
            messages.append(sock.recv(4096).decode())
        except socket.timeout:
            continue
        if not hup_sent and any("READY=1" in m for m in messages):
            proc.send_signal(signal.SIGHUP)
            hup_sent = True
            if port is not None:
                http = get_state(port)
    if proc.poll() is None:
        proc.kill()
    _, err = proc.communicate()
    sock.close()
    return proc.returncode, "\n".join(messages), err.decode(errors="replace"), http


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    seccomp_exec, tacse3d, src = sys.argv[1:]
    with tempfile.TemporaryDirectory() as tmp:
        allow = os.path.join(tmp, "allow")
        names = subprocess.run([os.path.join(src, "tests", "packaging", "unit_syscalls.sh"),
                                os.path.join(src, "packaging", "tacse3d.service")],
                               check=True, capture_output=True, text=True).stdout.split()
        assert "mlockall" in names and "setuid" not in names, "unexpected allow list"
        with open(allow, "w") as f:
            f.write("\n".join(names) + "\n")

        rc, notes, err, http = run_daemon(seccomp_exec, tacse3d, src, allow, tmp, "unit")
        if rc != 0:
            why = " (killed by SIGSYS: a call outside the unit's filter)" if rc == -signal.SIGSYS else ""
            print(f"FAIL: tacse3d under the unit's filter exited {rc}{why}\n{err}", file=sys.stderr)
            return 1
        for want in ("READY=1", "WATCHDOG=1", "STOPPING=1"):
            if want not in notes:
                print(f"FAIL: no {want} over NOTIFY_SOCKET; got: {notes!r}\n{err}", file=sys.stderr)
                return 1
        if "reload" not in err.lower():
            print(f"FAIL: SIGHUP reload not reported on stderr:\n{err}", file=sys.stderr)
            return 1
        if viewer_built(tacse3d) and http not in (200, 503):
            print(f"FAIL: GET /api/state under the filter: {http}\n{err}", file=sys.stderr)
            return 1
        with open(os.path.join(tmp, "can-unit.log")) as f:
            frames = sum(1 for line in f if line.startswith("("))
        rec = os.listdir(os.path.join(tmp, "rec-unit"))
        if frames < 100 or not rec:
            print(f"FAIL: {frames} CAN frames logged, recording holds {rec}", file=sys.stderr)
            return 1

        with open(allow, "w") as f:
            f.write("\n".join(n for n in names if n != "mlockall") + "\n")
        rc2, _, _, _ = run_daemon(seccomp_exec, tacse3d, src, allow, tmp, "nomlock")
        if rc2 != -signal.SIGSYS:
            print(f"FAIL: without mlockall on the list the daemon exited {rc2}, not SIGSYS: "
                  "the filter is not in force", file=sys.stderr)
            return 1
    print(f"daemon under SystemCallFilter ({len(names)} calls): exit 0, READY/WATCHDOG/STOPPING, "
          f"SIGHUP reload, {frames} CAN frames, recording {sorted(rec)}, viewer {http}; "
          "without mlockall: SIGSYS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
