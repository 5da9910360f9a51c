#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: the controller SDK .debs (docs/sdk.md): tacse3-dev (headers, static library, .so link,
# CMake package, pkg-config file, DBC, C++ example) and the runtime libtacse3-protocol<soversion>,
# from a configured build tree; then checks both against tests/packaging/contents-sdk.txt and
# builds and runs the consumers of tests/packaging/sdk against them (tests/packaging/test_sdk.sh;
# for amd64 also tests/packaging/test_sdk_checker.sh, the checker on damaged copies).
#
# Usage: scripts/package-sdk.sh BUILD_DIR ARCH     build, check, test (ARCH: amd64 | arm64 | armhf)
#        scripts/package-sdk.sh --check DEV_DEB LIB_DEB ARCH      check two .debs
#        scripts/package-sdk.sh --expected ARCH     print the expected entries (package kind path)
# BUILD_DIR must be configured with CMAKE_BUILD_TYPE=Release and CMAKE_INSTALL_LIBDIR=lib/<triplet>
# (scripts/package.sh does); the .debs land in BUILD_DIR/deb. Exits non-zero with one line per
# problem when a package does not match.
set -euo pipefail
cd "$(dirname "$0")/.."
SRC="$PWD"
CONTENTS="$SRC/tests/packaging/contents-sdk.txt"
SHLIBS="$SRC/packaging/deb/shlibs.txt"
MAINTAINER="tacse3 developers <tacse3@localhost>"

die() {
  echo "package-sdk: $*" >&2
  exit 1
}

project_version() {
  sed -n 's/^project(tacse3 VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt" | head -n1
}
# The SONAME version, by protocol/CMakeLists.txt's rule: major.minor while major is 0, else major.
soversion() {
  local v
  v=$(project_version)
  case "$v" in 0.*) echo "${v%.*}" ;; *) echo "${v%%.*}" ;; esac
}
lib_package() { echo "libtacse3-protocol$(soversion)"; }
multiarch() {
  case "$1" in
    amd64 | arm64 | armhf) dpkg-architecture -a "$1" -qDEB_HOST_MULTIARCH 2>/dev/null ;;
    *) die "unknown architecture '$1' (amd64 | arm64 | armhf)" ;;
  esac
}

