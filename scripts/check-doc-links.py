#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every relative link in the repository's Markdown resolves: the file exists and, for a
#fragment, the target page has a heading with that GitHub anchor.

Usage: scripts/check-doc-links.py [ROOT]      exit 0 when every link resolves, 1 otherwise.
"""
import pathlib
import re
import subprocess
import sys

LINK = re.compile(r"(?<!\!)\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
IMAGE = re.compile(r"\!\[[^\]]*\]\(([^)\s]+)\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def slug(text):
    """GitHub's heading anchor: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link in a heading keeps its text
    text = text.lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def body_lines(path):
    """The lines outside fenced code blocks."""
    fenced = False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith(("```", "~~~")):
            fenced = not fenced
            continue
        if not fenced:
            yield line


def anchors(path, cache={}):
    if path not in cache:
        seen, out = {}, set()
        for line in body_lines(path):
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            out.add(base if n == 0 else f"{base}-{n}")
        for m in re.finditer(r'<a (?:name|id)="([^"]+)"', path.read_text(encoding="utf-8")):
            out.add(m.group(1))
        cache[path] = out
    return cache[path]


def markdown_files(root):
    try:
        out = subprocess.run(["git", "-C", str(root), "ls-files", "-co", "--exclude-standard",
                              "*.md"], capture_output=True, text=True, check=True).stdout
        return sorted(root / p for p in out.splitlines() if (root / p).is_file())
    except (OSError, subprocess.CalledProcessError):
        return sorted(p for p in root.rglob("*.md")
                      if not {"build", "node_modules", ".git"} & set(p.parts))


def check(root):
    problems = []
    for page in markdown_files(root):
        rel_page = page.relative_to(root)
        for lineno, line in enumerate(body_lines(page), 1):
            line = re.sub(r"`[^`]*`", "", line)  # inline code is not a link
            for m in list(LINK.finditer(line)) + list(IMAGE.finditer(line)):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("//"):
                    continue  # an absolute URL or mailto:
                file_part, _, fragment = target.partition("#")
                dest = page if not file_part else (page.parent / file_part).resolve()
                if not dest.exists():
                    problems.append(f"{rel_page}: link to missing file {target}")
                elif fragment and dest.suffix == ".md" and fragment not in anchors(dest):
                    problems.append(f"{rel_page}: link to missing anchor {target}")
    return problems


def main(argv):
    root = pathlib.Path(argv[1] if len(argv) > 1 else pathlib.Path(__file__).resolve().parents[1])
    problems = check(root.resolve())
    for p in problems:
        print(p)
    if problems:
        print(f"check-doc-links: {len(problems)} broken link(s)")
        return 1
    print("check-doc-links: every relative link resolves")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
