#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: unpack the target's libraries (gpiod, turbojpeg, libcamera, spng, systemd, hwy) into build/sysroot/<arch>.
#
# Usage: scripts/make-sysroot.sh <aarch64|arm64|armhf> [--no-libcamera]
#
# The cross presets compile against Debian's cross toolchain (/usr/<triple>), which has libc and
# libstdc++ but not the HAL libraries. Installing them with multiarch (apt-get install pkg:arm64)
# upgrades host packages in lockstep and breaks on partial mirrors, so this script only downloads
# the target .debs (apt-get download) and unpacks them with dpkg -x into a private sysroot.
# cmake/Tacse3TargetDeps.cmake looks there through TACSE3_TARGET_SYSROOT (default:
# build/sysroot/<arch>). The new sysroot is assembled next to the old one and swapped in at the
# end, so a build reading it at the same time never sees a half-unpacked tree.
# Needs root (or sudo) once, for dpkg --add-architecture and apt-get update.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
  echo "usage: $0 <aarch64|arm64|armhf> [--no-libcamera]" >&2
  exit 2
}
[ $# -ge 1 ] || usage
case "$1" in
  aarch64 | arm64) DEB_ARCH=arm64 TRIPLE=aarch64-linux-gnu DIR_NAME=aarch64 ;;
  armhf | arm | armv7l) DEB_ARCH=armhf TRIPLE=arm-linux-gnueabihf DIR_NAME=armhf ;;
  *) usage ;;
