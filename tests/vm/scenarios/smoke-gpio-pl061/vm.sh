# SPDX-License-Identifier: Apache-2.0
# Smoke: the virt machine's built-in PL061 GPIO controller through libgpiod 1.6 tools and debugfs.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 60
set -eu
. /tacse3/lib.sh

gpiodetect | tee "$TACSE3_OUT/gpiodetect.txt"
grep -q '^gpiochip0 \[9030000.pl061\] (8 lines)' "$TACSE3_OUT/gpiodetect.txt" ||
  fail "no PL061 gpiochip0 with 8 lines"
gpioinfo gpiochip0 | tee "$TACSE3_OUT/gpioinfo.txt"
expect_eq "$(grep -c '^[[:space:]]*line ' "$TACSE3_OUT/gpioinfo.txt")" 8 "lines listed by gpioinfo"

base=$(sed -n 's/^gpiochip0: GPIOs \([0-9]*\)-.*/\1/p' /sys/kernel/debug/gpio)
[ -n "$base" ] || { cat /sys/kernel/debug/gpio; fail "no gpiochip0 in /sys/kernel/debug/gpio"; }

for v in 1 0 1; do
  gpioset --mode=signal gpiochip0 0="$v" &
  setter=$!
  sleep 0.5
  cat /sys/kernel/debug/gpio >"$TACSE3_OUT/debugfs-gpio-$v.txt"
  line=$(grep ' gpio-'"$base"' ' /sys/kernel/debug/gpio || true)
  echo "line 0 set to $v: $line"
  gpioinfo gpiochip0 | grep '^[[:space:]]*line   0:' | tee -a "$TACSE3_OUT/gpioinfo-held.txt" |
    grep -q '"gpioset" *output' || fail "gpioinfo does not show line 0 held as output by gpioset"
  want=$([ "$v" = 1 ] && echo hi || echo lo)
  echo "$line" | grep -q "out $want" || fail "debugfs shows '$line' for line 0, expected out $want"
  kill "$setter"; wait "$setter" 2>/dev/null || true
done
echo "ok: PL061 line 0 driven 1/0/1 and read back through debugfs"
