# SPDX-License-Identifier: Apache-2.0
# Stages a VM userland from Debian .debs: chosen files plus the closure of their shared libraries.
"""Usage: python3 userland.py --arch arm64 --spec FILE --out DIR --manifest FILE [--extra PKG ...]

The spec has one package a line: `PACKAGE MODE [GLOB ...] [@DEBARCH ...]`, '#' starts a
comment; `@amd64` (or `@arm64`) limits a line to that Debian architecture.
  files GLOB...  copy the package files matching the globs (paths without the leading './');
                 every glob must match something, so a layout change in Debian fails loudly
  all            copy the whole package except docs, manuals, locales and headers
  libs           copy only its shared libraries (*.so.*) from the library directories

Every ELF file copied gets its NEEDED libraries and its program interpreter from the packages'
Depends, resolved by soname: a package is downloaded and unpacked (dpkg -x) only when a library
is still missing, and only the dependencies of packages that supplied files are followed.

Paths are merged into /usr: bin, sbin and usr/sbin go to usr/bin, lib to usr/lib, lib64 to
usr/lib64. The guest root has /lib -> usr/lib and /lib64 -> usr/lib64 symlinks, and keeps /bin
for busybox, so nothing here can overwrite busybox or its applet links.

apt runs with the caller's APT_CONFIG (the private apt state of tests/vm/lib/common.sh).
"""
import argparse
import fnmatch
import os
import re
import shutil
import subprocess
import sys

SKIP_PREFIXES = ("usr/share/doc/", "usr/share/man/", "usr/share/locale/", "usr/share/lintian/",
                 "usr/share/bug/", "usr/share/bash-completion/", "usr/include/", "usr/share/info/")


def die(msg):
    sys.stderr.write("userland: ERROR: %s\n" % msg)
    sys.exit(1)


def merged(path):
    """Maps a package path (no leading slash) to its place in the merged-/usr guest root."""
    path = os.path.normpath(path).lstrip("/")
    for old, new in (("bin/", "usr/bin/"), ("sbin/", "usr/bin/"), ("usr/sbin/", "usr/bin/"),
                     ("lib/", "usr/lib/"), ("lib64/", "usr/lib64/")):
        if path.startswith(old):
            return new + path[len(old):]
    return path


class Debs:
    def __init__(self, arch, debdir, xdir):
        self.arch, self.debdir, self.xdir = arch, debdir, xdir
        self.trees = {}      # package -> extracted directory
        self.index = {}      # merged path -> (package, path inside that package's tree)

    def q(self, pkg):
        return pkg if ":" in pkg else "%s:%s" % (pkg, self.arch)

    def fetch(self, pkgs):
        """Downloads and unpacks packages named as apt wants them (name:arch, or name for
        architecture-independent ones)."""
        pkgs = [p for p in pkgs if p.split(":")[0] not in self.trees]
        if not pkgs:
            return
        names = {f.split("_", 1)[0]: f for f in deb_names(
            run(["apt-cache", "show", "--no-all-versions"] + pkgs))}
        if any(p.split(":")[0] not in names for p in pkgs):
            die("apt-cache show did not describe all of %s" % " ".join(pkgs))
        want = [names[p.split(":")[0]] for p in pkgs]
        stale = [p for p, f in zip(pkgs, want) if not os.path.exists(os.path.join(self.debdir, f))]
        if stale:
            for attempt in range(3):
                r = subprocess.run(["apt-get", "-q", "download"] + stale,
                                   cwd=self.debdir, capture_output=True, text=True)
                if r.returncode == 0:
                    break
                sys.stderr.write(r.stdout + r.stderr)
            else:
                die("apt-get download failed for %s" % " ".join(stale))
        for fname in want:
            name = fname.split("_", 1)[0]
            tree = os.path.join(self.xdir, fname[:-len(".deb")])
            if not os.path.exists(os.path.join(tree, ".extracted")):
                shutil.rmtree(tree, ignore_errors=True)
                os.makedirs(tree + ".tmp", exist_ok=True)
                run(["dpkg", "-x", os.path.join(self.debdir, fname), tree + ".tmp"])
                open(os.path.join(tree + ".tmp", ".extracted"), "w").close()
                os.rename(tree + ".tmp", tree)
            self.trees[name] = tree
            for root, dirs, files in os.walk(tree):
                for f in files + [d for d in dirs if os.path.islink(os.path.join(root, d))]:
                    rel = os.path.relpath(os.path.join(root, f), tree)
                    if rel != ".extracted":
                        self.index.setdefault(merged(rel), (name, rel))
        missing = [p for p in pkgs if p.split(":")[0] not in self.trees]
        if missing:
            die("apt did not return %s" % " ".join(missing))

    def depends(self, pkgs):
        """Direct Depends/PreDepends (first alternative; a virtual one's first provider)."""
        out = run(["apt-cache", "depends", "--no-recommends", "--no-suggests", "--no-conflicts",
                   "--no-breaks", "--no-replaces", "--no-enhances"] + [self.q(p) for p in pkgs])
        deps, skip_next, want_provider = [], False, False
        for line in out.splitlines():
            m = re.match(r"^  (\|?)(?:Pre)?Depends: (\S+)", line)
            if m:
                alt, name = m.group(1) == "|", m.group(2)
                if not skip_next:
                    if name.startswith("<"):
                        want_provider = True
                    else:
                        deps.append(name)
                skip_next = alt
                continue
            m = re.match(r"^    (\S+)", line)
            if m and want_provider:
                deps.append(m.group(1))
                want_provider = False
                continue
            if not line.startswith(" "):
                skip_next = want_provider = False
        return sorted(set(deps))

    def resolve(self, mpath, hops=0):
        """Follows symlinks through the index; returns (package, real file) or None."""
        if hops > 20 or mpath not in self.index:
            return None
        pkg, rel = self.index[mpath]
        src = os.path.join(self.trees[pkg], rel)
        if os.path.islink(src):
            target = os.readlink(src)
            nxt = merged(target) if target.startswith("/") else merged(
                os.path.join(os.path.dirname(rel), target))
            return self.resolve(nxt, hops + 1)
        return pkg, src