esac
WITH_LIBCAMERA=1
if [ "${2:-}" = "--no-libcamera" ]; then WITH_LIBCAMERA=0; elif [ $# -ge 2 ]; then usage; fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
SYSROOT="$PWD/build/sysroot/$DIR_NAME"
DEBS="$PWD/build/sysroot/.debs-$DIR_NAME"

# Top-level packages; their runtime dependencies are added below.
TOP=(libgpiod-dev libgpiod2 libturbojpeg0-dev libturbojpeg0)  # libgpiod2 ships libgpiodcxx.so.1
# Recording format (recording/, the replay/calibrate tools, tacse3d --record).
TOP+=(libspng-dev libspng0)
# The daemon's live view (tacse3d --http): cpp-httplib, a shared library in Debian.
TOP+=(libcpp-httplib-dev libcpp-httplib0.11)
# The daemon's sd_notify (READY=1, WATCHDOG=1).
TOP+=(libsystemd-dev libsystemd0)
# The dsp SIMD kernels: Google Highway's headers (Arm builds dispatch at compile time).
TOP+=(libhwy-dev)
if [ "$WITH_LIBCAMERA" = 1 ]; then TOP+=(libcamera-dev libcamera0.0.3); fi
# Provided by the cross toolchain (g++-<triple>): never mix a second copy into the sysroot, and
# never follow their dependencies (libspng-dev -> zlib1g-dev -> libc6-dev would otherwise drag in
# libcrypt-dev, libtirpc-dev, libssl3, krb5... next to the toolchain's libc).
SKIP_RE='^(libc6|libc6-dev|libgcc-s1|libstdc\+\+6|gcc-12-base|linux-libc-dev|libcrypt1)$'

if ! dpkg --print-foreign-architectures | grep -qx "$DEB_ARCH"; then
  echo "make-sysroot: adding dpkg architecture $DEB_ARCH (package lists only; nothing is installed)"
  $SUDO dpkg --add-architecture "$DEB_ARCH"
fi
# A mirror mid-sync can fail one index (e.g. the security suite); the main suite is enough here.
if ! apt-cache show "libgpiod-dev:$DEB_ARCH" >/dev/null 2>&1 || [ "${TACSE3_SYSROOT_UPDATE:-0}" = 1 ]; then
  $SUDO apt-get update -o Acquire::Retries=5 || echo "make-sysroot: apt-get update reported errors; continuing with the lists it got" >&2
fi

# apt here may keep no binary cache (docker-style images): give it one for this run, else every
# apt-cache call re-parses all package lists.
mkdir -p "$DEBS"
APTC=(-o "Dir::Cache::pkgcache=$DEBS/.pkgcache.bin" -o "Dir::Cache::srcpkgcache=$DEBS/.srcpkgcache.bin")
rm -f "$DEBS/.pkgcache.bin" "$DEBS/.srcpkgcache.bin"

# Dependency closure, one apt-cache call per level; skipped packages are not expanded.
declare -A seen=()
ALL=()
frontier=()
for p in "${TOP[@]}"; do seen[$p]=1; frontier+=("$p"); done
while [ ${#frontier[@]} -gt 0 ]; do
  ALL+=("${frontier[@]}")
  qualified=()
  for p in "${frontier[@]}"; do
    if [[ ! "$p" =~ $SKIP_RE ]]; then qualified+=("$p:$DEB_ARCH"); fi
  done
  frontier=()
  [ ${#qualified[@]} -gt 0 ] || break
  while read -r dep; do
    if [ -z "${seen[$dep]:-}" ]; then seen[$dep]=1; frontier+=("$dep"); fi
  done < <(apt-cache "${APTC[@]}" depends --no-recommends --no-suggests --no-conflicts --no-breaks \
    --no-replaces --no-enhances "${qualified[@]}" 2>/dev/null |
    sed -n 's/^ *|\{0,1\}\(Pre\)\{0,1\}Depends: \([^<][^ :]*\).*$/\2/p' | sort -u)
done
if [ ${#ALL[@]} -eq 0 ]; then
  echo "make-sysroot: apt-cache knows none of ${TOP[*]} for $DEB_ARCH; run apt-get update" >&2
  exit 1
fi

# Architecture-independent packages carry no target libraries; the toolchain's own are skipped.
cands=()
for p in "${ALL[@]}"; do
  if [[ ! "$p" =~ $SKIP_RE ]]; then cands+=("$p:$DEB_ARCH"); fi
done
# "package version" lines of the target-architecture packages.
mapfile -t PKGVERS < <(apt-cache "${APTC[@]}" show --no-all-versions "${cands[@]}" 2>/dev/null |
  awk '/^Package: /{p=$2} /^Version: /{v=$2} /^Architecture: /{a=$2}
       /^$/{if (p != "" && a != "all") print p, v; p=""; v=""; a=""}
       END{if (p != "" && a != "all") print p, v}' | sort -u)
deb_of() { # package version -> cached .deb path (apt-get download escapes ':' as %3a)
  echo "$DEBS/${1}_${2//:/%3a}_${DEB_ARCH}.deb"
}

# Always rebuilt from the cached .debs (no stale files, no merged-dir surprises), in a staging
# directory that replaces the live one only once it is complete.
FINAL="$SYSROOT"
SYSROOT="$FINAL.new"
rm -rf "${SYSROOT:?}"
mkdir -p "$SYSROOT"
# Download only what the cache lacks (the cache keeps the exact versions this sysroot holds).
dl=()
for pv in "${PKGVERS[@]}"; do
  read -r p v <<<"$pv"
  if [ ! -f "$(deb_of "$p" "$v")" ]; then dl+=("$p:$DEB_ARCH=$v"); fi
done
echo "make-sysroot: ${#PKGVERS[@]} $DEB_ARCH packages, ${#dl[@]} to download into $DEBS"
if [ ${#dl[@]} -gt 0 ]; then
  # As root, apt's sandbox user cannot write here; download as root instead of warning about it.
  sandbox=()
  if [ "$(id -u)" -eq 0 ]; then sandbox=(-o APT::Sandbox::User=root); fi
  (cd "$DEBS" && apt-get "${APTC[@]}" download -o Acquire::Retries=5 "${sandbox[@]}" "${dl[@]}")
fi

echo "make-sysroot: unpacking into $SYSROOT"
: >"$SYSROOT/.tacse3-sysroot.tmp"
for pv in "${PKGVERS[@]}"; do
  read -r p v <<<"$pv"
  deb=$(deb_of "$p" "$v")
  dpkg -x "$deb" "$SYSROOT"
  echo "$p $v" >>"$SYSROOT/.tacse3-sysroot.tmp"
done
rm -f "$DEBS/.pkgcache.bin" "$DEBS/.srcpkgcache.bin"

# Merge /lib into /usr/lib as on a merged-/usr Debian system, so every library sits in the one
# directory the build-tree RPATH names (libcamera's dependency chain reaches zlib in /lib).
if [ -d "$SYSROOT/lib" ] && [ ! -L "$SYSROOT/lib" ]; then
  mkdir -p "$SYSROOT/usr/lib"
  cp -a "$SYSROOT/lib/." "$SYSROOT/usr/lib/"
  rm -rf "${SYSROOT:?}/lib"
  ln -s usr/lib "$SYSROOT/lib"
fi

# Absolute symlinks (e.g. libfoo.so -> /lib/<triple>/libfoo.so.1) would point at the host; make
# them relative to the sysroot.
while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  case "$target" in
    /*) ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$SYSROOT$target")" "$link" ;;
  esac
done < <(find "$SYSROOT" -type l -print0)

{
  echo "# tacse3 target sysroot for $DEB_ARCH ($TRIPLE), made by scripts/make-sysroot.sh"
  sort "$SYSROOT/.tacse3-sysroot.tmp"
} >"$SYSROOT/.tacse3-sysroot"
rm -f "$SYSROOT/.tacse3-sysroot.tmp"
missing=0
for lib in libgpiodcxx.so libturbojpeg.so libspng.so libsystemd.so libcpp-httplib.so libcamera.so; do
  if [ -e "$SYSROOT/usr/lib/$TRIPLE/$lib" ]; then
    echo "  found $lib"
  elif [ "$lib" != libcamera.so ] || [ "$WITH_LIBCAMERA" = 1 ]; then
    echo "make-sysroot: $lib missing from $SYSROOT/usr/lib/$TRIPLE" >&2
    missing=1
  fi
done
if [ ! -e "$SYSROOT/usr/include/hwy/highway.h" ]; then
  echo "make-sysroot: hwy/highway.h (libhwy-dev) missing from $SYSROOT/usr/include" >&2
  missing=1
fi
if [ "$missing" = 1 ]; then
  echo "make-sysroot: incomplete sysroot left in $SYSROOT; $FINAL is unchanged" >&2
  exit 1
fi

# Swap with two renames: a concurrent build sees the old tree or the new one (or, for the instant
# between the renames, none), never a half-unpacked one.
if [ -e "$FINAL" ]; then
  rm -rf "${FINAL:?}.old"
  mv "$FINAL" "$FINAL.old"
fi
mv "$SYSROOT" "$FINAL"
rm -rf "${FINAL:?}.old"
echo "make-sysroot: done. Configure with -DTACSE3_TARGET_SYSROOT=$FINAL (the default for this arch)."
