#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the x86_64 test drivers Debian does not ship (vimc, gpio-sim, v4l2loopback) out of tree.
# Usage: tests/vm/build-oot-modules.sh KERNEL_RELEASE      (e.g. 6.1.0-56-amd64)
# Prints the directory holding the .ko files. Sources, all from Debian packages, unmodified except
# where noted: vimc from linux-source-<x.y>; gpio-sim from linux-source-<x.y> with kernel/irq/irq_sim.c
# bundled into the module (Debian has CONFIG_IRQ_SIM off) and its
# `handle_simple_irq(irq_to_desc(irq))` turned into `generic_handle_irq(irq)` (irq_to_desc is not
# exported); v4l2loopback from v4l2loopback-dkms. They are built against linux-headers-<release>,
# unpacked with dpkg -x (no install); module signing is off, and unsigned modules load.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
vm_lock

KREL="${1:?usage: build-oot-modules.sh KERNEL_RELEASE}"
case "$KREL" in *-amd64) ;; *) vm_die "out-of-tree modules are built for x86_64 only (got $KREL)" ;; esac
KMM=$(echo "$KREL" | cut -d. -f1,2)     # 6.1
OUT="$VM_BUILD/x86_64/$KREL/oot"
KEY=$(vm_hash "$0")
if [ -f "$OUT/.done-$KEY" ]; then echo "$OUT"; exit 0; fi

command -v gcc-12 >/dev/null || vm_die "gcc-12 is needed for linux-headers-$KREL (tests/vm/setup-host.sh)"
vm_apt_setup
vm_log "x86_64: fetching headers, kbuild, linux-source-$KMM, v4l2loopback-dkms"
mapfile -t debs < <(vm_fetch "linux-headers-$KREL:amd64" "linux-headers-${KREL%-amd64}-common" \
  "linux-kbuild-$KMM:amd64" "linux-source-$KMM" v4l2loopback-dkms)
pick() { printf '%s\n' "${debs[@]}" | grep "/$1_" || vm_die "no $1 package fetched"; }

rm -rf "$OUT"; mkdir -p "$OUT/src" "$OUT/hdr"
# Headers: the three packages unpacked into one root. The arch Makefile includes the common one
# by absolute path, so point it into this root.
for p in "linux-headers-$KREL" "linux-headers-${KREL%-amd64}-common" "linux-kbuild-$KMM"; do
  dpkg -x "$(pick "$p")" "$OUT/hdr"
done
KDIR="$OUT/hdr/usr/src/linux-headers-$KREL"
[ -f "$KDIR/Makefile" ] || vm_die "unexpected linux-headers layout: no $KDIR/Makefile"
sed -i "s|^include /usr/src/|include $OUT/hdr/usr/src/|" "$KDIR/Makefile"

# Sources: only the few files needed, straight out of linux-source's tarball.
srcver=$(basename "$(pick "linux-source-$KMM")" | cut -d_ -f2)
kver=$(basename "$(pick "linux-headers-$KREL")" | cut -d_ -f2)
[ "$srcver" = "$kver" ] || vm_log "note: linux-source-$KMM is $srcver, headers are $kver"
S="linux-source-$KMM"
dpkg-deb --fsys-tarfile "$(pick "linux-source-$KMM")" | tar -xO "./usr/src/$S.tar.xz" |
  tar -xJ -C "$OUT/src" "$S/drivers/media/test-drivers/vimc" "$S/drivers/gpio/gpio-sim.c" \
    "$S/drivers/gpio/gpiolib.h" "$S/kernel/irq/irq_sim.c"

mkdir -p "$OUT/build/vimc" "$OUT/build/gpio-sim" "$OUT/build/v4l2loopback"
cp "$OUT/src/$S/drivers/media/test-drivers/vimc/"*.[ch] "$OUT/src/$S/drivers/media/test-drivers/vimc/Makefile" \
  "$OUT/build/vimc/"
cp "$OUT/src/$S/drivers/gpio/gpio-sim.c" "$OUT/build/gpio-sim/gpio-sim-main.c"
cp "$OUT/src/$S/drivers/gpio/gpiolib.h" "$OUT/build/gpio-sim/"
sed 's/handle_simple_irq(irq_to_desc(\([a-z_]*\)));/generic_handle_irq(\1);/' \
  "$OUT/src/$S/kernel/irq/irq_sim.c" >"$OUT/build/gpio-sim/irq_sim.c"
grep -q 'generic_handle_irq(' "$OUT/build/gpio-sim/irq_sim.c" && ! grep -q 'irq_to_desc' "$OUT/build/gpio-sim/irq_sim.c" ||
  vm_die "irq_sim.c changed upstream: the irq_to_desc replacement no longer applies"
printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio-sim-main.o irq_sim.o\n' >"$OUT/build/gpio-sim/Kbuild"
tree=$(vm_extract "$(pick v4l2loopback-dkms)")
cp "$tree"/usr/src/v4l2loopback-*/* "$OUT/build/v4l2loopback/"

jobs=$(nproc)
for m in vimc gpio-sim v4l2loopback; do
  vm_log "x86_64: building $m.ko against linux-headers-$KREL"
  if ! make -C "$KDIR" M="$OUT/build/$m" CONFIG_VIDEO_VIMC=m -j"$jobs" modules >"$OUT/build/$m.log" 2>&1; then
    tail -30 "$OUT/build/$m.log" >&2; vm_die "building $m failed (log: $OUT/build/$m.log)"
  fi
  if grep -q 'WARNING: modpost: .* undefined' "$OUT/build/$m.log"; then
    grep 'WARNING: modpost' "$OUT/build/$m.log" >&2; vm_die "$m has undefined symbols"
  fi
  cp "$OUT/build/$m/$m.ko" "$OUT/"
  strip --strip-debug "$OUT/$m.ko"
done
rm -rf "$OUT/src"
touch "$OUT/.done-$KEY"
echo "$OUT"
