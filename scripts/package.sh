#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: build the arm64 and armhf .deb packages (cpack) and check each against tests/packaging/;
# with each, the controller SDK packages tacse3-dev and libtacse3-protocol<soversion>
# (scripts/package-sdk.sh), and those also for amd64 from a host Release build.
#
# Usage: scripts/package.sh [aarch64|armhf|amd64 ...] build + check (default: all three; amd64 = the
#                                                     SDK packages only)
#        scripts/package.sh --check DEB ARCH          check one .deb (ARCH: arm64 | armhf)
#        scripts/package.sh --expected ARCH           print the expected file list (kind path)
# Builds in build/package-<preset> (TACSE3_PACKAGE_BUILD_ROOT to change build/), with the tests
# and benchmarks off and only the packaged programs (amd64: the protocol libraries) built; the .debs
# land in build/package-<preset>/deb.
# The target sysroots must exist (scripts/make-sysroot.sh aarch64|armhf, done by scripts/setup.sh).
# Exits non-zero with one line per problem when a package does not match.
set -euo pipefail
cd "$(dirname "$0")/.."
SRC="$PWD"
CONTENTS="$SRC/tests/packaging/contents.txt"
SHLIBS="$SRC/packaging/deb/shlibs.txt"

die() {
  echo "package: $*" >&2
  exit 1
}

project_version() {
  sed -n 's/^project(tacse3 VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt" | head -n1
}

