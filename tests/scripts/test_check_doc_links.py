#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""scripts/check-doc-links.py: it passes the repository's docs and catches each kind of broken link.

Usage: test_check_doc_links.py CHECKER ROOT
"""
import pathlib
import subprocess
import sys
import tempfile

checker, root = sys.argv[1], sys.argv[2]
failures = []


def run(tree):
    return subprocess.run([sys.executable, checker, str(tree)], capture_output=True, text=True)


real = run(root)
if real.returncode != 0:
    failures.append("the repository has broken links:\n" + real.stdout)

GOOD = """# Title
## Scaling and overflow (Q formats)
## Twice
## Twice
See [self](#title), [q](#scaling-and-overflow-q-formats), [dup](#twice-1), [b](b.md#b-page),
[web](https://example.org/x.md), [mail](mailto:a@b.c), `[not a link](nowhere.md)`.
```
[in a fence](nowhere.md)
```
"""
cases = [
    ("[x](missing.md)", "link to missing file missing.md"),
    ("[x](b.md#no-such-heading)", "link to missing anchor b.md#no-such-heading"),
    ("[x](#twice-2)", "link to missing anchor #twice-2"),
    ("![img](pic.png)", "link to missing file pic.png"),
]
with tempfile.TemporaryDirectory() as tmp:
    tree = pathlib.Path(tmp)
    (tree / "b.md").write_text("# B page\n")
    (tree / "a.md").write_text(GOOD)
    out = run(tree)
    if out.returncode != 0:
        failures.append("good links were refused:\n" + out.stdout)
    for text, fragment in cases:
        (tree / "a.md").write_text(GOOD + text + "\n")
        out = run(tree)
        if out.returncode != 1 or fragment not in out.stdout:
            failures.append(f"{text}: expected exit 1 and '{fragment}', got {out.returncode}:\n{out.stdout}")

for f in failures:
    print("FAIL:", f)
print(f"{len(cases) + 2 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