def deb_names(show):
    """File names `apt-get download` gives the packages of an `apt-cache show` output, in order."""
    names = []
    for stanza in show.split("\n\n"):
        f = dict(re.findall(r"^(Package|Version|Architecture): (\S+)$", stanza, re.M))
        if "Package" in f:
            names.append("%s_%s_%s.deb" % (f["Package"], f["Version"].replace(":", "%3a"),
                                           f["Architecture"]))
    return names


def run(cmd, cwd=None):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if r.returncode != 0:
        die("%s failed:\n%s%s" % (" ".join(cmd), r.stdout, r.stderr))
    return r.stdout


def elf_info(path):
    """Returns (needed sonames, runpath dirs, interpreter) or None for a non-ELF file."""
    with open(path, "rb") as f:
        if f.read(4) != b"\x7fELF":
            return None
    out = subprocess.run(["readelf", "-dlW", path], capture_output=True, text=True).stdout
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", out)
    runpath = []
    for m in re.findall(r"\((?:RUNPATH|RPATH)\)\s+Library r(?:un)?path: \[([^\]]+)\]", out):
        runpath += m.split(":")
    interp = re.search(r"Requesting program interpreter: ([^\]]+)\]", out)
    return needed, runpath, interp.group(1) if interp else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--arch", required=True)
    ap.add_argument("--triplet", required=True)
    ap.add_argument("--spec", required=True)
    ap.add_argument("--debs", required=True)
    ap.add_argument("--xdir", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--manifest", required=True)
    ap.add_argument("--extra", nargs="*", default=[], help="more packages in 'libs' mode")
    ap.add_argument("--elf", nargs="*", default=[],
                    help="extra ELF files (host paths) whose libraries must be staged too")
    ap.add_argument("--have", help="manifest of an earlier staging: its files count as present "
                    "(not copied again) and its packages' dependencies may be followed")
    a = ap.parse_args()

    spec = []
    for line in open(a.spec):
        words = line.split("#", 1)[0].split()
        only = [w[1:] for w in words if w.startswith("@")]
        words = [w for w in words if not w.startswith("@")]
        if words and (not only or a.arch in only):
            spec.append((words[0], words[1], words[2:]))
    spec += [(p, "libs", []) for p in a.extra]

    debs = Debs(a.arch, a.debs, a.xdir)
    debs.fetch([debs.q(p) for p, _, _ in spec])
    have, have_pkgs = set(), set()
    if a.have:
        for line in open(a.have):
            path, pkg = line.rstrip("\n").split("\t")
            have.add(path)
            have_pkgs.add(pkg)
        debs.fetch([debs.q(p) for p in sorted(have_pkgs)])
    libdirs = ["usr/lib/" + a.triplet, "usr/lib"]
    staged = {}      # merged path -> source file
    origin = {}      # merged path -> package that supplied it
    for pkg, mode, globs in spec:
        tree = debs.trees[pkg]
        rels = []
        for root, dirs, files in os.walk(tree):
            for f in files + [d for d in dirs if os.path.islink(os.path.join(root, d))]:
                rels.append(os.path.relpath(os.path.join(root, f), tree))
        rels = [r for r in rels if r != ".extracted"]
        if mode == "files":
            for g in globs:
                hit = [r for r in rels if fnmatch.fnmatch(r, g)]
                if not hit:
                    die("%s: no file matches %s" % (pkg, g))
                for r in hit:
                    staged[merged(r)] = os.path.join(tree, r)
                    origin[merged(r)] = pkg
        elif mode in ("all", "libs"):
            for r in rels:
                m = merged(r)
                if m.startswith(SKIP_PREFIXES):
                    continue
                if mode == "libs" and not (os.path.dirname(m) in libdirs and ".so." in m):
                    continue
                staged[m] = os.path.join(tree, r)
                origin[m] = pkg
        else:
            die("%s: unknown mode %s" % (pkg, mode))

    extra_elfs = list(a.elf)
    scanned, providers, followed = set(), set(p for p, _, _ in spec) | have_pkgs, set()
    pending = {}   # soname (or merged interpreter path) -> directories to search (None: exact path)
    while True:
        for m, src in list(staged.items()) + [(None, e) for e in extra_elfs]:
            if (m, src) in scanned or os.path.islink(src) or not os.path.isfile(src):
                continue
            scanned.add((m, src))
            info = elf_info(src)
            if not info:
                continue
            needed, runpath, interp = info
            dirs = []
            for rp in runpath:
                if m is not None:
                    rp = rp.replace("$ORIGIN", "/" + os.path.dirname(m))
                dirs.append(merged(rp))
            dirs += libdirs
            if interp:
                pending.setdefault(merged(interp), None)
            for so in needed:
                pending.setdefault(so, dirs)
        progress = False
        for so, dirs in list(pending.items()):
            cands = [so] if dirs is None else [os.path.join(d, so) for d in dirs]
            if any(c in staged or c in have for c in cands):
                del pending[so]
                continue
            for c in cands:
                hit = debs.resolve(c)
                if hit:
                    staged[c], origin[c] = hit[1], hit[0]
                    providers.add(hit[0])
                    del pending[so]
                    progress = True
                    break
        if not pending and not progress:
            break
        if pending and not progress:
            todo = sorted(providers - followed)
            deps = [d for d in debs.depends(todo) if d.split(":")[0] not in debs.trees] if todo else []
            followed.update(todo)
            if not todo:
                die("unresolved libraries: %s\n  Add the Debian package that ships each one to "
                    "TACSE3_VM_EXTRA_PACKAGES (or to tests/vm/userland.spec)." % " ".join(sorted(pending)))
            if deps:
                debs.fetch(deps)

    # Copy, dereferencing library symlinks except those inside "all"/"files" packages.
    os.makedirs(a.out, exist_ok=True)
    with open(a.manifest, "w") as man:
        for m in sorted(staged):
            src, dst = staged[m], os.path.join(a.out, m)
            os.makedirs(os.path.dirname(dst), exist_ok=True)
            if os.path.lexists(dst):
                os.unlink(dst)
            if os.path.islink(src):
                target = os.readlink(src)
                hit = debs.resolve(m)
                if not target.startswith("/") and (merged(os.path.join(os.path.dirname(m), target)) in staged):
                    os.symlink(target, dst)
                elif hit:
                    shutil.copy2(hit[1], dst)
                else:
                    os.symlink(target, dst)
            elif os.path.isdir(src):
                os.makedirs(dst, exist_ok=True)
            else:
                shutil.copy2(src, dst)
            man.write("%s\t%s\n" % (m, origin.get(m, "?")))
    sys.stderr.write("userland: %d files from %d packages (%d unpacked)\n"
                     % (len(staged), len(set(origin.values())), len(debs.trees)))


if __name__ == "__main__":
    main()