# expected ARCH: "package kind path [target]" per line, placeholders and headers expanded.
expected() {
  local arch="$1" ma so ver pkg kind path arrow target h
  ma=$(multiarch "$arch")
  so=$(soversion)
  ver=$(project_version)
  while read -r pkg kind path arrow target; do
    case "$pkg" in '' | '#'*) continue ;; esac
    path=${path//%M/$ma}; path=${path//%S/$so}; path=${path//%V/$ver}
    target=${target//%S/$so}; target=${target//%V/$ver}
    case "$kind" in
      headers)
        for h in "$SRC"/protocol/include/tacse3/protocol/*.hpp; do
          echo "$pkg file ${path//%/$(basename "$h")}"
        done
        ;;
      link)
        if [ "$arrow" != "->" ] || [ -z "$target" ]; then die "$CONTENTS: link $path needs '-> target'"; fi
        echo "$pkg link $path $target"
        ;;
      file | archive | solib) echo "$pkg $kind $path" ;;
      *) die "$CONTENTS: unknown kind '$kind' for $path" ;;
    esac
  done <"$CONTENTS"
}

# "soname" -> the Depends entry of its package (packaging/deb/shlibs.txt), or nothing.
depends_of() {
  awk -v so="$1" '$1 == so { $1 = ""; sub(/^ +/, ""); print; exit }' "$SHLIBS"
}
# needed_depends SOLIB: the sorted, de-duplicated Depends of its DT_NEEDED; fails on an unmapped one.
needed_depends() {
  local so dep
  for so in $(readelf -d "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    dep=$(depends_of "$so")
    [ -n "$dep" ] || { echo "$(basename "$1") needs $so, which packaging/deb/shlibs.txt does not map to a package" >&2; return 1; }
    echo "$dep"
  done | sort -u
}

elf_re() {
  case "$1" in
    amd64) echo 'ELF 64-bit LSB .*x86-64' ;;
    arm64) echo 'ELF 64-bit LSB .*ARM aarch64' ;;
    armhf) echo 'ELF 32-bit LSB .*ARM, EABI5' ;;
  esac
}
machine_of() {
  case "$1" in amd64) echo 'X86-64' ;; arm64) echo 'AArch64' ;; armhf) echo 'ARM' ;; esac
}

# check_deb DEB PKGKEY ARCH ROOT: contents and per-kind checks of one package; problems on stdout.
check_one() {
  local deb="$1" key="$2" arch="$3" root="$4" tmp="$5" kind path target f desc
  dpkg-deb -c "$deb" | awk '{ t = substr($1, 1, 1); p = $6; sub(/^\./, "", p)
                              if (t == "-") print p; else if (t == "l") print p, $8 }' | sort >"$tmp/$key.have"
  expected "$arch" | awk -v k="$key" '$1 == k { if ($2 == "link") print $3, $4; else print $3 }' |
    sort >"$tmp/$key.want"
  comm -23 "$tmp/$key.want" "$tmp/$key.have" | sed 's/^/missing or different: /'
  comm -13 "$tmp/$key.want" "$tmp/$key.have" | sed 's/^/unexpected: /; s/$/ (not in tests\/packaging\/contents-sdk.txt)/'
  dpkg-deb -c "$deb" | awk '{ t = substr($1, 1, 1) } t != "-" && t != "d" && t != "l" { print "not a file, link or directory: " $6 }'
  while read -r _ kind path; do
    f="$root$path"
    [ -f "$f" ] || continue # reported as missing above
    case "$kind" in
      archive)
        readelf -h "$f" | sed -n 's/^ *Machine: *//p' | sort -u | while read -r m; do
          [[ "$m" == *"$(machine_of "$arch")"* ]] || echo "$path: member machine '$m', expected $(machine_of "$arch")"
        done
        [ -n "$(readelf -h "$f" | sed -n 's/^ *Machine: *//p')" ] || echo "$path: no ELF members"
        ;;
      solib)
        desc=$(file -b "$f")
        [[ "$desc" =~ $(elf_re "$arch") ]] || echo "$path: file says '$desc', expected /$(elf_re "$arch")/"
        [[ "$desc" == *"shared object"* ]] || echo "$path: not a shared object ($desc)"
        [[ "$desc" == *", stripped"* ]] || echo "$path: not stripped"
        [ "$(readelf -d "$f" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')" = "libtacse3_protocol.so.$(soversion)" ] ||
          echo "$path: SONAME '$(readelf -d "$f" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')', expected libtacse3_protocol.so.$(soversion)"
        if readelf -d "$f" | grep -qE '\((RPATH|RUNPATH)\)'; then echo "$path: has an RPATH/RUNPATH"; fi
        # Defined global symbols of the dynamic table, demangled: only the tacse3::protocol API.
        readelf --dyn-syms -W "$f" | awk '$7 != "UND" && ($5 == "GLOBAL" || $5 == "WEAK" || $5 == "UNIQUE") && $8 != "" { print $8 }' |
          sed 's/@.*//' | c++filt >"$tmp/syms"
        [ -s "$tmp/syms" ] || echo "$path: exports no symbols"
        { grep -v '^tacse3::protocol::' "$tmp/syms" || :; } | { grep -vx 'TACSE3_PROTOCOL' || :; } |
          head -n 5 | sed "s|^|$path exports |"
        wc -l <"$tmp/syms" >"$tmp/nsyms"
        ;;
    esac
  done < <(expected "$arch" | awk -v k="$key" '$1 == k')
}

