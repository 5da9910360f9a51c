#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3: how much of each tacse3d thread's stack is used (docs/performance.md, "Thread stacks").
#
# Usage: bench/memory/thread-stacks.py BUILD_DIR BOARD [--http PORT]
#   BOARD  a board file, or "replay": measure-rss.sh's replay board (the sim board with both pads
#          replaying a tacse3-sim recording, paced, looping)
#
# Runs tacse3d for 8 s with memory locking refused (no CAP_IPC_LOCK, RLIMIT_MEMLOCK 0), so a
# stack's pages become resident only when touched: the resident part of a thread's stack
# mapping is its high-water mark, to the page. Each thread's stack mapping is the one holding the
# stack pointer it blocks with (/proc/PID/task/TID/syscall). With --http PORT the daemon also
# serves the viewer there, and curl fetches the page, every endpoint and an event stream.
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

ap = argparse.ArgumentParser()
ap.add_argument("build")
ap.add_argument("board")
ap.add_argument("--http", type=int)
a = ap.parse_args()
daemon = os.path.join(a.build, "firmware", "tacse3d")
if not os.access(daemon, os.X_OK):
    sys.exit(f"thread-stacks: {daemon} not found; build it (ninja -C {a.build} tacse3d)")
tmp = tempfile.TemporaryDirectory()
board = a.board
if board == "replay":
    sim = os.path.join(a.build, "tools", "sim", "tacse3-sim")
    rec = os.path.join(tmp.name, "rec")
    subprocess.run([sim, "--out", rec, "--motion", "rz", "--magnitude", "30"], check=True,
                   stdout=subprocess.DEVNULL)
    text = open(os.path.join(os.path.dirname(__file__), "../../boards/sim/board.toml")).read()
    text = text.replace('backend = "sim"', f'backend = "replay"\ndevice = "{rec}"')
    text = re.sub(r"(?m)^repeat = .*", "repeat = true", text)
    text = re.sub(r"(?m)^realtime = .*", "realtime = true", text)
    board = os.path.join(tmp.name, "replay.toml")
    open(board, "w").write(text)
cmd = [daemon, "--board", board, "--seconds", "8", "--can-log", "/dev/null", "--quiet"]
if a.http:
    cmd += ["--http", f"127.0.0.1:{a.http}"]
cmd = ["prlimit", "--memlock=0:0", "setpriv", "--bounding-set=-ipc_lock", "--inh-caps=-all"] + cmd
proc = subprocess.Popen(cmd, stderr=subprocess.PIPE)
time.sleep(3)
if a.http:
    url = f"http://127.0.0.1:{a.http}"
    subprocess.Popen(["timeout", "4", "curl", "-sN", f"{url}/api/stream", "-o", "/dev/null"])
    paths = ["/", "/api/state", "/api/info", "/api/fields", "/api/image/left.jpg",
             "/api/image/right.jpg"]
    fetch = " ".join(f"{url}{p} -o /dev/null" for p in paths)
    subprocess.Popen(["sh", "-c", f"for i in $(seq 20); do curl -s {fetch}; sleep 0.05; done"])
    time.sleep(2)
time.sleep(1)
pid = proc.pid  # prlimit and setpriv exec the daemon
threads = []
for tid in sorted(os.listdir(f"/proc/{pid}/task"), key=int):
    name = open(f"/proc/{pid}/task/{tid}/comm").read().strip()
    fields = []
    for _ in range(2000):  # a running thread shows no stack pointer: wait until it blocks
        fields = open(f"/proc/{pid}/task/{tid}/syscall").read().split()
        if len(fields) >= 3:
            break
        time.sleep(0.001)
    threads.append((name, tid, int(fields[-2], 16) if len(fields) >= 3 else None))
maps = []
for line in open(f"/proc/{pid}/smaps"):
    m = re.match(r"([0-9a-f]+)-([0-9a-f]+) ", line)
    if m:
        maps.append({"lo": int(m[1], 16), "hi": int(m[2], 16), "size": 0, "rss": 0})
    elif line.startswith(("Size:", "Rss:")):
        maps[-1][line.split(":")[0].lower()] = int(line.split()[1])
print(f"{'thread':16} {'tid':>7} {'stack KiB':>10} {'used KiB':>9}")
for name, tid, sp in threads:
    m = next((m for m in maps if sp is not None and m["lo"] <= sp < m["hi"]), None)
    if m is None:
        print(f"{name:16} {tid:>7} {'?':>10} {'?':>9}  (no stack pointer seen)")
    else:
        print(f"{name:16} {tid:>7} {m['size']:>10} {m['rss']:>9}")
_, err = proc.communicate()
if proc.returncode != 0:
    sys.exit(f"thread-stacks: tacse3d exited {proc.returncode}: {err.decode()[-400:]}")
