# SPDX-License-Identifier: Apache-2.0
# Smoke: the guest itself: kernel release, busybox intact, every staged program's libraries resolve.
# shellcheck shell=sh
# vm-arch: aarch64 x86_64
# vm-timeout: 60
set -eu
. /tacse3/lib.sh

expect_eq "$(uname -r)" "$TACSE3_KREL" "running kernel release"
[ -f /bin/busybox ] && [ ! -L /bin/busybox ] || fail "/bin/busybox is not the busybox binary"
busybox true || fail "busybox does not run"
expect_eq "$(type ip)" "ip is a function" "lib.sh wraps iproute2's ip over busybox's applet"
ip -V | grep -q iproute2 || fail "ip is not iproute2"
[ -f "/lib/modules/$(uname -r)/modules.dep" ] || fail "no modules.dep"

# glibc's loader lists what each ELF program needs (like ldd) without running it.
n=0; bad=0
for f in /usr/bin/* /usr/lib/*/libcamera/*_ipa_proxy /opt/tacse3/bin/*; do
  [ -f "$f" ] && [ -x "$f" ] || continue
  head -c 4 "$f" | grep -q 'ELF' || continue
  n=$((n + 1))
  out=$(LD_TRACE_LOADED_OBJECTS=1 "$f" 2>&1) || { echo "$f: $out"; bad=$((bad + 1)); continue; }
  if echo "$out" | grep -q 'not found'; then echo "$f:"; echo "$out" | grep 'not found'; bad=$((bad + 1)); fi
done
echo "$n ELF programs checked"
expect_eq "$bad" 0 "programs with unresolved libraries"
for t in candump cansend v4l2-ctl media-ctl gpiodetect gpioset; do
  command -v "$t" >/dev/null || fail "$t missing"
done
v4l2-ctl --version
gpiodetect --version | head -1
