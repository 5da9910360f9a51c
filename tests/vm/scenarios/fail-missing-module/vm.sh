# SPDX-License-Identifier: Apache-2.0
# Deliberately failing: expects gpio-mockup, which Debian does not build. Shows that a failing
# shellcheck shell=sh
# driver check fails the suite: `tests/vm/run.sh x86_64 fail-missing-module` exits 1.
# vm-arch: aarch64 x86_64
# vm-timeout: 30
# vm-default: no
set -eu
. /tacse3/lib.sh
check "modprobe gpio-mockup" modprobe gpio-mockup gpio_mockup_ranges=-1,8
gpiodetect | grep -q gpio-mockup || fail "no gpio-mockup chip"
