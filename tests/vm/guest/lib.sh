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

# ---- helpers for the project's scenarios (tacse3d against real drivers) ----

# skip MESSAGE: ends the scenario as skipped (rc 77): what it needs is not in the guest. run.sh
# reports SKIP, and fails the suite for it when TACSE3_VM_REQUIRE_ALL=1.
skip() { echo "SKIP: $*"; exit 77; }

# need_daemon: skips the rest of the scenario when the project's tacse3d was not put into the guest
# (run.sh --bin ARCH=.../tacse3d). Everything before the call (driver bring-up) has run and passed.
need_daemon() {
  command -v tacse3d >/dev/null 2>&1 || skip "tacse3d is not in the guest (run.sh --bin $TACSE3_ARCH=<build>/firmware/tacse3d)"
}

# vivid_hdmi_320x240 DEV: selects vivid's HDMI input with 640x480@120 CVT-RB DV timings and sets the
# scaled capture format to 320x240 YUYV (the webcam input offers no 320x240). 119.1 Hz nominal.
vivid_hdmi_320x240() {
  _v=$(basename "$1")
  wait_for "$1" 5
  v4l2-ctl -d "$1" --info | grep -q 'Driver name *: vivid' || fail "$1 is not vivid"
  check "$_v: HDMI input" v4l2-ctl -d "$1" --set-input 3
  # Timings cannot change while a process (a daemon killed at the end of the previous scenario and
  # still exiting under TCG) streams from the node: retry for a few seconds on EBUSY.
  _i=0
  until v4l2-ctl -d "$1" --set-dv-bt-timings cvt,width=640,height=480,fps=120,reduced-blanking=1 \
        >/tmp/dv.txt 2>&1; do
    grep -q 'busy' /tmp/dv.txt && [ $_i -lt 30 ] || fail "$_v: DV timings 640x480@120: $(cat /tmp/dv.txt)"
    sleep 0.2; _i=$((_i + 1))
  done
  echo "ok: $_v: DV timings 640x480@120"
  # No text overlay: vivid draws its frame counter and time into every frame, which the pipeline
  # would take for a moving contact. The colour bars alone are static: no contact.
  check "$_v: OSD text off" v4l2-ctl -d "$1" -c osd_text_mode=2
  check "$_v: 320x240 YUYV" v4l2-ctl -d "$1" --set-fmt-video=width=320,height=240,pixelformat=YUYV
  v4l2-ctl -d "$1" --get-fmt-video | grep -q 'Width/Height *: 320/240' || fail "$_v: format is not 320x240"
}

# vivid_node N: the /dev node of vivid instance N (vivid-00N-vid-cap), empty if there is none.
# All instances hang off one platform device, vivid.0.
vivid_node() {
  for _n in /sys/class/video4linux/video*; do
    [ "$(cat "$_n/name" 2>/dev/null)" = "vivid-00$1-vid-cap" ] && { echo "/dev/${_n##*/}"; return 0; }
  done
  return 0
}

# vivid_two_sensors: two vivid capture devices at 320x240, as the two pads, with stable names like a
# udev rule would make: /dev/tacse3-left -> vivid.0's node, /dev/tacse3-right -> vivid.1's.
vivid_two_sensors() {
  if ! lsmod | grep -q '^vivid'; then
    check "modprobe vivid n_devs=2" modprobe vivid n_devs=2 node_types=0x1,0x1
  fi
  vivid_sensor 0 /dev/tacse3-left
  vivid_sensor 1 /dev/tacse3-right
}

# vivid_sensor N LINK: configures vivid.N for 320x240 and points LINK at its node.
vivid_sensor() {
  _i=0
  while [ -z "$(vivid_node "$1")" ]; do
    [ $_i -ge 50 ] && fail "vivid instance $1 has no video node"
    sleep 0.1; _i=$((_i + 1))
  done
  vivid_hdmi_320x240 "$(vivid_node "$1")"
  ln -sfn "$(vivid_node "$1")" "$2"
  log "$2 -> $(vivid_node "$1")"
}

