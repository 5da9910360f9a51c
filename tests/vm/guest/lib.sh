# SPDX-License-Identifier: Apache-2.0
# Helpers for scenario scripts inside the test VM: `. /tacse3/lib.sh` (busybox sh).
# shellcheck shell=sh
# Environment set by /init for every scenario:
#   TACSE3_ARCH (aarch64|x86_64), TACSE3_KREL, TACSE3_SCENARIO, TACSE3_SCENARIO_DIR (cwd),
#   TACSE3_OUT (directory returned to the host as build/vm/logs/<arch>/<scenario>/),
#   TACSE3_PREFIX=/opt/tacse3 (project binaries; $TACSE3_PREFIX/bin is first in PATH).

# Debian's static busybox runs its own applets before searching PATH ("standalone shell"), so in a
# plain `sh` script `ip` would be busybox's ip even though iproute2's is in /usr/bin. Shell
# functions win over applets: wrap every real program that shares a name with an applet.
_applets=" $(busybox --list | tr '\n' ' ') "
for _f in /opt/tacse3/bin/* /usr/bin/*; do
  _n=${_f##*/}
  case "$_n" in *[!A-Za-z0-9_]*|"") continue ;; esac
  case "$_applets" in *" $_n "*) [ -x "$_f" ] && eval "$_n() { $_f \"\$@\"; }" ;; esac
done
unset _f _n _applets

# uptime_ms: milliseconds since boot (10 ms resolution).
uptime_ms() { awk '{ printf "%d\n", $1 * 1000 }' /proc/uptime; }

log() { echo "[$(uptime_ms) ms] $*"; }

# fail MESSAGE: ends the scenario as failed.
fail() { echo "FAIL: $*"; exit 1; }

# check DESCRIPTION CMD [ARG...]: runs CMD, fails the scenario if it fails.
check() {
  _d=$1; shift
  if "$@"; then echo "ok: $_d"; else _rc=$?; fail "$_d (exit $_rc: $*)"; fi
}

# expect_eq ACTUAL EXPECTED DESCRIPTION
expect_eq() {
  if [ "$1" = "$2" ]; then echo "ok: $3 ($1)"; else fail "$3: got '$1', expected '$2'"; fi
}

# expect_ge ACTUAL MINIMUM DESCRIPTION   (integers)
expect_ge() {
  if [ "$1" -ge "$2" ] 2>/dev/null; then echo "ok: $3 ($1 >= $2)"; else fail "$3: got '$1', expected >= $2"; fi
}

# kv FILE KEY: the value of KEY in a file of "key=value key=value ..." words.
kv() { awk -v k="$2" '{ for (i = 1; i <= NF; i++) if (index($i, k "=") == 1) v = substr($i, length(k) + 2) } END { print v }' "$1"; }

# wait_for PATH SECONDS: waits until PATH exists.
wait_for() {
  _i=0
  while [ ! -e "$1" ]; do
    [ "$_i" -ge $(($2 * 10)) ] && fail "timed out after $2 s waiting for $1"
    sleep 0.1; _i=$((_i + 1))
  done
}

# udev_mark_devices: what udevd would leave behind for libcamera (libudev only reports devices
# it has initialised): /run/udev/data/c<major>:<minor> with "I:<usec>" for every V4L2, media
# and V4L2 sub-device node. Call it after loading the drivers.
udev_mark_devices() {
  mkdir -p /run/udev/data
  for _d in /sys/class/video4linux/* /sys/class/media/* /sys/bus/media/devices/*; do
    [ -r "$_d/dev" ] || continue
    echo "I:1" >"/run/udev/data/c$(cat "$_d/dev")"
  done
}

# vcan_up [NAME]: loads vcan and brings NAME (default vcan0) up.
vcan_up() {
  _n=${1:-vcan0}
  modprobe vcan || fail "modprobe vcan"
  ip link show "$_n" >/dev/null 2>&1 || ip link add dev "$_n" type vcan || fail "ip link add $_n"
  ip link set "$_n" up || fail "ip link set $_n up"
}
