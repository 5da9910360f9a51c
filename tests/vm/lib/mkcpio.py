# SPDX-License-Identifier: Apache-2.0
# Writes a newc cpio archive (initramfs) of a directory, owned by root, plus device nodes.
"""Usage: python3 mkcpio.py DIR OUT.cpio [--dev PATH:c|b:MAJOR:MINOR ...]

Needs no root and no mknod: ownership is forced to 0:0 and device nodes are written as
archive entries. Entries are sorted, mtimes kept, so the output is stable for the same input.
"""
import os
import stat
import sys


def header(ino, mode, size, mtime, nlink, rmaj, rmin, name):
    fields = (ino, mode, 0, 0, nlink, int(mtime), size, 0, 0, rmaj, rmin, len(name) + 1, 0)
    h = b"070701" + b"".join(b"%08X" % f for f in fields)
    h += name.encode() + b"\0"
    return h + b"\0" * ((4 - len(h) % 4) % 4)


def pad(n):
    return b"\0" * ((4 - n % 4) % 4)


def main():
    src, out, devs = sys.argv[1], sys.argv[2], []
    args = sys.argv[3:]
    while args:
        if args[0] == "--dev":
            path, kind, ma, mi = args[1].split(":")
            devs.append((path.strip("/"), kind, int(ma), int(mi)))
            args = args[2:]
        else:
            sys.exit("mkcpio: unknown argument %s" % args[0])
    entries = []
    for root, dirs, files in os.walk(src):
        dirs.sort()
        for n in sorted(dirs + files):
            entries.append(os.path.relpath(os.path.join(root, n), src))
    ino = 1
    with open(out, "wb") as f:
        for rel in sorted(entries):
            p = os.path.join(src, rel)
            st = os.lstat(p)
            ino += 1
            if stat.S_ISLNK(st.st_mode):
                data = os.readlink(p).encode()
            elif stat.S_ISREG(st.st_mode):
                with open(p, "rb") as g:
                    data = g.read()
            elif stat.S_ISDIR(st.st_mode):
                data = b""
            else:
                continue
            f.write(header(ino, st.st_mode, len(data), st.st_mtime, 2 if data == b"" and
                           stat.S_ISDIR(st.st_mode) else 1, 0, 0, rel))
            f.write(data + pad(len(data)))
        for path, kind, ma, mi in devs:
            ino += 1
            mode = (stat.S_IFCHR if kind == "c" else stat.S_IFBLK) | 0o600
            f.write(header(ino, mode, 0, 0, 1, ma, mi, path))
        f.write(header(0, 0, 0, 0, 1, 0, 0, "TRAILER!!!"))


if __name__ == "__main__":
    main()
