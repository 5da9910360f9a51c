#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the host packages the VM test suite (tests/vm/run.sh) needs on Debian 12.
# Usage: tests/vm/setup-host.sh   (root or sudo; called from scripts/setup.sh)
# The guest kernels, modules, busybox and tools are NOT installed here: run.sh downloads them at
# test time into build/vm/ with apt-get download + dpkg -x, using its own apt state.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
PACKAGES=(
  qemu-system-arm      # qemu-system-aarch64 (virt machine, cortex-a72, TCG)
  qemu-system-x86      # qemu-system-x86_64 (pc machine, isa-debug-exit, TCG)
  kmod                 # depmod -b / modprobe -d --show-depends on the guest module trees
  python3              # tests/vm/lib/userland.py (library closure), mkcpio.py (initramfs)
  binutils             # readelf (ELF NEEDED/interpreter), strip (out-of-tree modules)
  xz-utils tar         # linux-source-<x.y>.tar.xz
  gcc-12 make          # out-of-tree vimc, gpio-sim, v4l2loopback against linux-headers (dpkg -x)
  apt dpkg coreutils   # apt-get download, dpkg -x, timeout
)
if [ "${1:-}" = --print ]; then printf '%s\n' "${PACKAGES[@]}"; exit 0; fi
. "$(dirname "$0")/../../scripts/lib/apt.sh"
apt_update tests/vm/setup-host.sh
$SUDO apt-get install -y --no-install-recommends -o Acquire::Retries=5 -o DPkg::Lock::Timeout=600 \
  "${PACKAGES[@]}"
echo "tests/vm/setup-host.sh: done"
