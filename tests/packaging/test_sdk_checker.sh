#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The SDK package checker (scripts/package-sdk.sh --check) on damaged copies of two good amd64
# packages: the good pair passes, and each defect it exists to catch is refused with its message.
# Usage: tests/packaging/test_sdk_checker.sh DEV_DEB LIB_DEB     (scripts/package-sdk.sh runs it)
set -euo pipefail
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
fail() {
  echo "test-sdk-checker: FAIL: $*" >&2
  exit 1
}
[ $# -eq 2 ] || { echo "usage: $0 DEV_DEB LIB_DEB" >&2; exit 2; }
dev="$1" lib="$2"
ma=$(dpkg-architecture -a amd64 -qDEB_HOST_MULTIARCH 2>/dev/null)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
check() { "$SRC/scripts/package-sdk.sh" --check "$1" "$2" amd64 >"$TMP/out" 2>&1; }
check "$dev" "$lib" || fail "the good packages are refused: $(cat "$TMP/out")"

# damaged NAME dev|lib 'commands run in the unpacked tree' REGEX: repack with the change, expect REGEX.
n=0
damaged() {
  local name="$1" which="$2" change="$3" want="$4" tree out d="$dev" l="$lib"
  tree="$TMP/$name/tree"
  mkdir -p "$TMP/$name/out"
  if [ "$which" = dev ]; then dpkg-deb -R "$dev" "$tree"; else dpkg-deb -R "$lib" "$tree"; fi
  (cd "$tree" && eval "$change")
  if [ "$which" = dev ]; then out="$TMP/$name/out/$(basename "$dev")"; d="$out"; else out="$TMP/$name/out/$(basename "$lib")"; l="$out"; fi
  dpkg-deb --root-owner-group -b "$tree" "$out" >/dev/null
  if check "$d" "$l"; then fail "$name: the checker accepted it"; fi
  grep -qE "$want" "$TMP/out" || fail "$name: refused without saying /$want/: $(cat "$TMP/out")"
  n=$((n + 1))
}
damaged no-header dev 'rm usr/include/tacse3/protocol/codec.hpp' 'missing or different: /usr/include/tacse3/protocol/codec.hpp'
damaged extra-file dev "touch usr/lib/$ma/libextra.a" "unexpected: /usr/lib/$ma/libextra.a"
damaged wrong-link dev "ln -sfn libtacse3_protocol.so.0 usr/lib/$ma/libtacse3_protocol.so" \
  "missing or different: /usr/lib/$ma/libtacse3_protocol.so libtacse3_protocol.so.0"
damaged extra-depends lib "sed -i 's/^Depends: .*/&, libstdc++6 (>= 12)/' DEBIAN/control" "Depends: .*libstdc"
damaged no-trigger lib 'rm DEBIAN/triggers' 'DEBIAN/triggers lacks'
# A library that exports a symbol outside tacse3::protocol (the SONAME it should have).
so=$(basename "$(dpkg-deb -c "$lib" | awk '$1 ~ /^-/ { print $6 }')")
printf 'int helper(int x) { return x + 1; }\n' >"$TMP/helper.cpp"
g++ -shared -fPIC -s -Wl,-soname,"$(dpkg-deb -f "$lib" Package | sed 's/^libtacse3-protocol/libtacse3_protocol.so./')" \
  -o "$TMP/helper.so" "$TMP/helper.cpp"
damaged foreign-symbol lib "cp '$TMP/helper.so' usr/lib/$ma/$so" "exports helper\(int\)"
echo "test-sdk-checker: the good amd64 pair passes; $n damaged copies refused (missing header, extra file, wrong link, extra Depends, no ldconfig trigger, foreign symbol)"
