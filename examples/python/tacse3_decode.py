#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 example: decode tacse3 gripper CAN frames with the tacse3 package (live bus or log).
"""Decode the tacse3 gripper CAN protocol with the tacse3 Python package (python-can).

    /usr/bin/python3 tacse3_decode.py --log run.log            # candump -L log
    candump -L can0 | /usr/bin/python3 tacse3_decode.py --log -
    /usr/bin/python3 tacse3_decode.py --channel can0           # live SocketCAN

Needs the package: installed (python3-tacse3 .deb or the wheel), or from the repository with
PYTHONPATH=python/src. Output: one JSON object per line (the same keys as
`tacse3-canmon --format json`) for every complete cycle, status frame, command and ACK; a
summary of counter gaps / CRC errors on stderr.
"""

import argparse
import json
import sys

import can

import tacse3


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--log", help="candump -L log file, - for stdin")
    src.add_argument("--channel", help="live SocketCAN interface, e.g. can0")
    ap.add_argument("--node", type=int, default=0, help="only this node id")
    ap.add_argument("--extended", action="store_true", help="29-bit identifiers")
    ap.add_argument("--extended-base", type=lambda s: int(s, 0),
                    default=tacse3.table.DEFAULT_EXTENDED_BASE)
    args = ap.parse_args()

    try:
        layout = tacse3.IdLayout(args.extended, args.extended_base)
    except ValueError as e:
        ap.error(f"--extended-base: {e}")
    decoder = tacse3.BusDecoder(layout, args.node)
    if args.log is not None:
        source = tacse3.LogReader(args.log)
    else:
        source = can.Bus(interface="socketcan", channel=args.channel, fd=True)
    try:
        for msg in source:
            for obj in decoder.feed(msg):
                print(json.dumps(obj.to_json(), separators=(",", ":")), flush=args.log is None)
    except KeyboardInterrupt:
        pass
    except OSError as e:
        sys.exit(f"tacse3_decode: {e}")
    for node, r in sorted(decoder.nodes.items()):
        s = r.stats
        print(f"tacse3_decode: node {node}: {s.cycles} cycles, counter gaps {s.gaps}, "
              f"repeated {s.repeated}, incomplete {s.incomplete}, stale {s.stale}",
              file=sys.stderr)
    bad = f", {source.bad_lines} malformed log lines" if args.log is not None else ""
    print(f"tacse3_decode: {decoder.crc_errors} CRC errors, {decoder.length_errors} length errors"
          f"{bad}", file=sys.stderr)


if __name__ == "__main__":
    main()