# vivid_measure FRAMES OUTFILE: streams both vivid devices together with v4l2-ctl, as the daemon
# will, and writes "frames= dropped= delivered_fps= nominal_fps=" per device to OUTFILE. vivid
# stamps buffers on its nominal schedule and skips sequence numbers when the emulated CPU falls
# behind: the delivered rate is (frames-1)/(last-first timestamp).
vivid_measure() {
  : >"$2"
  for _d in tacse3-left tacse3-right; do
    v4l2-ctl -d /dev/$_d --stream-mmap=4 --stream-count="$1" --verbose >/tmp/$_d-measure.txt 2>&1 &
  done
  wait
  for _d in tacse3-left tacse3-right; do
    awk -v d=$_d '/cap dqbuf:/ { for (i = 1; i <= NF; i++) { if ($i == "seq:") s = $(i + 1); if ($i == "ts:") t = $(i + 1) }
        n++; if (n == 1) { s0 = s; t0 = t } }
      END { if (n < 2 || t == t0) { print d " frames=0"; exit 1 }
            printf "%s frames=%d dropped=%d span_s=%.3f delivered_fps=%.1f nominal_fps=%.1f\n",
                   d, n, s - s0 + 1 - n, t - t0, (n - 1) / (t - t0), (s - s0) / (t - t0) }' \
      /tmp/$_d-measure.txt >>"$2" || fail "$_d: no frames measured"
  done
  cat "$2"
}

# can_marker CODE: puts an event marker on vcan0 (identifier 0x01E: node 0, which no tacse3 node
# uses) so that the host sees the event on the candump clock of the CAN log. CODE: 2 hex digits.
can_marker() { cansend vcan0 "01E#$1" || fail "cansend marker $1"; log "marker $1"; }

# tacse3_cmd ID TARGET CODE A2 A3 A4 A5 SEQ [RESERVED_NIBBLE]: prints a Command frame for cansend,
# "ID#<8 bytes>", with the CRC-8/SAE-J1850 of docs/can-protocol.md computed over the identifier
# word (4 bytes, little-endian) and bytes 0..6. ID is 3 hex digits (node << 5 | 0x10).
tacse3_cmd() {
  awk -v id="$1" -v b0="$3" -v b1="$2" -v b2="$4" -v b3="$5" -v b4="$6" -v b5="$7" -v seq="$8" \
      -v rsv="${9:-0}" 'function crc8(c, x,   k) { c = xor(c, x); for (k = 0; k < 8; k++)
        c = and(c, 128) ? and(xor(lshift(c, 1), 29), 255) : and(lshift(c, 1), 255); return c }
    function hex(s) { return ("0x" s) + 0 }
    BEGIN { n = split(sprintf("%d %d %d %d %d %d %d", hex(b0), b1, hex(b2), hex(b3), hex(b4), hex(b5),
                              seq * 16 + rsv), b, " ")
      i = hex(id); c = 255
      c = crc8(c, and(i, 255)); c = crc8(c, and(rshift(i, 8), 255)); c = crc8(c, 0); c = crc8(c, 0)
      out = ""; for (k = 1; k <= 7; k++) { c = crc8(c, b[k]); out = out sprintf("%02X", b[k]) }
      printf "%s#%s%02X\n", id, out, xor(c, 255) }'
}

# gpiosim_chip NAME LINES [LINE_NAME...]: a live gpio-sim chip with LINES lines, the first ones
# named; prints "CHIP DEV" (e.g. "gpiochip0 gpio-sim.0"). Reuses the chip when it exists.
gpiosim_chip() {
  _cfg=/sys/kernel/config/gpio-sim/$1
  if [ ! -d "$_cfg" ]; then
    lsmod | grep -q '^gpio_sim' || modprobe gpio-sim || fail "modprobe gpio-sim"
    mkdir "$_cfg" "$_cfg/bank0" || fail "configfs gpio-sim/$1"
    echo "$2" >"$_cfg/bank0/num_lines"
    _i=0; shift 2
    for _n in "$@"; do mkdir "$_cfg/bank0/line$_i"; echo "$_n" >"$_cfg/bank0/line$_i/name"; _i=$((_i + 1)); done
    echo 1 >"$_cfg/live" || fail "gpio-sim $1 live"
  fi
  echo "$(cat "$_cfg/bank0/chip_name") $(cat "$_cfg/dev_name")"
}

# daemon_start BOARD [ARGS...]: starts tacse3d in the background (stderr to $TACSE3_OUT/daemon.log),
# DAEMON_PID is its pid. candump_start first, so the log has the boot.
daemon_start() {
  _b=$1; shift
  log "tacse3d --board $_b $*"
  tacse3d --board "$_b" --verbose "$@" 2>"$TACSE3_OUT/daemon.log" &
  DAEMON_PID=$!
  echo "$DAEMON_PID" >"$TACSE3_OUT/daemon.pid"
}

