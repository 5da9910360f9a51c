#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""scripts/check-includes.py: it passes the real tree and names each kind of crossing it must catch.

Usage: test_check_includes.py CHECKER ROOT
"""
import pathlib
import subprocess
import sys
import tempfile

checker, root = sys.argv[1], sys.argv[2]


def run(tree):
    return subprocess.run([sys.executable, checker, str(tree)], capture_output=True, text=True)


def write(tree, rel, text):
    p = tree / rel
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)


failures = []
real = run(root)
if real.returncode != 0:
    failures.append("the source tree breaks the rule:\n" + real.stdout)

# Each case: (file, its text, a fragment the message must carry). A clean file sits beside them.
cases = [
    ("dsp/src/a.cpp", '#include "tacse3/hal/camera.hpp"\n', 'dsp/ may not include "tacse3/hal/camera.hpp"'),
    ("dsp/include/tacse3/dsp/b.hpp", "#include <vector>\n", "may not include <vector>"),
    ("dsp/src/c.cpp", '#include "tacse3/dsp_ref/x.hpp"\n', 'dsp/ may not include "tacse3/dsp_ref/x.hpp"'),
    ("protocol/src/d.cpp", '#include "tacse3/dsp/types.hpp"\n', 'protocol/ may not include'),
    ("dsp/src/d2.cpp", '#include "tacse3/fileio/file_io.hpp"\n', 'dsp/ may not include'),
    ("fileio/src/d3.cpp", '#include "tacse3/dsp/types.hpp"\n', 'fileio/ may not include'),
    ("sim/src/e.cpp", '#include "tacse3/config/board_file.hpp"\n', 'sim/ may not include'),
    ("config/src/f.cpp", '#include "tacse3/hal/gpio.hpp"\n', 'config/ may not include'),
    ("recording/src/g.cpp", '#include "tacse3/sim/pad.hpp"\n', 'recording/ may not include'),
    ("hal/can/src/h.cpp", '#include "tacse3/firmware/daemon.hpp"\n', 'hal/ may not include'),
    ("firmware/src/i.cpp", '#include "tacse3/tools/replay.hpp"\n', 'firmware/ may not include'),
    ("tools/x/j.cpp", '#include "tacse3/firmware/daemon.hpp"\n', 'tools/ may not include'),
    ("tools/x/k.cpp", '#include "tacse3/nonsense/a.hpp"\n', "unknown module"),
    ("viewer/src/l.cpp", '#include "tacse3/firmware/engine.hpp"\n', 'viewer/ may not include'),
    ("viewer/src/m.cpp", '#include "tacse3/tools/replay.hpp"\n', 'viewer/ may not include'),
    ("hal/can/src/n.cpp", '#include "tacse3/viewer/view_server.hpp"\n', 'hal/ may not include'),
    ("recording/src/o.cpp", '#include "tacse3/viewer/view_json.hpp"\n', 'recording/ may not include'),
]
with tempfile.TemporaryDirectory() as tmp:
    tree = pathlib.Path(tmp)
    write(tree, "hal/camera/src/ok.cpp",
          '#include "tacse3/sim/pad.hpp"\n#include "tacse3/recording/recording.hpp"\n#include <vector>\n')
    write(tree, "dsp/reference/src/ok.cpp", '#include "tacse3/dsp_ref/x.hpp"\n#include <vector>\n')
    write(tree, "config/src/ok.cpp", '#include "tacse3/fileio/file_io.hpp"\n#include "tacse3/dsp/x.hpp"\n')
    write(tree, "viewer/src/ok.cpp", '#include "tacse3/hal/thread.hpp"\n#include "tacse3/dsp/x.hpp"\n')
    write(tree, "firmware/src/ok.cpp", '#include "tacse3/viewer/view_server.hpp"\n')
    write(tree, "tools/x/ok.cpp", '#include "tacse3/viewer/view_server.hpp"\n')
    clean = run(tree)
    if clean.returncode != 0:
        failures.append("a clean tree was refused:\n" + clean.stdout)
    for rel, text, fragment in cases:
        write(tree, rel, text)
        out = run(tree)
        if out.returncode != 1 or f"{rel}:1:" not in out.stdout or fragment not in out.stdout:
            failures.append(f"{rel}: expected exit 1 and '{fragment}', got {out.returncode}:\n{out.stdout}")
        (tree / rel).unlink()

for f in failures:
    print("FAIL:", f)
print(f"{len(cases) + 2 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
