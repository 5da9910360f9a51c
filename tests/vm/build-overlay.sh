#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the per-run initramfs overlay: guest /init, scenarios, project binaries and their libs.
# Usage: tests/vm/build-overlay.sh ARCH OUT.cpio BASE_MANIFEST [--bin PATH]... SCENARIO...
#   --bin PATH  a file goes to /opt/tacse3/bin/<name>; a directory's contents are merged into
#               /opt/tacse3/ (so DIR/bin/tacse3d -> /opt/tacse3/bin/tacse3d, DIR/etc/... too).
#               Shared libraries of every ELF file in there are resolved against the same Debian
#               packages as the base (arch-matched) and added; a missing one is an error naming it.
#   SCENARIO    a directory tests/vm/scenarios/<name>/ with vm.sh; it lands in /tacse3/scenarios/.
# The kernel unpacks this archive over the base one (concatenated cpio archives).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
vm_lock

ARCH="${1:?usage}"; OUTCPIO="${2:?usage}"; MANIFEST="${3:?usage}"; shift 3
vm_arch_vars "$ARCH"
bins=(); scen=()
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bins+=("$2"); shift 2 ;;
    *) scen+=("$1"); shift ;;
  esac
done

ROOT="$VM_BUILD/$ARCH/overlay"
rm -rf "$ROOT"; mkdir -p "$ROOT/tacse3/scenarios" "$ROOT/etc/tacse3-vm" "$ROOT/opt/tacse3/bin"
install -m 755 "$VM_DIR/guest/init" "$ROOT/init"
install -m 644 "$VM_DIR/guest/lib.sh" "$ROOT/tacse3/lib.sh"
KREL=$(basename "$(dirname "$MANIFEST")")     # .../<arch>/<release>/base-<key>.manifest
printf 'TACSE3_ARCH=%s\nTACSE3_KREL=%s\n' "$ARCH" "$KREL" >"$ROOT/etc/tacse3-vm/run.conf"
: >"$ROOT/etc/tacse3-vm/scenarios"
for s in "${scen[@]}"; do
  name=$(basename "$s")
  [ -f "$s/vm.sh" ] || vm_die "scenario $name has no vm.sh"
  cp -a "$s" "$ROOT/tacse3/scenarios/$name"
  t=$(sed -n 's/^# vm-timeout: *\([0-9][0-9]*\).*/\1/p' "$s/vm.sh" | head -1)
  echo "$name ${t:-120}" >>"$ROOT/etc/tacse3-vm/scenarios"
done

for b in "${bins[@]}"; do
  if [ -d "$b" ]; then cp -a "$b/." "$ROOT/opt/tacse3/"
  elif [ -f "$b" ]; then cp -a "$b" "$ROOT/opt/tacse3/bin/"
  else vm_die "--bin $b: no such file or directory"; fi
done
mapfile -t elfs < <(find "$ROOT/opt/tacse3" -type f -exec sh -c \
  'head -c4 "$1" | grep -q "^.ELF" && echo "$1"' _ {} \;)
if [ ${#elfs[@]} -gt 0 ]; then
  want=$([ "$ARCH" = aarch64 ] && echo AArch64 || echo X86-64)
  for e in "${elfs[@]}"; do
    readelf -h "$e" | grep -q "Machine:.*$want" ||
      vm_die "${e#"$ROOT"} is not an $ARCH binary ($(readelf -h "$e" | sed -n 's/ *Machine: *//p'))"
  done
  vm_apt_setup
  python3 "$VM_DIR/lib/userland.py" --arch "$DEB_ARCH" --triplet "$TRIPLET" --spec /dev/null \
    --debs "$VM_BUILD/debs" --xdir "$VM_BUILD/x" --out "$ROOT" \
    --manifest "$VM_BUILD/$ARCH/overlay.manifest" --have "$MANIFEST" --elf "${elfs[@]}"
fi
python3 "$VM_DIR/lib/mkcpio.py" "$ROOT" "$OUTCPIO"