# candump_start: candump -L vcan0 into $TACSE3_OUT/can.log (CANDUMP_PID). candump_stop ends it.
# -D: keep running while vcan0 is down (scenario 3); -r: a 2 MiB socket buffer, so that candump
# itself, slowed by TCG, does not drop frames that would look like the daemon's gaps.
candump_start() {
  candump -D -r 2097152 -L vcan0 >"$TACSE3_OUT/can.log" &
  CANDUMP_PID=$!
  sleep 0.2
}
candump_stop() { kill "$CANDUMP_PID" 2>/dev/null; wait "$CANDUMP_PID" 2>/dev/null || true; }

# wait_can_frame ID SECONDS: waits until the CAN log has a frame with identifier ID (3 hex digits).
wait_can_frame() {
  _i=0
  while ! grep -q " vcan0 $1#" "$TACSE3_OUT/can.log" 2>/dev/null; do
    [ "$_i" -ge $(($2 * 10)) ] && fail "no CAN frame $1 within $2 s"
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "tacse3d exited early (rc: see daemon.log): $(tail -3 "$TACSE3_OUT/daemon.log")"
    sleep 0.1; _i=$((_i + 1))
  done
}

# daemon_stop_timed: SIGTERM to tacse3d; writes "sigterm_ms= exit=" to $TACSE3_OUT/stop.txt (time
# from the signal until the process was gone, 10 ms resolution).
daemon_stop_timed() {
  _t0=$(uptime_ms)
  kill -TERM "$DAEMON_PID"
  _i=0
  while kill -0 "$DAEMON_PID" 2>/dev/null && [ $_i -lt 500 ]; do sleep 0.01; _i=$((_i + 1)); done
  _t1=$(uptime_ms)
  _rc=0; wait "$DAEMON_PID" || _rc=$?
  echo "sigterm_ms=$((_t1 - _t0)) exit=$_rc" | tee "$TACSE3_OUT/stop.txt"
}

# vivid_unplug N / vivid_replug N: one sensor disappears mid-stream and comes back. `modprobe vivid
# n_devs=2` makes both instances children of ONE platform device (vivid.0), so a sysfs unbind takes
# both away (vivid_unbind_all); for one sensor, vivid's per-instance "disconnect" control emulates a
# USB unplug: the node stays but every ioctl, and open(), fails with ENODEV, and the instance comes
# back by itself once the last open file of it is closed. This shell keeps one open (fd 7) so the
# sensor stays away until vivid_replug closes it, whatever the daemon does meanwhile. Markers on
# vcan0: 01 just before the unplug, 0A once v4l2-ctl has returned (it takes a few hundred ms to start
# under TCG, so the disconnect lies between the two), 02 when the node opens again.
vivid_unplug() {
  _node=$(vivid_node "$1")
  exec 7<"$_node"
  can_marker 01
  v4l2-ctl -d "$_node" -c disconnect=1 || fail "vivid-00$1 disconnect"
  can_marker 0A
}
vivid_replug() {
  exec 7<&-
  _node=$(vivid_node "$1"); _i=0
  until v4l2-ctl -d "$_node" --info >/dev/null 2>&1; do
    [ $_i -ge 100 ] && fail "vivid-00$1 ($_node) did not come back within 10 s (still open somewhere?)"
    sleep 0.1; _i=$((_i + 1))
  done
  can_marker 02
}

# vivid_unbind_all / vivid_rebind_all: the sysfs path: unbind the vivid platform device (both pads
# vanish, their nodes with them), then bind it again and set both up like at the start (a new
# vivid instance starts on its webcam input). Markers 08 before the unbind, 09 when both are ready.
vivid_unbind_all() {
  # The links go first, so the daemon cannot reopen the fresh nodes before vivid_rebind_all has set
  # them up (a streaming node refuses new DV timings: EBUSY).
  rm -f /dev/tacse3-left /dev/tacse3-right
  can_marker 08
  echo vivid.0 >/sys/bus/platform/drivers/vivid/unbind || fail "sysfs unbind vivid.0"
}
vivid_rebind_all() {
  echo vivid.0 >/sys/bus/platform/drivers/vivid/bind || fail "sysfs bind vivid.0"
  vivid_sensor 0 /dev/tacse3-left
  vivid_sensor 1 /dev/tacse3-right
  can_marker 09
}

# daemon_streaming BOARD [ARGS...]: candump on vcan0, tacse3d started, and its first Status frame
# (identifier 0x028, node 1) seen within TACSE3_DAEMON_UP_S seconds (default 30): it is streaming.
daemon_streaming() {
  candump_start
  daemon_start "$@"
  wait_can_frame 028 "${TACSE3_DAEMON_UP_S:-30}"
}

