#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fetches the current Debian kernel + modules for a VM architecture (apt-get download + dpkg -x).
# Usage: tests/vm/build-kernel.sh aarch64|x86_64
# Prints the kernel directory $VM_BUILD/<arch>/<release>/kernel (vmlinuz, config, release, and
# modules/ = an unpacked lib/modules/<release> tree, depmod'ed; on x86_64 with the out-of-tree
# vimc, gpio-sim and v4l2loopback in extra/). /boot and the host's packages are never touched.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
vm_lock

ARCH="${1:?usage: build-kernel.sh aarch64|x86_64}"
vm_arch_vars "$ARCH"
vm_apt_setup
KREL=$(vm_kernel_release "$ARCH")
OUT="$VM_BUILD/$ARCH/$KREL/kernel"

if [ ! -f "$OUT/.done" ]; then
  vm_log "$ARCH: fetching linux-image-$KREL ($DEB_ARCH)"
  deb=$(vm_fetch "linux-image-$KREL:$DEB_ARCH")
  tree=$(vm_extract "$deb")
  [ -f "$tree/boot/vmlinuz-$KREL" ] || vm_die "no boot/vmlinuz-$KREL in $deb"
  rm -rf "$OUT"; mkdir -p "$OUT"
  cp "$tree/boot/vmlinuz-$KREL" "$OUT/vmlinuz"
  cp "$tree/boot/config-$KREL" "$OUT/config"
  if [ "$ARCH" = x86_64 ]; then
    # Decompressing the xz bzImage is slow under TCG. The kernel has CONFIG_PVH, so qemu can
    # start the uncompressed ELF vmlinux directly (PVH entry): unpack it once here.
    python3 - "$OUT/vmlinuz" "$OUT/vmlinux" <<'PY'
import lzma, sys
data = open(sys.argv[1], "rb").read()
at = data.find(b"\xfd7zXZ\x00")
if at >= 0:
    out = lzma.LZMADecompressor().decompress(data[at:])
    if out[:4] == b"\x7fELF":
        open(sys.argv[2], "wb").write(out)
PY
    if [ -f "$OUT/vmlinux" ] && readelf -n "$OUT/vmlinux" | grep -q 'Xen.*0x00000012'; then :
    else rm -f "$OUT/vmlinux"; vm_log "no PVH vmlinux could be unpacked: booting the bzImage (slower)"; fi
  fi
  echo "$KREL" >"$OUT/release"
  basename "$deb" >"$OUT/package"
  # Hard-linked copy of the module tree, so depmod output and extra modules stay out of the cache.
  mkdir -p "$OUT/root/lib/modules"
  cp -al "$tree/lib/modules/$KREL" "$OUT/root/lib/modules/$KREL"
  touch "$OUT/.done"
fi

MODDIR="$OUT/root/lib/modules/$KREL"
if [ "$ARCH" = x86_64 ]; then
  oot=$("$VM_DIR/build-oot-modules.sh" "$KREL")
  mkdir -p "$MODDIR/extra"
  for ko in "$oot"/*.ko; do
    cmp -s "$ko" "$MODDIR/extra/$(basename "$ko")" || cp "$ko" "$MODDIR/extra/"
  done
fi
if [ ! -f "$MODDIR/modules.dep" ] || [ -n "$(find "$MODDIR/extra" -newer "$MODDIR/modules.dep" -name '*.ko' 2>/dev/null)" ]; then
  depmod -b "$OUT/root" "$KREL"
fi
echo "$OUT"
