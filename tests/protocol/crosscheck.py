#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 protocol: an encoder-written candump log decoded by tacse3-canmon, the Python example and
# the DBC through candied; all must agree with each other and with the encoder's own record.
"""usage: crosscheck.py --mode canmon|all --workdir DIR --make-log EXE --canmon EXE
                       [--dbcgen EXE --dbc FILE --python PY --example FILE --node-script FILE]
                       [--emulator "qemu-aarch64-static|-L|/usr/aarch64-linux-gnu"]

--mode canmon checks tacse3-canmon against the encoder's record and the injected faults.
--mode all adds the Python example (python3-can) and the DBC decoder (node + candied).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys

TYPES = {
    "cycle": ["node", "counter", "t_us", "valid", "single_sensor", "pose_reset", "saturated",
              "wx", "wy", "wz", "vx", "vy", "vz", "qw", "qx", "qy", "qz", "px", "py", "pz",
              "sat_w", "sat_v", "sat_p"],
    "status": ["node", "counter", "state", "health_left", "health_right", "contact_left",
               "contact_right", "slip_left", "slip_right", "stream_enabled", "fusion",
               "velocity_mode", "confidence", "rate_divider", "fault", "rejected_commands",
               "calibrated"],
    "status_contact": ["node", "counter", "area_left", "area_right", "confidence_left",
                       "confidence_right"],
    "status_timing": ["node", "counter", "dsp_time", "latency_p50", "latency_p99"],
    "status_counters": ["node", "counter", "dropped_left", "dropped_right", "can_tx_dropped"],
    "ack": ["node", "command", "result", "sequence"],
    "command": ["node", "command", "target_node", "sequence"],
}
# The injected faults of make_log.cpp and what every decoder must count.
EXPECTED_CYCLES = {1: 240 - 3, 2: 120}
FAILURES = []


def fail(msg):
    FAILURES.append(msg)
    print("FAIL: " + msg, file=sys.stderr)


def run(cmd, stdout_path=None):
    print("+ " + " ".join(cmd), file=sys.stderr)
    with open(stdout_path, "w") if stdout_path else open(os.devnull, "w") as out:
        r = subprocess.run(cmd, stdout=out, stderr=subprocess.PIPE, text=True, timeout=120)
    sys.stderr.write(r.stderr)
    if r.returncode != 0:
        raise SystemExit(f"command failed ({r.returncode}): {' '.join(cmd)}")
    return r.stderr


def load(path, extra_types=()):
    objs = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            o = json.loads(line)
            if o.get("type") in TYPES or o.get("type") in extra_types:
                objs.append(o)
    return objs


def same(a, b):
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        return a == b
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=0, abs_tol=1e-9)
    return a == b


def compare(name_a, objs_a, name_b, objs_b):
    for t, keys in TYPES.items():
        a = [o for o in objs_a if o["type"] == t]
        b = [o for o in objs_b if o["type"] == t]
        if not a and not b:
            continue
        if len(a) != len(b):
            fail(f"{name_a} has {len(a)} '{t}' objects, {name_b} has {len(b)}")
            continue
        bad = 0
        for i, (x, y) in enumerate(zip(a, b)):
            for k in keys:
                if k not in x or k not in y:
                    continue
                if not same(x[k], y[k]):
                    bad += 1
                    if bad <= 5:
                        fail(f"{t} #{i} '{k}': {name_a}={x[k]!r} {name_b}={y[k]!r}")
        if bad == 0:
            print(f"ok: {len(a)} '{t}' objects agree ({name_a} vs {name_b})", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mode", choices=["canmon", "all"], required=True)
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--make-log", required=True)
    ap.add_argument("--canmon", required=True)
    ap.add_argument("--dbcgen")
    ap.add_argument("--dbc")
    ap.add_argument("--python", default="/usr/bin/python3")
    ap.add_argument("--example")
    ap.add_argument("--node-script")
    ap.add_argument("--emulator", default="", help="cross emulator command, parts separated by |")
    args = ap.parse_args()
    emu = [e for e in args.emulator.split("|") if e]

    os.makedirs(args.workdir, exist_ok=True)
    w = lambda name: os.path.join(args.workdir, name)  # noqa: E731
    run(emu + [args.make_log, "--log", w("bus.log"), "--truth", w("truth.jsonl")])
    summary = run(emu + [args.canmon, "--log", w("bus.log"), "--format", "json"],
                  w("canmon.jsonl"))
    run(emu + [args.canmon, "--log", w("bus.log"), "--format", "csv"], w("canmon.csv"))
    # stdin path: candump -L ... | tacse3-canmon --log -
    with open(w("bus.log")) as log, open(w("canmon_stdin.csv"), "w") as out:
        subprocess.run(emu + [args.canmon, "--log", "-", "--format", "csv"], stdin=log,
                       stdout=out, check=True, timeout=120)

    truth = load(w("truth.jsonl"))
    canmon = load(w("canmon.jsonl"), extra_types=("summary",))
    compare("encoder", truth, "canmon", [o for o in canmon if o["type"] == "cycle"])

    # canmon's own accounting of the injected faults
    final = [o for o in canmon if o["type"] == "summary"]
    if len(final) != 1:
        fail("canmon printed no summary object")
    else:
        s = final[0]
        n1, n2 = s["nodes"]["1"], s["nodes"]["2"]
        checks = {
            "node 1 cycles": (n1["cycles"], EXPECTED_CYCLES[1]),
            "node 1 CRC errors": (n1["crc_errors"], 1),
            "node 1 incomplete cycles": (n1["incomplete"], 2),
            "node 1 counter gaps": (n1["counter_gaps"], 1),
            "node 1 repeated frames": (n1["repeated"], 5),
            "node 1 stale cycles": (n1["stale"], 0),
            "node 1 status counter gaps": (n1["status_counter_gaps"], 0),
            "node 2 cycles": (n2["cycles"], EXPECTED_CYCLES[2]),
            "node 2 counter gaps": (n2["counter_gaps"], 0),
            "foreign frames": (s["foreign_frames"], 20),
        }
        for what, (got, want) in checks.items():
            if got != want:
                fail(f"canmon {what}: {got}, expected {want}")
        # 600 classic + 120 FD frames per second of node 1/2 at 500 kbit/s: between 15 and 30 %
        if not 0.15 < s["bus_load_average"] < 0.30:
            fail(f"canmon average bus load {s['bus_load_average']} not plausible")
        print(f"ok: canmon counted the injected faults; bus load average "
              f"{100 * s['bus_load_average']:.2f}%, peak {100 * s['bus_load_peak']:.2f}%",
              file=sys.stderr)
    if "node 1: 237 cycles" not in summary:
        fail("canmon's stderr summary does not report node 1's 237 cycles")
    with open(w("canmon.csv")) as f:
        rows = f.read().splitlines()
    with open(w("canmon_stdin.csv")) as f:
        rows_stdin = f.read().splitlines()
    if not rows or not rows[0].startswith("t_us,node,counter,valid"):
        fail("canmon CSV header missing")
    if len(rows) - 1 != sum(EXPECTED_CYCLES.values()):
        fail(f"canmon CSV has {len(rows) - 1} cycle rows")
    if rows != rows_stdin:
        fail("canmon --log FILE and --log - (stdin) disagree")

    if args.mode == "all":
        for what, path in (("python3", args.python), ("node", shutil.which("node"))):
            if not path or not os.path.exists(path):
                raise SystemExit(f"{what} not found")
        node_modules = os.path.join(os.path.dirname(args.node_script), "node_modules", "candied")
        if not os.path.isdir(node_modules):
            raise SystemExit("candied is not installed: run `npm ci` in "
                             + os.path.dirname(args.node_script))
        run([args.python, args.example, "--log", w("bus.log")], w("python.jsonl"))
        run(emu + [args.dbcgen, "--node", "2", "--output", w("node2.dbc")])
        run(["node", args.node_script, w("bus.log"), args.dbc, w("node2.dbc")], w("dbc.jsonl"))
        python = load(w("python.jsonl"))
        dbc = load(w("dbc.jsonl"))
        compare("canmon", canmon, "python-can example", python)
        compare("canmon", canmon, "candied+DBC", dbc)
        compare("python-can example", python, "candied+DBC", dbc)
        for name, objs in (("python", python), ("dbc", dbc)):
            for node, want in EXPECTED_CYCLES.items():
                got = sum(1 for o in objs if o["type"] == "cycle" and o["node"] == node)
                if got != want:
                    fail(f"{name}: node {node} has {got} cycles, expected {want}")

    if FAILURES:
        print(f"{len(FAILURES)} check(s) failed", file=sys.stderr)
        return 1
    print("crosscheck: all decoders agree", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
