#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3: install everything needed to build, run and test tacse3 on a fresh Debian 12 machine.
# Usage: scripts/setup.sh   (as root, or as a user with sudo)
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
APT_OPTS=(-y -o Acquire::Retries=5 -o DPkg::Lock::Timeout=600)
export DEBIAN_FRONTEND=noninteractive

PACKAGES=(
  # toolchain and build
  build-essential cmake ninja-build pkg-config git file clang clang-format
  # a compiler cache: the arm64 package build reuses the aarch64 test build's objects
  ccache
  # cross builds for the Raspberry Pi targets, run under qemu-user
  g++-aarch64-linux-gnu g++-arm-linux-gnueabihf qemu-user-static
  # libraries
  libeigen3-dev googletest libgtest-dev libbenchmark-dev
  libtomlplusplus-dev libcli11-dev libspng-dev libpng-dev nlohmann-json3-dev
  # the dsp stages' SIMD kernels (Google Highway; docs/performance.md says why)
  libhwy-dev
  # OpenCV's DIS optical flow, for the bench-only comparison tacse3_bench_vs_dis
  libopencv-video-dev
  # hardware backends: MJPEG decode, GPIO, libcamera
  libturbojpeg0-dev libgpiod-dev libcamera-dev
  # tacse3-replay --plot: SVG and PNG figures (host builds only; docs/replay.md)
  libcairo2-dev
  # tacse3d --http and tacse3-replay --view, the web view: the HTTP server (docs/viewer.md says
  # why this one)
  libcpp-httplib-dev
  # its browser tests (tests/viewer): headless Chromium driven by selenium, and headless
  # Firefox driven over Marionette by a Perl module (Debian has no geckodriver)
  chromium chromium-driver python3-selenium firefox-esr libfirefox-marionette-perl
  # the daemon: systemd notify/watchdog; packaging: dpkg-deb and file for the .deb checks,
  # help2man for the manual pages made from each program's --help
  libsystemd-dev dpkg-dev file help2man
  # unit, sysusers and networkd checks of the packaging tests (systemd-analyze verify, security);
  # libseccomp runs the daemon under the unit's system-call filter
  systemd libseccomp-dev
  # fuzzing (libFuzzer and sanitizer runtimes for clang)
  libclang-rt-14-dev
  # the Python package (python/): python-can; its wheel is built offline with Debian's pip,
  # setuptools and wheel. Also the protocol cross-check with the independent DBC decoder (npm).
  python3 python3-can python3-pip python3-setuptools python3-wheel
)
# The real-driver VM suite (tests/vm): qemu-system, kmod, the module build tools. Its guest kernels
# and userland are fetched at test time with apt-get download into build/vm/.
mapfile -t VM_PACKAGES < <(tests/vm/setup-host.sh --print)
PACKAGES+=("${VM_PACKAGES[@]}")

. scripts/lib/apt.sh
apt_update setup
$SUDO apt-get install "${APT_OPTS[@]}" "${PACKAGES[@]}"
# Debian's npm conflicts with a NodeSource nodejs: install it only when no npm is present.
command -v npm >/dev/null || $SUDO apt-get install "${APT_OPTS[@]}" nodejs npm

# Target libraries (libgpiod, turbojpeg, libcamera) for the aarch64 and armhf cross builds,
# unpacked into build/sysroot/<arch> without touching the host's packages.
scripts/make-sysroot.sh aarch64
scripts/make-sysroot.sh armhf

# The independent DBC decoder used by the protocol tests (pinned by package-lock.json).
for dir in tests/protocol/dbc; do
  if [ -f "$dir/package-lock.json" ]; then
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
  fi
done
echo "tacse3 setup: done"