# loopback_pads SLOWDOWN: two v4l2loopback devices (/dev/video20 left, /dev/video21 right) fed by
# tacse3-v4l2-feed from the recording tests/vm/suite.sh stages ($TACSE3_PREFIX/share/tacse3/vm/
# e2e-rec), at its rate / SLOWDOWN. The feeder repeats the first (undeformed, no contact) frame until
# /tmp/go exists, then plays the recording once and holds its last frame 2 s. FEEDER_PID is its pid;
# its log is $TACSE3_OUT/feed.log. Skips the scenario when the feeder or the recording is missing.
loopback_pads() {
  _rec=$TACSE3_PREFIX/share/tacse3/vm/e2e-rec
  if [ ! -e /dev/video21 ]; then
    # smoke-v4l2loopback may have loaded it with one device: reload with both pads.
    lsmod | grep -q '^v4l2loopback' && { rmmod v4l2loopback || fail "rmmod v4l2loopback"; }
    check "modprobe v4l2loopback (2 devices)" modprobe v4l2loopback devices=2 video_nr=20,21 \
      card_label=tacse3-left,tacse3-right exclusive_caps=1 max_buffers=8
  fi
  wait_for /dev/video20 5
  wait_for /dev/video21 5
  command -v tacse3-v4l2-feed >/dev/null || skip "tacse3-v4l2-feed is not in the guest (tests/vm/suite.sh builds it)"
  [ -f "$_rec/recording.json" ] || skip "no recording at $_rec (tests/vm/suite.sh renders it)"
  cp "$_rec/recording.json" "$TACSE3_OUT/"
  rm -f /tmp/go
  tacse3-v4l2-feed --rec "$_rec" --left /dev/video20 --right /dev/video21 --slowdown "$1" \
    --go /tmp/go --hold-s 2 2>"$TACSE3_OUT/feed.log" &
  FEEDER_PID=$!
  _i=0
  until grep -q '^feed: .* loaded' "$TACSE3_OUT/feed.log"; do
    kill -0 "$FEEDER_PID" 2>/dev/null || fail "feeder: $(cat "$TACSE3_OUT/feed.log")"
    [ $_i -ge 600 ] && fail "the feeder did not load the recording in 60 s"
    sleep 0.1; _i=$((_i + 1))
  done
  cat "$TACSE3_OUT/feed.log"
  v4l2-ctl -d /dev/video20 --get-fmt-video >"$TACSE3_OUT/video20-fmt.txt"
  grep -q 'Width/Height *: 320/240' "$TACSE3_OUT/video20-fmt.txt" || fail "loopback capture side is not 320x240"
  echo "ok: both loopback devices carry 320x240 frames"
}

# can_flap_scenario CYCLES: two vivid pads, vcan0, tacse3d started with ./board.toml and seen
# sending Status, then can_flap CYCLES, then the timed SIGTERM.
can_flap_scenario() {
  vivid_two_sensors
  vcan_up vcan0
  need_daemon
  daemon_start ./board.toml
  timeout 30 candump -n 1 vcan0,028:7FF >/dev/null 2>&1 || fail "no Status frame within 30 s of the start"
  can_flap "$1"
  daemon_stop_timed
}

# can_flap CYCLES: with tacse3d streaming on vcan0, takes vcan0 down and up CYCLES times. After each
# up the daemon's next Timestamp frame (0x021, node 1) must arrive within 5 s, read by a fresh
# candump, and the daemon must still run. Writes "cycles= resumed= resume_ms_median= resume_ms_max="
# to $TACSE3_OUT/flap.txt (resume: from `ip link set up` returning to candump's first frame).
can_flap() {
  _n=$1; _k=0; : >/tmp/resume_ms
  while [ "$_k" -lt "$_n" ]; do
    ip link set vcan0 down || fail "cycle $_k: ip link set vcan0 down"
    ip link set vcan0 up || fail "cycle $_k: ip link set vcan0 up"
    _t0=$(uptime_ms)
    timeout 5 candump -n 1 vcan0,021:7FF >/dev/null 2>&1 || fail "cycle $_k: no Timestamp frame within 5 s of vcan0 up"
    echo $(($(uptime_ms) - _t0)) >>/tmp/resume_ms
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "cycle $_k: tacse3d exited: $(tail -3 "$TACSE3_OUT/daemon.log")"
    _k=$((_k + 1))
  done
  _med=$(sort -n /tmp/resume_ms | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }')
  _max=$(sort -n /tmp/resume_ms | tail -1)
  echo "cycles=$_n resumed=$(wc -l </tmp/resume_ms) resume_ms_median=$_med resume_ms_max=$_max" | tee "$TACSE3_OUT/flap.txt"
}