# check DEV_DEB LIB_DEB ARCH: prints every problem, returns 1 if any.
check_debs() {
  local dev="$1" lib="$2" arch="$3" version tmp solib want deps
  [ -f "$dev" ] || die "no such package: $dev"
  [ -f "$lib" ] || die "no such package: $lib"
  version=$(project_version)
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' RETURN
  mkdir -p "$tmp/dev" "$tmp/lib"
  dpkg-deb -x "$dev" "$tmp/dev"
  dpkg-deb -x "$lib" "$tmp/lib"
  {
    field() { # deb field expected
      [ "$(dpkg-deb -f "$1" "$2")" = "$3" ] || echo "$(basename "$1"): $2: '$(dpkg-deb -f "$1" "$2")', expected '$3'"
    }
    [ "$(basename "$dev")" = "tacse3-dev_${version}_${arch}.deb" ] || echo "file name $(basename "$dev"), expected tacse3-dev_${version}_${arch}.deb"
    [ "$(basename "$lib")" = "$(lib_package)_${version}_${arch}.deb" ] || echo "file name $(basename "$lib"), expected $(lib_package)_${version}_${arch}.deb"
    for deb in "$dev" "$lib"; do
      field "$deb" Version "$version"
      field "$deb" Architecture "$arch"
      field "$deb" Multi-Arch same
    done
    field "$dev" Package tacse3-dev
    field "$dev" Depends "$(lib_package) (= $version)"
    field "$lib" Package "$(lib_package)"
    check_one "$dev" dev "$arch" "$tmp/dev" "$tmp" | sed "s|^|$(basename "$dev"): |"
    check_one "$lib" lib "$arch" "$tmp/lib" "$tmp" | sed "s|^|$(basename "$lib"): |"
    # Runtime package: Depends from the library's DT_NEEDED, an shlibs file, the ldconfig trigger.
    solib="$tmp/lib/usr/lib/$(multiarch "$arch")/libtacse3_protocol.so.$version"
    if [ -f "$solib" ]; then
      want=$(needed_depends "$solib" 2>&1 | paste -sd, | sed 's/,/, /g')
      field "$lib" Depends "$want"
    fi
    dpkg-deb -I "$lib" shlibs >"$tmp/shlibs" 2>/dev/null || :
    [ "$(cat "$tmp/shlibs")" = "libtacse3_protocol $(soversion) $(lib_package) (>= $version)" ] ||
      echo "$(basename "$lib"): DEBIAN/shlibs is '$(cat "$tmp/shlibs")'"
    [ "$(dpkg-deb -I "$lib" triggers 2>/dev/null)" = "activate-noawait ldconfig" ] ||
      echo "$(basename "$lib"): DEBIAN/triggers lacks 'activate-noawait ldconfig'"
  } >"$tmp/problems"
  if [ -s "$tmp/problems" ]; then
    sed 's/^/package-sdk: /' "$tmp/problems" >&2
    return 1
  fi
  echo "package-sdk: $(basename "$dev") OK ($(dpkg-deb -c "$dev" | grep -vc '^d') entries, $(du -k "$dev" | cut -f1) KiB)"
  echo "package-sdk: $(basename "$lib") OK ($(cat "$tmp/nsyms") exported symbols, $(du -k "$lib" | cut -f1) KiB; Depends: $(dpkg-deb -f "$lib" Depends))"
}

# control STAGE PACKAGE ARCH SECTION DEPENDS SUMMARY LONG-DESCRIPTION-LINES...
write_control() {
  local stage="$1" pkg="$2" arch="$3" section="$4" depends="$5" summary="$6"
  shift 6
  mkdir -p "$stage/DEBIAN"
  {
    echo "Package: $pkg"
    echo "Version: $(project_version)"
    echo "Architecture: $arch"
    echo "Multi-Arch: same"
    echo "Section: $section"
    echo "Priority: optional"
    echo "Maintainer: $MAINTAINER"
    echo "Installed-Size: $(du -sk --exclude=DEBIAN "$stage" | cut -f1)"
    [ -z "$depends" ] || echo "Depends: $depends"
    echo "Description: $summary"
    printf ' %s\n' "$@"
  } >"$stage/DEBIAN/control"
}

