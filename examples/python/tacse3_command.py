#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 example: send one command to a gripper and wait for its ACK with tacse3.Client.
"""Send a command to a tacse3 gripper over SocketCAN and wait for its ACK/NACK.

    /usr/bin/python3 tacse3_command.py --channel can0 --node 1 tare
    /usr/bin/python3 tacse3_command.py --channel can0 --node 1 rate-divider 2
    /usr/bin/python3 tacse3_command.py --channel can0 --node 1 query stream

Exit status as tacse3-ctl: 0 ACK, 1 no CAN, 2 bad arguments, 3 NACK, 4 no ACK in time.
"""

import argparse
import sys

import can

import tacse3


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--channel", required=True, help="SocketCAN interface, e.g. can0")
    ap.add_argument("--node", type=int, default=1, help="node id of the gripper (1..63)")
    ap.add_argument("--timeout", type=float, default=tacse3.client.DEFAULT_TIMEOUT_S,
                    help="seconds to wait for the ACK")
    ap.add_argument("command", choices=["tare", "reset-pose", "finger-separation", "fusion",
                                        "rate-divider", "stream", "query"])
    ap.add_argument("args", nargs="*", help="finger-separation METRES | fusion joint|paper "
                    "[auto|velocity|displacement] | rate-divider N | stream on|off | query ITEM")
    a = ap.parse_args()
    kw = {"finger-separation": lambda v: {"finger_separation": float(v[0])},
          "fusion": lambda v: {"fusion": v[0].upper(),
                               "velocity_mode": (v[1] if len(v) > 1 else "auto").upper()},
          "rate-divider": lambda v: {"rate_divider": int(v[0])},
          "stream": lambda v: {"stream": {"on": 1, "off": 0}[v[0]]},
          "query": lambda v: {"query": v[0].upper().replace("-", "_")}}
    try:
        arguments = kw[a.command](a.args) if a.command in kw else {}
        command = a.command.upper().replace("-", "_")
        command = {"FINGER_SEPARATION": "SET_FINGER_SEPARATION", "FUSION": "SET_FUSION",
                   "RATE_DIVIDER": "SET_RATE_DIVIDER", "STREAM": "SET_STREAM"}.get(command,
                                                                                   command)
        tacse3.encode_command(a.node, command, 0, **arguments)  # checks the arguments
    except (IndexError, KeyError, ValueError) as e:
        ap.error(f"{a.command}: bad arguments {a.args}: {e}")
    try:
        bus = can.Bus(interface="socketcan", channel=a.channel)
    except (OSError, can.CanError) as e:
        sys.exit(f"tacse3_command: cannot open {a.channel}: {e}")
    with bus:
        client = tacse3.Client(bus, a.node, timeout=a.timeout)
        try:
            ack = client.send(command, **arguments)
        except tacse3.NackError as e:
            print(f"tacse3_command: {e}", file=sys.stderr)
            sys.exit(3)
        except tacse3.AckTimeout as e:
            print(f"tacse3_command: {e}", file=sys.stderr)
            sys.exit(4)
        except tacse3.ClientError as e:
            sys.exit(f"tacse3_command: {e}")
    reply = ack.query_reply() if command == "QUERY" else ""
    print(f"node {a.node}: {command} acknowledged (seq {ack.sequence}) {reply}".rstrip())


if __name__ == "__main__":
    main()
