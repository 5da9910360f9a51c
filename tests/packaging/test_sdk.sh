#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 SDK test: extracts tacse3-dev and the runtime library package into a scratch tree (no root,
# dpkg-deb -x) and builds the consumer of tests/packaging/sdk against it the ways docs/sdk.md
# gives, then runs each build (it decodes a golden frame and checks the values).
#   amd64:        CMake find_package static and shared, pkg-config shared (g++ without -std) and
#                 static, and the packaged controller example
#   arm64, armhf: the cross compiler with pkg-config, shared and static, run under qemu-user
# Usage: tests/packaging/test_sdk.sh DEV_DEB LIB_DEB ARCH     (scripts/package-sdk.sh runs it)
set -euo pipefail
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
CONSUMER="$SRC/tests/packaging/sdk"

fail() {
  echo "test-sdk: FAIL: $*" >&2
  exit 1
}
[ $# -eq 3 ] || { echo "usage: $0 DEV_DEB LIB_DEB ARCH" >&2; exit 2; }
dev="$1" lib="$2" arch="$3"
ma=$(dpkg-architecture -a "$arch" -qDEB_HOST_MULTIARCH 2>/dev/null) || fail "unknown architecture $arch"
soname=$(dpkg-deb -f "$lib" Package | sed 's/^libtacse3-protocol/libtacse3_protocol.so./')
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
root="$TMP/root"
libdir="$root/usr/lib/$ma"
dpkg-deb -x "$dev" "$root"
dpkg-deb -x "$lib" "$root"

needs_lib() { readelf -d "$1" | grep -q "(NEEDED).*\[$soname\]"; }
# check_run WHAT BINARY shared|static [runner...]: the link kind by DT_NEEDED, then the run.
check_run() {
  local what="$1" bin="$2" kind="$3" out
  shift 3
  if [ "$kind" = shared ]; then
    needs_lib "$bin" || fail "$what: does not need $soname (readelf -d)"
  else
    if needs_lib "$bin"; then fail "$what: needs $soname, expected the static library"; fi
  fi
  out=$("$@" "$bin" 2>&1) || fail "$what: the consumer failed: $out"
  grep -q '^consumer: node 1 angular 1.234 -0.500 30.000 rad/s; bad CRC refused$' <<<"$out" ||
    fail "$what: unexpected output: $out"
  echo "test-sdk: $arch $what: $out"
}

export PKG_CONFIG_PATH="$libdir/pkgconfig"
pc_cflags=$(pkg-config --cflags tacse3-protocol) || fail "pkg-config cannot read $PKG_CONFIG_PATH/tacse3-protocol.pc"
[[ " $pc_cflags " == *" -std=c++20 "* ]] || fail "tacse3-protocol.pc Cflags lack -std=c++20: $pc_cflags"
read -ra cflags <<<"$pc_cflags"
static_lib="$(pkg-config --variable=libdir tacse3-protocol)/libtacse3_protocol.a"
[ -f "$static_lib" ] || fail "pkg-config's libdir has no libtacse3_protocol.a: $static_lib"

if [ "$arch" = amd64 ]; then
  # CMake: find_package in the extracted tree only, static (default) and shared.
  for kind in static shared; do
    shared=OFF
    [ "$kind" = static ] || shared=ON
    cmake -S "$CONSUMER" -B "$TMP/cmake-$kind" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      "-DCMAKE_PREFIX_PATH=$root/usr" "-Dtacse3_PROTOCOL_SHARED=$shared" >"$TMP/log" 2>&1 ||
      fail "cmake ($kind): $(cat "$TMP/log")"
    grep -qx "tacse3_DIR:PATH=$libdir/cmake/tacse3" "$TMP/cmake-$kind/CMakeCache.txt" ||
      fail "cmake ($kind) found tacse3 elsewhere: $(grep '^tacse3_DIR' "$TMP/cmake-$kind/CMakeCache.txt")"
    cmake --build "$TMP/cmake-$kind" >"$TMP/log" 2>&1 || fail "cmake --build ($kind): $(cat "$TMP/log")"
    check_run "CMake $kind" "$TMP/cmake-$kind/consumer" "$kind" env LD_LIBRARY_PATH="$libdir"
  done
  # pkg-config as an integrator types it: no -std of our own, the shared library by default. The
  # libraries come after the source: Debian's g++ links with --as-needed.
  # shellcheck disable=SC2046 # word splitting of pkg-config's output is intended
  g++ "$CONSUMER/consumer.cpp" $(pkg-config --cflags --libs tacse3-protocol) -o "$TMP/pc-shared" 2>"$TMP/log" ||
    fail "g++ consumer.cpp \$(pkg-config --cflags --libs tacse3-protocol): $(cat "$TMP/log")"
  check_run "pkg-config shared" "$TMP/pc-shared" shared env LD_LIBRARY_PATH="$libdir"
  g++ "${cflags[@]}" "$CONSUMER/consumer.cpp" "$static_lib" -o "$TMP/pc-static" 2>"$TMP/log" ||
    fail "g++ with libtacse3_protocol.a: $(cat "$TMP/log")"
  check_run "pkg-config static" "$TMP/pc-static" static env -u LD_LIBRARY_PATH
  # The controller example as shipped, stand-alone against the package.
  if ! { cmake -S "$root/usr/share/doc/tacse3-dev/examples/controller" -B "$TMP/example" -G Ninja \
    -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=$root/usr" && cmake --build "$TMP/example"; } >"$TMP/log" 2>&1; then
    fail "the packaged controller example: $(cat "$TMP/log")"
  fi
  "$TMP/example/tacse3-controller-example" --log - </dev/null >"$TMP/log" 2>&1 ||
    fail "the packaged controller example does not run: $(cat "$TMP/log")"
  echo "test-sdk: $arch the packaged controller example builds and runs"
else
  case "$arch" in
    arm64) cross=aarch64-linux-gnu qemu="qemu-aarch64-static" ;;
    armhf) cross=arm-linux-gnueabihf qemu="qemu-arm-static" ;;
    *) fail "unknown architecture $arch" ;;
  esac
  command -v "$cross-g++" >/dev/null || fail "$cross-g++ not installed"
  command -v "$qemu" >/dev/null || fail "$qemu not installed (qemu-user-static)"
  # shellcheck disable=SC2046
  "$cross-g++" "$CONSUMER/consumer.cpp" $(pkg-config --cflags --libs tacse3-protocol) -o "$TMP/pc-shared" 2>"$TMP/log" ||
    fail "$cross-g++ \$(pkg-config ...): $(cat "$TMP/log")"
  check_run "cross pkg-config shared" "$TMP/pc-shared" shared "$qemu" -L "/usr/$cross" -E "LD_LIBRARY_PATH=$libdir"
  "$cross-g++" "${cflags[@]}" "$CONSUMER/consumer.cpp" "$static_lib" -o "$TMP/pc-static" 2>"$TMP/log" ||
    fail "$cross-g++ with libtacse3_protocol.a: $(cat "$TMP/log")"
  check_run "cross static" "$TMP/pc-static" static "$qemu" -L "/usr/$cross"
fi
