#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: build the Python package (python/) as a wheel and as the Debian package python3-tacse3,
# offline, with Debian's pip, setuptools and wheel; then install each into a scratch directory and
# import it with /usr/bin/python3 (which sees Debian's python3-can).
#
# Usage: scripts/package-python.sh [--out DIR]      (default: build/python-package)
# Writes DIR/tacse3-<version>-py3-none-any.whl and DIR/python3-tacse3_<version>_all.deb.
# Exits non-zero with a message naming the problem.
set -euo pipefail
cd "$(dirname "$0")/.."
SRC="$PWD"
OUT="$SRC/build/python-package"
PY=/usr/bin/python3

die() {
  echo "package-python: $*" >&2
  exit 1
}

while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || { echo "usage: $0 [--out DIR]" >&2; exit 2; }; OUT="$2"; shift 2 ;;
    -h | --help) sed -n '3,9p' "$0"; exit 0 ;;
    *) echo "package-python: unknown argument '$1' (usage: $0 [--out DIR])" >&2; exit 2 ;;
  esac
done
for tool in dpkg-deb "$PY"; do
  command -v "$tool" >/dev/null || die "$tool not found (scripts/setup.sh installs it)"
done
{ "$PY" -c 'import setuptools, wheel, can' && "$PY" -m pip --version; } >/dev/null 2>&1 ||
  die "$PY lacks pip, setuptools, wheel or can: apt-get install python3-pip python3-setuptools python3-wheel python3-can"

# One version everywhere: the CMake project, pyproject.toml and tacse3.__version__.
version=$(sed -n 's/^project(tacse3 VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt | head -n1)
py_version=$(sed -n 's/^version = "\(.*\)"$/\1/p' python/pyproject.toml)
init_version=$(sed -n 's/^__version__ = "\(.*\)"$/\1/p' python/src/tacse3/__init__.py)
[ "$py_version" = "$version" ] || die "python/pyproject.toml version $py_version != project version $version"
[ "$init_version" = "$version" ] || die "tacse3.__version__ $init_version != project version $version"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$OUT"
wheel="$OUT/tacse3-$version-py3-none-any.whl"
deb="$OUT/python3-tacse3_${version}_all.deb"
rm -f "$wheel" "$deb"

# setuptools writes build/ and *.egg-info next to pyproject.toml: build from a copy.
cp -r python "$tmp/src"
rm -rf "$tmp/src/tests"
"$PY" -m pip wheel --quiet --no-build-isolation --no-deps --no-index --wheel-dir "$tmp/wheel" "$tmp/src" ||
  die "pip wheel failed"
mv "$tmp/wheel/tacse3-$version-py3-none-any.whl" "$wheel"

# The .deb: the wheel's contents in Debian's directory for pure Python modules.
root="$tmp/root"
site="$root/usr/lib/python3/dist-packages"
mkdir -p "$site" "$root/DEBIAN" "$root/usr/share/doc/python3-tacse3"
"$PY" -m zipfile -e "$wheel" "$site"
rm -f "$site"/tacse3-*.dist-info/RECORD # pip's record of the wheel install, not dpkg's
cp python/README.md "$root/usr/share/doc/python3-tacse3/README.md"
cat >"$root/DEBIAN/control" <<CONTROL
Package: python3-tacse3
Version: $version
Architecture: all
Section: python
Priority: optional
Maintainer: tacse3 developers <tacse3@localhost>
Depends: python3 (>= 3.9), python3-can (>= 4.0)
Description: tacse3 gripper CAN protocol for Python controllers
 Decodes the tacse3 gripper's twist/pose cycles and status frames, encodes every
 command, sends commands and waits for their ACK (tacse3.Client), and reads
 candump -L logs. Pure Python on python-can.
CONTROL
find "$root" -type d -exec chmod 755 {} +
find "$root" -type f -exec chmod 644 {} +
dpkg-deb --root-owner-group --build "$root" "$deb" >/dev/null || die "dpkg-deb failed"

# Install each into a scratch directory and import it from there.
check_import() { # dir what
  PYTHONPATH="$1" PYTHONDONTWRITEBYTECODE=1 "$PY" - "$1" "$2" <<'CHECK'
import os, sys
import tacse3
where, what = sys.argv[1], sys.argv[2]
if not os.path.realpath(tacse3.__file__).startswith(os.path.realpath(where)):
    sys.exit(f"package-python: {what}: imported {tacse3.__file__}, not the packaged copy")
ack = tacse3.decode(tacse3.encode_ack(tacse3.Ack(1, "TARE", "ACK", 3)))
assert (ack.command, ack.sequence, ack.ok) == ("TARE", 3, True), ack
print(f"package-python: {what}: import tacse3 {tacse3.__version__} OK "
      f"(protocol {'.'.join(map(str, tacse3.PROTOCOL_VERSION))})")
CHECK
}
mkdir -p "$tmp/wheel-root" "$tmp/deb-root"
"$PY" -m zipfile -e "$wheel" "$tmp/wheel-root"
check_import "$tmp/wheel-root" "$(basename "$wheel")" || die "the wheel does not import"
dpkg-deb -x "$deb" "$tmp/deb-root"
check_import "$tmp/deb-root/usr/lib/python3/dist-packages" "$(basename "$deb")" ||
  die "the .deb does not import"
[ "$(dpkg-deb -f "$deb" Depends)" = "python3 (>= 3.9), python3-can (>= 4.0)" ] ||
  die "$(basename "$deb"): unexpected Depends: $(dpkg-deb -f "$deb" Depends)"
listing=$(dpkg-deb -c "$deb")
grep -q ' ./usr/lib/python3/dist-packages/tacse3/message_table.json$' <<<"$listing" ||
  die "$(basename "$deb") lacks tacse3/message_table.json"
echo "package-python: wrote $wheel and $deb"