# Expected entries for this source tree, "kind path" per line (boards expanded, conditions applied).
expected() {
  local kind path cond rest board
  while read -r kind path cond rest; do
    case "$kind" in '' | '#'*) continue ;; esac
    if [ -n "$rest" ]; then die "$CONTENTS: unexpected fields after '$cond' for $path"; fi
    if [ -n "$cond" ]; then
      case "$cond" in
        if=*) [ -e "$SRC/${cond#if=}" ] || continue ;;
        *) die "$CONTENTS: unknown condition '$cond' for $path" ;;
      esac
    fi
    case "$kind" in
      elf)
        # Every program comes with its manual page and bash completion.
        echo "elf $path"
        echo "file /usr/share/man/man1/$(basename "$path").1.gz"
        echo "file /usr/share/bash-completion/completions/$(basename "$path")"
        ;;
      file | conffile) echo "$kind $path" ;;
      boards)
        for board in "$SRC"/boards/*/board.toml; do
          [ -e "$board" ] || continue
          board=$(basename "$(dirname "$board")")
          echo "file ${path//%/$board}"
        done
        ;;
      *) die "$CONTENTS: unknown kind '$kind' for $path" ;;
    esac
  done <"$CONTENTS"
}

# "soname package constraint..." -> the Depends entry of one soname, or nothing.
depends_of() {
  awk -v so="$1" '$1 == so { $1 = ""; sub(/^ +/, ""); print; exit }' "$SHLIBS"
}

# check DEB ARCH: prints every problem, returns 1 if any.
check_deb() {
  local deb="$1" arch="$2" version errors=0 tmp
  local -a problems=()
  [ -f "$deb" ] || die "no such package: $deb"
  case "$arch" in
    arm64) file_re='ELF 64-bit LSB .*ARM aarch64' ;;
    armhf) file_re='ELF 32-bit LSB .*ARM, EABI5' ;;
    *) die "unknown architecture '$arch' (arm64 | armhf)" ;;
  esac
  version=$(project_version)
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' RETURN
  bad() { problems+=("$*"); }

  # Control fields.
  [ "$(basename "$deb")" = "tacse3_${version}_${arch}.deb" ] ||
    bad "file name $(basename "$deb"), expected tacse3_${version}_${arch}.deb"
  [ "$(dpkg-deb -f "$deb" Package)" = tacse3 ] || bad "Package: $(dpkg-deb -f "$deb" Package), expected tacse3"
  [ "$(dpkg-deb -f "$deb" Architecture)" = "$arch" ] ||
    bad "Architecture: $(dpkg-deb -f "$deb" Architecture), expected $arch"
  [ "$(dpkg-deb -f "$deb" Version)" = "$version" ] ||
    bad "Version: $(dpkg-deb -f "$deb" Version), expected $version (project version)"

  # Contents: exactly the expected regular files (directories are implied, no links expected).
  expected >"$tmp/expected"
  dpkg-deb -c "$deb" | awk '{ p = $6; sub(/^\./, "", p); t = substr($1, 1, 1); print t, p }' >"$tmp/listing"
  awk '$1 == "-" { print $2 }' "$tmp/listing" | sort >"$tmp/have"
  awk '$1 != "-" && $1 != "d" { print $2 }' "$tmp/listing" | while read -r p; do
    echo "not a regular file or directory: $p"
  done >"$tmp/odd"
  while read -r p; do bad "$p"; done <"$tmp/odd"
  awk '{ print $2 }' "$tmp/expected" | sort >"$tmp/want"
  while read -r p; do bad "missing: $p"; done < <(comm -23 "$tmp/want" "$tmp/have")
  while read -r p; do bad "unexpected file: $p (not in tests/packaging/contents.txt)"; done < <(comm -13 "$tmp/want" "$tmp/have")

  # Conffiles and maintainer scripts.
  mkdir -p "$tmp/root" "$tmp/control"
  dpkg-deb -x "$deb" "$tmp/root"
  dpkg-deb -e "$deb" "$tmp/control"
  awk '$1 == "conffile" { print $2 }' "$tmp/expected" | sort >"$tmp/want-conf"
  if [ -f "$tmp/control/conffiles" ]; then sort "$tmp/control/conffiles" >"$tmp/have-conf"; else : >"$tmp/have-conf"; fi
  while read -r p; do bad "not in conffiles: $p"; done < <(comm -23 "$tmp/want-conf" "$tmp/have-conf")
  while read -r p; do bad "conffiles lists $p, expected only the conffile entries"; done < <(comm -13 "$tmp/want-conf" "$tmp/have-conf")
  for script in postinst prerm postrm; do
    [ -x "$tmp/control/$script" ] || bad "DEBIAN/$script missing or not executable"
  done

  # Binaries: architecture, no build-tree RPATH, stripped, executable; collect DT_NEEDED.
  : >"$tmp/needed"
  while read -r kind p; do
    [ "$kind" = elf ] || continue
    local f="$tmp/root$p" desc
    [ -f "$f" ] || continue # reported as missing above
    desc=$(file -b "$f")
    [[ "$desc" =~ $file_re ]] || bad "$p: file says '$desc', expected /$file_re/"
    [[ "$desc" == *", stripped"* ]] || bad "$p: not stripped"
    if [ "$arch" = armhf ] && ! readelf -h "$f" | grep -q 'hard-float ABI'; then
      bad "$p: not the hard-float ABI (readelf -h)"
    fi
    if readelf -d "$f" | grep -qE '\((RPATH|RUNPATH)\)'; then
      bad "$p: has $(readelf -d "$f" | grep -E '\((RPATH|RUNPATH)\)' | sed 's/.*\[\(.*\)\]/\1/' | head -n1) as RPATH/RUNPATH"
    fi
    [ "$(stat -c %a "$f")" = 755 ] || bad "$p: mode $(stat -c %a "$f"), expected 755"
    readelf -d "$f" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p' | while read -r so; do echo "$p $so"; done >>"$tmp/needed"
  done <"$tmp/expected"

  # Depends: exactly the packages that provide the binaries' libraries (packaging/deb/shlibs.txt).
  : >"$tmp/want-dep"
  while read -r p so; do
    local dep
    dep=$(depends_of "$so")
    if [ -z "$dep" ]; then
      bad "$p needs $so, which packaging/deb/shlibs.txt does not map to a package"
    else
      echo "$dep" >>"$tmp/want-dep"
    fi
  done <"$tmp/needed"
  sort -u "$tmp/want-dep" -o "$tmp/want-dep"
  dpkg-deb -f "$deb" Depends | tr ',' '\n' | sed 's/^ *//; s/ *$//' | sed '/^$/d' | sort -u >"$tmp/have-dep"
  while read -r d; do bad "Depends lacks '$d' (needed by the binaries)"; done < <(comm -23 "$tmp/want-dep" "$tmp/have-dep")
  while read -r d; do bad "Depends has '$d', which no packaged binary needs"; done < <(comm -13 "$tmp/want-dep" "$tmp/have-dep")

  if [ ${#problems[@]} -gt 0 ]; then
    for msg in "${problems[@]}"; do echo "package: $(basename "$deb"): $msg" >&2; done
    errors=1
  else
    echo "package: $(basename "$deb") OK ($(wc -l <"$tmp/have") files; Depends: $(dpkg-deb -f "$deb" Depends))"
  fi
  return "$errors"
}

case "${1:-}" in
  --check)
    [ $# -eq 3 ] || die "usage: $0 --check DEB ARCH"
    check_deb "$2" "$3"
    exit $?
    ;;
  --expected)
    expected
    exit 0
    ;;
  -h | --help)
    sed -n '3,15p' "$0"
    exit 0
    ;;