build_debs() {
  local dir="$1" arch="$2" version ma tmp dev lib solib deps
  version=$(project_version)
  ma=$(multiarch "$arch")
  [ -f "$dir/CMakeCache.txt" ] || die "$dir is not a configured build tree"
  grep -qx "CMAKE_INSTALL_LIBDIR:PATH=lib/$ma" "$dir/CMakeCache.txt" ||
    die "$dir: configure with -DCMAKE_INSTALL_LIBDIR=lib/$ma (the multiarch directory)"
  cmake --build "$dir" -j "${TACSE3_JOBS:-$(nproc)}" --target tacse3_protocol tacse3_protocol_shared
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' RETURN
  cmake --install "$dir" --component protocol --prefix "$tmp/dev/usr" >/dev/null
  cmake --install "$dir" --component protocol_runtime --prefix "$tmp/lib/usr" --strip >/dev/null
  local doc="$tmp/dev/usr/share/doc/tacse3-dev"
  mkdir -p "$doc/examples/controller"
  cp "$SRC/docs/sdk.md" "$doc/"
  cp "$SRC"/examples/controller/* "$doc/examples/controller/"
  find "$tmp/dev" "$tmp/lib" -type d -exec chmod 755 {} +
  find "$tmp/dev" "$tmp/lib" -type f -exec chmod 644 {} +

  solib="$tmp/lib/usr/lib/$ma/libtacse3_protocol.so.$version"
  [ -f "$solib" ] || die "cmake --install did not write $solib"
  deps=$(needed_depends "$solib" | paste -sd, | sed 's/,/, /g') || die "unmapped library (see above)"
  write_control "$tmp/lib" "$(lib_package)" "$arch" libs "$deps" \
    "tacse3 gripper CAN protocol library (shared)" \
    "The shared library libtacse3_protocol.so.$(soversion): the tacse3 gripper's CAN" \
    "message encoder and decoder for controllers linked against it (tacse3-dev)."
  echo "libtacse3_protocol $(soversion) $(lib_package) (>= $version)" >"$tmp/lib/DEBIAN/shlibs"
  echo "activate-noawait ldconfig" >"$tmp/lib/DEBIAN/triggers"
  write_control "$tmp/dev" tacse3-dev "$arch" libdevel "$(lib_package) (= $version)" \
    "tacse3 gripper CAN protocol: controller SDK" \
    "What a C++20 controller project needs to talk to the tacse3 gripper: the" \
    "protocol headers, the static and shared library, the CMake package" \
    "(find_package(tacse3 COMPONENTS protocol)), the pkg-config file" \
    "tacse3-protocol.pc, the DBC, and the controller example in" \
    "/usr/share/doc/tacse3-dev/examples."
  chmod 644 "$tmp/lib/DEBIAN/"* "$tmp/dev/DEBIAN/control"
  mkdir -p "$dir/deb"
  dev="$dir/deb/tacse3-dev_${version}_${arch}.deb"
  lib="$dir/deb/$(lib_package)_${version}_${arch}.deb"
  dpkg-deb --root-owner-group -Zxz -b "$tmp/dev" "$dev" >/dev/null
  dpkg-deb --root-owner-group -Zxz -b "$tmp/lib" "$lib" >/dev/null
  check_debs "$dev" "$lib" "$arch"
  "$SRC/tests/packaging/test_sdk.sh" "$dev" "$lib" "$arch"
  # The checker itself, once (its host compiler builds the foreign-symbol library).
  if [ "$arch" = amd64 ]; then "$SRC/tests/packaging/test_sdk_checker.sh" "$dev" "$lib"; fi
}

case "${1:-}" in
  --check)
    [ $# -eq 4 ] || die "usage: $0 --check DEV_DEB LIB_DEB ARCH"
    check_debs "$2" "$3" "$4"
    exit $?
    ;;
  --expected)
    [ $# -eq 2 ] || die "usage: $0 --expected ARCH"
    expected "$2"
    exit 0
    ;;
  -h | --help)
    sed -n '3,14p' "$0"
    exit 0
    ;;
esac
[ $# -eq 2 ] || { echo "usage: $0 BUILD_DIR ARCH | --check DEV_DEB LIB_DEB ARCH | --expected ARCH" >&2; exit 2; }
for tool in cmake dpkg-deb dpkg-architecture file readelf c++filt; do
  command -v "$tool" >/dev/null || die "$tool not found (scripts/setup.sh installs it)"
done
multiarch "$2" >/dev/null
build_debs "$1" "$2"
