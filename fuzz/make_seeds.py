#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# tacse3 fuzz: writes the seed corpus (fuzz/corpus/<target>/) from the spec's golden frames.
"""Regenerate with: python3 fuzz/make_seeds.py  (stdlib only, plus libturbojpeg.so.0 through
ctypes for the JPEG seeds; the output is committed)."""
import ctypes
import glob
import os
import struct
import zlib

SRC = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ROOT = os.path.join(SRC, "fuzz", "corpus")
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
    config_seeds()
    recording_seeds()
    png_seeds()
    mjpeg_seeds()


def config_seeds():
    """The shipped board and calibration files, and broken variants of each kind."""
    for path in sorted(glob.glob(os.path.join(SRC, "boards", "*", "board.toml"))):
        with open(path, "rb") as f:
            write("board", os.path.basename(os.path.dirname(path)), f.read())
    for name, text in {
            "unknown_key": "version = 1\nnmae = 1\n[sensors.left]\nbackend = \"sim\"\n",
            "wrong_type": "version = \"1\"\n[sensors.left]\nbackend = \"sim\"\n",
            "out_of_range": "version = 1\n[sensors.left]\nbackend = \"sim\"\nfps = 100000\n",
            "syntax": "version = 1\n[sensors.left\n",
            "non_ascii_key": "version = 1\n\u00e9 = 1\n",
            "multiline_backslash": "name = \"\"\"\\\n\u00a7\"\"\"\nversion = 1\n",
            "empty": ""}.items():
        write("board", name, text.encode())
    # found by fuzz_board: toml++ 3.3 reached undefined behaviour on these (a non-ASCII character
    # where it tests for whitespace); now refused before toml++ sees them
    for i, data in enumerate([b"\xcc\x8f\x0d", b"\xef\xaf\xbb\x6e", b"\xef\xbb\xbe\x02"]):
        write("board", f"toml_unreachable_{i}", data)
        write("calibration", f"toml_unreachable_{i}", data)
    for path in [os.path.join(SRC, "packaging", "calibration.toml"),
                 os.path.join(SRC, "tools", "replay", "data", "sim-calibration.toml")]:
        with open(path, "rb") as f:
            write("calibration", os.path.basename(path).replace(".toml", ""), f.read())
    head = "format = \"tacse3-calibration\"\nversion = 1\n"
    for name, text in {
            "minimal": head,
            "wrong_format": "format = \"other\"\nversion = 1\n",
            "newer_version": "format = \"tacse3-calibration\"\nversion = 99\n",
            "unknown_key": head + "[left]\nc_velocty = 1.0\n",
            "out_of_range": head + "[left]\nc_velocity = -1.0\n",
            "nan": head + "[left]\nc_velocity = nan\n",
            "non_ascii": head + "[left]\n\ufefe = 1\n"}.items():
        write("calibration", name, text.encode())


REC_JSON = """{"format": "tacse3-recording", "version": 1, "width": 320, "height": 240, "fps": 120.0,
 "sensors": ["left", "right"],
 "rig": {"pixel_pitch_mm": 0.075, "finger_separation_mm": 40.0, "layout": "mirrored"}}"""
REC_FRAMES = "index,t_ns\n0,1000\n1,8334333\n2,16667666\n"
REC_TRUTH = ("t_ns,qw,qx,qy,qz,px,py,pz\n1000,1,0,0,0,0,0,0\n"
             "8334333,0.999,0.0447,0,0,0.001,0,0\n")
REC_LABELS = ("index,t_ns,sensor,phase,in_contact,slipping,slip_fraction,area_mm2,centroid_u_mm,"
              "centroid_v_mm,peak_depth_mm\n0,1000,left,grasp,1,0,0.0000,12.5,0.1,-0.2,0.5\n")


