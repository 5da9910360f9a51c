#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The dependency rule, checked over every #include line of the source tree.

    dsp, protocol, fileio      know nothing of the rest
    sim, config, recording     know dsp, protocol and fileio only
    hal, viewer                hal wraps the OS; viewer (the web view) may use hal and the
                               layers above
    firmware, tools            wire everything together (neither includes the other)

The fixed-point dsp path also stays pure: it may include only the standard, Eigen and Highway
(SIMD) headers in DSP_STD_ALLOWED (no I/O, no threads, no heap containers).

Usage: scripts/check-includes.py [ROOT]     exit 0 when clean, 1 with one line per violation.
"""
import pathlib
import re
import sys

# Project include prefix (tacse3/<prefix>/...) -> the module that owns it.
PREFIX_MODULE = {
    "dsp": "dsp",
    "dsp_ref": "dsp_ref",
    "protocol": "protocol",
    "protocol_dbc": "protocol",
    "fileio": "fileio",
    "sim": "sim",
    "config": "config",
    "recording": "recording",
    "hal": "hal",
    "viewer": "viewer",
    "firmware": "firmware",
    "tools": "tools",
    "version.hpp": "version",  # generated from the CMake project version (cmake/version.hpp.in)
}

BOTTOM = {"dsp", "protocol", "fileio"}
MIDDLE = BOTTOM | {"sim", "config", "recording"}
# Source folder (relative to ROOT) -> the modules its files may include. Longest match wins.
ALLOWED = {
    "dsp": {"dsp"},
    "dsp/reference": {"dsp", "dsp_ref"},
    "protocol": {"protocol"},
    "fileio": {"fileio"},
    "sim": MIDDLE - {"config", "recording"},
    "config": MIDDLE - {"sim", "recording"},
    "recording": MIDDLE - {"sim", "config"},
    "hal": MIDDLE | {"hal"},
    "viewer": MIDDLE | {"hal", "viewer"},
    "firmware": MIDDLE | {"hal", "viewer", "firmware", "version"},
    "tools": MIDDLE | {"hal", "viewer", "tools", "dsp_ref", "version"},
}

DSP_STD_ALLOWED = {
    "algorithm", "array", "bit", "cmath", "cstddef", "cstdint", "cstring", "limits", "numbers",
    "type_traits", "utility", "Eigen/Core", "Eigen/Geometry", "Eigen/Eigenvalues",
    "emmintrin.h", "arm_neon.h",
    "hwy/highway.h", "hwy/foreach_target.h", "hwy/targets.h",
}

SOURCE_SUFFIXES = {".hpp", ".cpp", ".h", ".c"}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def owner(rel: pathlib.PurePosixPath):
    """The ALLOWED key for a file, or None when the file is not under a checked folder."""
    parts = rel.parts
    for n in range(len(parts) - 1, 0, -1):
        key = "/".join(parts[:n])
        if key in ALLOWED:
            return key
    return None


def check(root: pathlib.Path):
    problems = []
    tops = sorted({k.split("/")[0] for k in ALLOWED})
    files = sorted(p for top in tops for p in (root / top).rglob("*"))
    for path in files:
        if path.suffix not in SOURCE_SUFFIXES or not path.is_file():
            continue
        rel = pathlib.PurePosixPath(path.relative_to(root).as_posix())
        key = owner(rel)
        if key is None:
            continue
        for lineno, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            kind, target = m.groups()
            if kind == '"' and target.startswith("tacse3/"):
                prefix = target.split("/")[1]
                module = PREFIX_MODULE.get(prefix)
                if module is None:
                    problems.append(f"{rel}:{lineno}: unknown module in #include \"{target}\"")
                elif module not in ALLOWED[key]:
                    problems.append(f"{rel}:{lineno}: {key}/ may not include \"{target}\" "
                                    f"(allowed: {', '.join(sorted(ALLOWED[key]))})")
            elif kind == "<" and key == "dsp" and target not in DSP_STD_ALLOWED:
                problems.append(f"{rel}:{lineno}: the fixed-point dsp path may not include "
                                f"<{target}> (no I/O, threads or heap; see DSP_STD_ALLOWED)")
    return problems


def main(argv):
    root = pathlib.Path(argv[1] if len(argv) > 1 else pathlib.Path(__file__).resolve().parents[1])
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print(f"check-includes: {len(problems)} include(s) break the dependency rule "
              "(README.md, Layout): move the code to the layer that may use it")
        return 1
    print("check-includes: the dependency rule holds")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
