#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 fuzz: writes the seed corpus (fuzz/corpus/<target>/) from the spec's golden frames.
"""Regenerate with: python3 fuzz/make_seeds.py  (stdlib only; the output is committed)."""
import os
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
GOLDEN = {  # identifier -> payload, from tests/protocol/test_golden.cpp / docs/can-protocol.md
    0x021: "D202964900005948", 0x022: "D2040CFE30755089", 0x023: "FF7FE0B1008051A7",
    0x024: "D007FAC060E853B6", 0x025: "F40118FCA8615087", 0x028: "42BBE10200037072",
    0x029: "D007FFFFFA7D7087", 0x02A: "B20C0410FEFF70DD", 0x02B: "01000102FFFF70EE",
    0x030: "010100000000305E", 0x031: "01000000000030E6",
}
FD = "".join(GOLDEN[i][:14] for i in range(0x021, 0x026)) + "00" * 28 + "08"  # CycleFd


def write(target, name, data):
    d = os.path.join(ROOT, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def main():
    for can_id, hexdata in GOLDEN.items():
        payload = bytes.fromhex(hexdata)
        # decoder: [flags][id LE][len][payload]; with and without CRC recomputation
        write("decoder", f"std_{can_id:03x}", bytes([0]) + struct.pack("<I", can_id) + bytes([8]) + payload)
        write("decoder", f"std_{can_id:03x}_fix", bytes([16]) + struct.pack("<I", can_id) + bytes([8]) + payload)
        write("candump", f"line_{can_id:03x}", f"(1700000000.123456) can0 {can_id:03X}#{hexdata}".encode())
    fd = bytes.fromhex(FD)
    write("decoder", "fd_026", bytes([2 | 4]) + struct.pack("<I", 0x026) + bytes([64]) + fd)
    write("decoder", "ext_ts", bytes([1 | 8 | 16]) + struct.pack("<I", 0x1ACE0021) + bytes([8])
          + bytes.fromhex(GOLDEN[0x021]))
    write("candump", "fd_line", f"(1700000000.000001) can0 026##1{FD}".encode())
    write("candump", "ext_line", b"(0000000001.000000) vcan0 1ACE0041#D202964900005912")
    write("candump", "rtr", b"(1.000000) can0 030#R8")
    write("candump", "error", b"(1.000000) can0 20000080#0000000000000000")
    # found by fuzz_candump: a control character inside the interface name
    write("candump", "iface_control_char", b"(1.000000) ca\x01n0 030#R8")
    # command: [ctrl: node | fix-CRC][len][payload]
    for name, hexdata in {"tare": "0101000000003000", "reset": "0201000000000000",
                          "finger": "0301342100001000", "fusion": "0401010200002000",
                          "divider": "0501040000004000", "stream": "0601000000005000",
                          "query": "0701040000006000", "unknown": "0901000000000000",
                          "wrong_node": "0102000000000000", "reserved": "0101010000000000"}.items():
        write("command", name, bytes([1 | 0x40, 8]) + bytes.fromhex(hexdata))
    write("command", "short", bytes([1, 3]) + bytes.fromhex("010100"))
    # reassembler: [ctrl][7 payload bytes] per classic frame (CRC computed by the harness)
    cycle = b""
    for k in range(3):
        for part, hexdata in enumerate([GOLDEN[0x021], GOLDEN[0x022], GOLDEN[0x023], GOLDEN[0x024],
                                        GOLDEN[0x025]]):
            p = bytearray(bytes.fromhex(hexdata)[:7])
            p[6] = (p[6] & 0x0F) | (k << 4)             # counter k
            if part == 0:
                p[0] = (p[0] + k) & 0xFF                  # advancing time stamp
            cycle += bytes([part]) + bytes(p)
    write("reassembler", "three_cycles", cycle)
    write("reassembler", "fd_cycle", bytes([5]) + fd[:63] + bytes([5]) + fd[:63])
    write("reassembler", "faults", cycle[:16] + bytes([8]) + cycle[17:40] + bytes([16]) + cycle[41:])


if __name__ == "__main__":
    main()