def recording_seeds():
    """fuzz_recording's input: recording.json, frames.csv, truth.csv, sim_labels.csv, cut at
    lines "%%" (a part left out: that file is absent)."""
    def rec(*parts):
        return "\n%%\n".join(parts).encode()
    write("recording", "complete", rec(REC_JSON, REC_FRAMES, REC_TRUTH, REC_LABELS))
    write("recording", "json_and_frames", rec(REC_JSON, REC_FRAMES))
    write("recording", "one_sensor", rec(REC_JSON.replace('"left", "right"', '"right"'), REC_FRAMES))
    write("recording", "json_only", rec(REC_JSON))
    write("recording", "json_syntax", rec(REC_JSON[:-5], REC_FRAMES))
    write("recording", "wrong_format", rec(REC_JSON.replace("tacse3-recording", "x"), REC_FRAMES))
    write("recording", "frames_header", rec(REC_JSON, "idx,t\n0,1\n"))
    write("recording", "frames_backwards", rec(REC_JSON, "index,t_ns\n0,5\n1,4\n"))
    write("recording", "frames_gap", rec(REC_JSON, "index,t_ns\n0,5\n2,9\n"))
    write("recording", "frames_truncated", rec(REC_JSON, REC_FRAMES[:-4]))
    write("recording", "truth_not_unit", rec(REC_JSON, REC_FRAMES, REC_TRUTH.replace("0.999", "0.5")))
    write("recording", "labels_phase", rec(REC_JSON, REC_FRAMES, REC_TRUTH,
                                           REC_LABELS.replace("grasp", "dance")))


def png(width, height, colour_type, bit_depth=8, rows=None):
    channels = {0: 1, 2: 3}[colour_type]
    if rows is None:
        rows = b"".join(b"\0" + bytes((x * 7 + y * 13) & 0xFF for x in range(width * channels))
                        for y in range(height))
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


def png_seeds():
    grey = png(8, 6, 0)
    write("png", "grey_8x6", grey)
    write("png", "rgb_8x6", png(8, 6, 2))
    write("png", "truncated", grey[:40])
    write("png", "bad_crc", grey[:29] + bytes([grey[29] ^ 1]) + grey[30:])
    write("png", "grey16", png(4, 2, 0, 16, b"".join(b"\0" + bytes(8) for _ in range(2))))
    write("png", "huge_header", png(1, 1, 0)[:16] + struct.pack(">II", 1 << 30, 1 << 30)
          + png(1, 1, 0)[24:])


def jpeg(width, height, grey):
    """A JPEG of a gradient, from libjpeg-turbo (tjCompress2)."""
    tj = ctypes.CDLL("libturbojpeg.so.0")
    tj.tjInitCompress.restype = ctypes.c_void_p
    handle = ctypes.c_void_p(tj.tjInitCompress())
    channels = 1 if grey else 3
    pixels = bytes((x * 5 + y * 11) & 0xFF for y in range(height) for x in range(width * channels))
    out = ctypes.POINTER(ctypes.c_ubyte)()
    size = ctypes.c_ulong(0)
    TJPF_RGB, TJPF_GRAY, TJSAMP_420, TJSAMP_GRAY = 0, 6, 2, 3
    rc = tj.tjCompress2(handle, pixels, width, 0, height, TJPF_GRAY if grey else TJPF_RGB,
                        ctypes.byref(out), ctypes.byref(size), TJSAMP_GRAY if grey else TJSAMP_420,
                        75, 0)
    assert rc == 0, "tjCompress2 failed"
    data = ctypes.string_at(out, size.value)
    tj.tjFree(out)
    tj.tjDestroy(handle)
    return data


def mjpeg_seeds():
    """fuzz_mjpeg's input: [size/format byte][JPEG]; size index 0: 16x8, 1: 32x24, 2: 320x240;
    bit 2: RGB output."""
    small = jpeg(16, 8, True)
    write("mjpeg", "grey_16x8", bytes([0]) + small)
    write("mjpeg", "rgb420_32x24", bytes([1 | 4]) + jpeg(32, 24, False))
    write("mjpeg", "grey_320x240", bytes([2]) + jpeg(320, 240, True))
    write("mjpeg", "wrong_size", bytes([1]) + small)
    write("mjpeg", "truncated", bytes([0]) + small[:len(small) // 2])
    write("mjpeg", "trailing_garbage", bytes([0]) + small + b"\x00garbage")
    write("mjpeg", "no_soi", bytes([0]) + small[2:])


if __name__ == "__main__":
    main()
