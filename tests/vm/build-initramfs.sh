#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the cached base initramfs of a VM: static busybox, kernel modules, Debian userland + libs.
# Usage: tests/vm/build-initramfs.sh aarch64|x86_64
# Prints the path of base-<key>.cpio (uncompressed newc: unpacking is faster than decompressing
# under TCG); base-<key>.manifest next to it lists the userland files and their packages.
# Cached under $VM_BUILD/<arch>/<kernel release>/, keyed by the inputs' content. The guest's
# /init, the scenarios and the project's binaries are not in it: build-overlay.sh adds them as a
# second archive appended to this one, so changing a scenario does not rebuild this.
# Env: TACSE3_VM_EXTRA_PACKAGES  more Debian packages whose shared libraries go in (e.g. libfoo1)
#      TACSE3_VM_EXTRA_MODULES   more kernel modules (with their dependencies)
#      TACSE3_VM_DROP_MODULES    modules to leave out on purpose (e.g. "vcan"), to see a driver
#                                path fail; never set in CI
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
vm_lock

ARCH="${1:?usage: build-initramfs.sh aarch64|x86_64}"
vm_arch_vars "$ARCH"
KDIR=$("$VM_DIR/build-kernel.sh" "$ARCH")
KREL=$(cat "$KDIR/release")
MODROOT="$KDIR/root"

# Modules loadable in the guest (each with its dependencies, from modprobe --show-depends).
MODULES=(can can-raw can-bcm can-gw can-dev vcan vxcan vivid configfs virtio_pci virtio_blk)
case "$ARCH" in
  aarch64) MODULES+=(virtio_mmio) ;;                         # PL061 GPIO is built in
  x86_64)  MODULES+=(vimc gpio-sim v4l2loopback) ;;          # built by build-oot-modules.sh
esac
read -r -a extra_mods <<<"${TACSE3_VM_EXTRA_MODULES:-}"
MODULES+=("${extra_mods[@]}")
read -r -a extra_pkgs <<<"${TACSE3_VM_EXTRA_PACKAGES:-}"
read -r -a drop_mods <<<"${TACSE3_VM_DROP_MODULES:-}"

KEY=$( { cat "$0" "$VM_DIR/userland.spec" "$VM_DIR/lib/userland.py" "$VM_DIR/lib/mkcpio.py"
         echo "${MODULES[*]} | ${extra_pkgs[*]} | ${drop_mods[*]}"
         cat "$KDIR/package"; sha256sum "$MODROOT/lib/modules/$KREL/extra/"*.ko 2>/dev/null || true
       } | sha256sum | cut -c1-16)
D="$VM_BUILD/$ARCH/$KREL"
CPIO="$D/base-$KEY.cpio"
if [ -f "$CPIO" ] && [ -f "${CPIO%.cpio}.manifest" ]; then echo "$CPIO"; exit 0; fi

vm_apt_setup
ROOT="$D/rootfs"
rm -rf "$ROOT"; mkdir -p "$ROOT"
vm_log "$ARCH: staging base initramfs for $KREL in $ROOT"

# 1. busybox (static) in /bin with one symlink per applet. `busybox --list` names busybox itself:
#    a link busybox -> busybox would replace the binary with a symlink loop (init fails, -40).
#    The applet list comes from the amd64 build of the same package (runnable here; same config).
bb_t=$(vm_extract "$(vm_fetch "busybox-static:$DEB_ARCH")")
bb_host=$bb_t
[ "$DEB_ARCH" = amd64 ] || bb_host=$(vm_extract "$(vm_fetch busybox-static:amd64)")
mkdir -p "$ROOT/bin"
cp "$bb_t/bin/busybox" "$ROOT/bin/busybox"
"$bb_host/bin/busybox" --list | while read -r applet; do
  case "$applet" in busybox|""|*/*) continue ;; esac
  ln -s busybox "$ROOT/bin/$applet"
done

# 2. Merged-/usr layout: real tools in /usr/bin, busybox applets in /bin (PATH puts /usr/bin
#    first), so copying a tool never writes through an applet symlink into busybox.
mkdir -p "$ROOT"/{usr/bin,usr/lib,dev,proc,sys,run,tmp,out,etc,opt,mnt,root,var}
ln -s bin "$ROOT/sbin"
ln -s bin "$ROOT/usr/sbin"
ln -s usr/lib "$ROOT/lib"
if [ "$ARCH" = x86_64 ]; then mkdir -p "$ROOT/usr/lib64"; ln -s usr/lib64 "$ROOT/lib64"; fi
ln -s ../run "$ROOT/var/run"
printf 'root:x:0:0:root:/root:/bin/sh\n' >"$ROOT/etc/passwd"
printf 'root:x:0:\nvideo:x:44:\nplugdev:x:46:\ngpio:x:997:\n' >"$ROOT/etc/group"
echo tacse3-vm >"$ROOT/etc/hostname"

# 3. Kernel modules and their dependencies, then depmod for the guest's modprobe.
MD="$ROOT/usr/lib/modules/$KREL"
mkdir -p "$MD"
for m in "${MODULES[@]}"; do
  deps=$(modprobe -d "$MODROOT" -S "$KREL" --show-depends "$m" 2>&1) ||
    vm_die "module $m: $deps"
  while read -r verb path _; do
    case "$verb" in
      insmod) rel=${path#"$MODROOT/lib/modules/$KREL/"}
              mkdir -p "$MD/$(dirname "$rel")"; cp "$path" "$MD/$rel" ;;
      builtin) ;;
      *) vm_die "module $m: unexpected modprobe output: $verb $path" ;;
    esac
  done <<<"$deps"
done
for m in "${drop_mods[@]}"; do
  vm_log "$ARCH: leaving out module $m on purpose (TACSE3_VM_DROP_MODULES)"
  find "$MD" -name "$m.ko" -delete
done
cp "$MODROOT/lib/modules/$KREL"/modules.{builtin,builtin.modinfo,order} "$MD/"
depmod -b "$ROOT" "$KREL"

# 4. Userland from Debian packages (tools + shared-library closure).
python3 "$VM_DIR/lib/userland.py" --arch "$DEB_ARCH" --triplet "$TRIPLET" \
  --spec "$VM_DIR/userland.spec" --debs "$VM_BUILD/debs" --xdir "$VM_BUILD/x" \
  --out "$ROOT" --manifest "${CPIO%.cpio}.manifest" --extra "${extra_pkgs[@]}"

# 5. Sanity: busybox is still the binary, not a link or another tool.
[ ! -L "$ROOT/bin/busybox" ] && cmp -s "$bb_t/bin/busybox" "$ROOT/bin/busybox" ||
  vm_die "bin/busybox was overwritten while staging"

# Keep the three most recent variants (e.g. with TACSE3_VM_DROP_MODULES set) besides this one.
{ ls -t "$D"/base-*.cpio 2>/dev/null || true; } | tail -n +4 |
  while read -r old; do rm -f "$old" "${old%.cpio}.manifest"; done
python3 "$VM_DIR/lib/mkcpio.py" "$ROOT" "$CPIO.tmp" --dev dev/console:c:5:1 --dev dev/null:c:1:3
mv "$CPIO.tmp" "$CPIO"
vm_log "$ARCH: base initramfs $(du -h "$CPIO" | cut -f1) ($(wc -l <"${CPIO%.cpio}.manifest") userland files, $(find "$MD" -name '*.ko' | wc -l) modules)"
echo "$CPIO"
