#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tacse3-replay --plot end to end: a short simulated rotation replayed to an SVG and a PNG.

The SVG must be well-formed XML of the layout's size with one stroke per series and legend sample
in each role's colour (8 panels with truth, 6 and a note without); the PNG must decode at that
size, not blank, with the truth, estimate and error colours in it. An output that cannot be
written fails before the replay and leaves neither the figure nor the CSV.

Usage: test_replay_plot.py TOOLS_BUILD_DIR
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zlib

# tools/common/include/tacse3/tools/plot_render.hpp and plot_layout.hpp.
TRUTH, ESTIMATE, ERROR, NOTE = (230, 159, 0), (0, 114, 178), (213, 94, 0), (180, 0, 0)
WIDTH = 900


def height(panels):
    return 62 + panels * 110 + (panels - 1) * 24 + 46


def run(args, expect_rc=0):
    p = subprocess.run(args, capture_output=True, text=True, timeout=120)
    if p.returncode != expect_rc:
        sys.exit(f"FAIL: {' '.join(args)}: exit {p.returncode}, expected {expect_rc}\n{p.stderr}")
    return p


def rgb(text):
    return tuple(round(float(v) * 2.55) for v in text)


def svg_colours(path):
    """(stroke colour -> count of stroked paths, set of fill colours), after an XML parse."""
    root = ET.parse(path).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg", root.tag
    strokes, fills = {}, set()
    for el in root.iter():
        style = el.get("style", "")
        m = re.search(r"stroke:rgb\(([\d.]+)%,([\d.]+)%,([\d.]+)%\)", style)
        if m and el.tag.endswith("path"):
            c = rgb(m.groups())
            strokes[c] = strokes.get(c, 0) + 1
        m = re.search(r"fill:rgb\(([\d.]+)%,([\d.]+)%,([\d.]+)%\)", style)
        if m:
            fills.add(rgb(m.groups()))
    return root, strokes, fills


def png_pixels(path):
    """(width, height, set of RGB colours) of an 8-bit RGB, non-interlaced PNG (cairo's RGB24)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, ihdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype, _, _, interlace = ihdr
    assert (depth, ctype, interlace) == (8, 2, 0), ihdr
    raw, bpp, stride = zlib.decompress(idat), 3, w * 3
    prev, colours = bytearray(stride), set()
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        colours.update(zip(line[0::3], line[1::3], line[2::3]))
        prev = line
    return w, h, colours


def main():
    tools = sys.argv[1]
    sim, replay = f"{tools}/sim/tacse3-sim", f"{tools}/replay/tacse3-replay"
    t = tempfile.mkdtemp(prefix="tacse3-plot.")
    try:
        rec = f"{t}/rz5"
        run([sim, "-q", "--out", rec, "--object", "sphere", "--motion", "rz", "--magnitude", "5",
             "--colour", "grey", "--approach-s", "0.02", "--grasp-s", "0.1", "--settle-s", "0.02",
             "--hold-s", "0.05"])
        run([replay, rec, "-q", "--out", f"{t}/o.csv", "--plot", f"{t}/f.svg"])
        root, strokes, fills = svg_colours(f"{t}/f.svg")
        assert root.get("viewBox") == f"0 0 {WIDTH} {height(8)}", root.get("viewBox")
        # 6 axis panels × (series + legend) for truth and estimate; 2 error panels.
        assert (strokes.get(TRUTH), strokes.get(ESTIMATE), strokes.get(ERROR)) == (12, 12, 4), strokes
        assert NOTE not in fills, "a note on a figure with truth"

        run([replay, rec, "-q", "--out", f"{t}/o.csv", "--plot", f"{t}/f.PNG"])
        w, h, colours = png_pixels(f"{t}/f.PNG")
        assert (w, h) == (WIDTH, height(8)), (w, h)
        for name, c in (("truth", TRUTH), ("estimate", ESTIMATE), ("error", ERROR)):
            assert c in colours, f"no {name} colour {c} in the PNG"
        assert len(colours) > 20, "blank PNG"

        bare = f"{t}/bare"
        shutil.copytree(rec, bare)
        os.remove(f"{bare}/truth.csv")
        run([replay, bare, "-q", "--out", f"{t}/o.csv", "--plot", f"{t}/bare.svg"])
        root, strokes, fills = svg_colours(f"{t}/bare.svg")
        assert root.get("viewBox") == f"0 0 {WIDTH} {height(6)}", root.get("viewBox")
        assert (strokes.get(TRUTH), strokes.get(ESTIMATE), strokes.get(ERROR)) == (None, 12, None), strokes
        assert NOTE in fills, "no note that the truth is missing"

        # A figure that cannot be written: refused before the replay, no CSV left behind.
        p = run([replay, rec, "-q", "--out", f"{t}/x.csv", "--plot", f"{t}/nodir/f.svg"], 1)
        assert f"--plot {t}/nodir/f.svg" in p.stderr, p.stderr
        assert not os.path.exists(f"{t}/x.csv"), "CSV left after a --plot failure"
        # An existing figure is replaced whole.
        run([replay, rec, "-q", "--out", f"{t}/o.csv", "--plot", f"{t}/bare.svg"])
        assert svg_colours(f"{t}/bare.svg")[0].get("viewBox") == f"0 0 {WIDTH} {height(8)}"
        assert not [n for n in os.listdir(t) if n.startswith(".")], os.listdir(t)
    finally:
        shutil.rmtree(t)
    print("replay --plot: 1 passed, 0 failed")


if __name__ == "__main__":
    main()