esac

for tool in cmake cpack dpkg-deb dpkg-architecture file readelf help2man; do
  command -v "$tool" >/dev/null || die "$tool not found (scripts/setup.sh installs it)"
done
JOBS="${TACSE3_JOBS:-$(nproc)}"
ROOT="${TACSE3_PACKAGE_BUILD_ROOT:-$SRC/build}"
presets=("$@")
if [ ${#presets[@]} -eq 0 ]; then presets=(aarch64 armhf amd64); fi

failed=0
for preset in "${presets[@]}"; do
  case "$preset" in
    aarch64) arch=arm64 ;;
    armhf) arch=armhf ;;
    amd64) arch=amd64 ;;
    *) die "unknown preset '$preset' (aarch64 | armhf | amd64)" ;;
  esac
  dir="$ROOT/package-$preset"
  # The SDK's libraries go to the multiarch directory, so the packages of several architectures
  # install side by side (Multi-Arch: same).
  libdir="lib/$(dpkg-architecture -a "$arch" -qDEB_HOST_MULTIARCH 2>/dev/null)"
  if [ "$preset" = amd64 ]; then
    echo "=== [amd64] configure a host Release build (tests and benchmarks off) ==="
    cmake -S "$SRC" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTACSE3_WERROR=ON \
      -DTACSE3_BUILD_TESTS=OFF -DTACSE3_BUILD_BENCH=OFF "-DCMAKE_INSTALL_LIBDIR=$libdir" \
      >"$dir.configure.log" 2>&1 || { cat "$dir.configure.log" >&2; die "[amd64] configure failed"; }
    echo "=== [amd64] SDK packages ==="
    rm -rf "$dir/deb"
    "$SRC/scripts/package-sdk.sh" "$dir" amd64 || failed=1
    continue
  fi
  [ -d "$SRC/build/sysroot/$preset" ] ||
    die "no target sysroot build/sysroot/$preset: run scripts/make-sysroot.sh $preset"
  echo "=== [$preset] configure (tests and benchmarks off) ==="
  cmake --preset "$preset" -B "$dir" -DTACSE3_BUILD_TESTS=OFF -DTACSE3_BUILD_BENCH=OFF \
    "-DCMAKE_INSTALL_LIBDIR=$libdir" >"$dir.configure.log" 2>&1 ||
    { cat "$dir.configure.log" >&2; die "[$preset] configure failed"; }
  echo "=== [$preset] build the packaged programs ==="
  cmake --build "$dir" -j "$JOBS" --target tacse3_package_programs
  echo "=== [$preset] cpack ==="
  rm -rf "$dir/deb"
  (cd "$dir" && cpack --config CPackConfig.cmake) >"$dir.cpack.log" 2>&1 ||
    { cat "$dir.cpack.log" >&2; die "[$preset] cpack failed"; }
  deb="$dir/deb/tacse3_$(project_version)_$arch.deb"
  if [ ! -f "$deb" ]; then
    ls "$dir/deb" >&2 || true
    die "[$preset] cpack did not write $deb"
  fi
  check_deb "$deb" "$arch" || failed=1
  echo "=== [$preset] SDK packages ==="
  "$SRC/scripts/package-sdk.sh" "$dir" "$arch" || failed=1
done
if [ "$failed" != 0 ]; then die "package check failed (see the lines above)"; fi
echo "package: all packages OK"
