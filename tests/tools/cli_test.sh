#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Scripted CLI tests of tacse3-replay, tacse3-calibrate, tacse3-sim, tacse3-canmon and (when
# given) tacse3d: exit codes, messages, output files.
# Usage: cli_test.sh BIN_DIR [TACSE3D] (BIN_DIR: the build's tools/ folder)
set -u
BIN="$1"
TACSE3D="${2:-}"
SIM="$BIN/sim/tacse3-sim"
REPLAY="$BIN/replay/tacse3-replay"
CAL="$BIN/calibrate/tacse3-calibrate"
CANMON="$BIN/canmon/tacse3-canmon"
T="${TMPDIR:-/tmp}/tacse3_cli_test.$$"
mkdir -p "$T"
trap 'rm -rf "$T"' EXIT
fails=0
check() {  # check NAME CONDITION...
  name="$1"; shift
  if "$@"; then echo "ok   $name"; else echo "FAIL $name"; fails=$((fails + 1)); fi
}
contains() { grep -q -- "$2" "$1"; }
lacks() { ! grep -q -- "$2" "$1"; }
# A FIFO or a device must be an error at once: `timeout` turns a hang into exit 124.
bounded() { timeout 20 "$@"; }

"$SIM" -q --out "$T/rec" --object sphere --motion rz --magnitude 2 --colour grey \
  --approach-s 0.05 --grasp-s 0.2 --settle-s 0.05 --hold-s 0.1 || { echo "FAIL tacse3-sim"; exit 1; }
frames=$(($(wc -l < "$T/rec/frames.csv") - 1))

"$REPLAY" "$T/rec" --out "$T/out.csv" > "$T/stdout" 2> "$T/stderr"
check "replay exits 0" test $? -eq 0
check "replay CSV header" test "$(head -1 "$T/out.csv")" = \
  "t_ns,wx,wy,wz,vx,vy,vz,qw,qx,qy,qz,px,py,pz,valid_left,valid_right"
check "replay CSV rows = frames" test "$(($(wc -l < "$T/out.csv") - 1))" -eq "$frames"
check "replay summary has the rotation" contains "$T/stdout" "rotation: *estimated"
check "replay summary has the truth" contains "$T/stdout" "truth *2.00 deg"
check "a full truth gives no truth warning" lacks "$T/stdout" "truth.csv ends at"
check "a run with valid frames gives no all-invalid warning" lacks "$T/stdout" "no frame gave"

# A contact threshold no f^z reaches: no frame is valid, and the summary says what to check.
printf 'format = "tacse3-calibration"\nversion = 1\n\n[sensor]\ncontact_tau_on = 100\ncontact_tau_off = 50\n' \
  > "$T/deaf.toml"
"$REPLAY" "$T/rec" --calibration "$T/deaf.toml" --out "$T/x.csv" > "$T/stdout_d" 2> /dev/null
check "replay with no valid frame exits 0" test $? -eq 0
check "it reads no valid frame" contains "$T/stdout_d" "estimate valid in 0% of frames"
check "and warns, naming the threshold" contains "$T/stdout_d" \
  "warning: no frame gave a valid estimate.*contact_tau_on 100 may be above"

# A truth.csv that ends before the last frame: the summary warns, naming the file and its end.
cp -r "$T/rec" "$T/rect"
head -3 "$T/rec/truth.csv" > "$T/rect/truth.csv"
truth_end=$(tail -1 "$T/rect/truth.csv" | cut -d, -f1)
"$REPLAY" "$T/rect" --out "$T/x.csv" > "$T/stdout_t" 2> /dev/null
check "replay with a short truth exits 0" test $? -eq 0
check "the short truth is warned about" contains "$T/stdout_t" \
  "warning: $T/rect/truth.csv ends at t = $(awk -v t="$truth_end" 'BEGIN { printf "%.3f", t * 1e-9 }') s"

# No --calibration: a simulator recording runs on the simulator's calibration, anything else on
# the built-in defaults, which is UNCALIBRATED at start (stderr) and in the summary.
check "a sim recording defaults to the simulator's calibration" \
  contains "$T/stdout" "calibration .*sim-calibration.toml (the simulator's"
check "a sim recording is not UNCALIBRATED" lacks "$T/stderr" "UNCALIBRATED"
cp -r "$T/rec" "$T/recn"
sed -i 's/"generator": *"tacse3-sim"/"generator": "a camera"/' "$T/recn/recording.json"
"$REPLAY" "$T/recn" --out "$T/x.csv" > "$T/stdout_n" 2> "$T/stderr_n"
check "replay of a non-sim recording exits 0" test $? -eq 0
check "it says UNCALIBRATED at start" \
  contains "$T/stderr_n" "tacse3-replay: UNCALIBRATED: calibration built-in defaults"
check "and in the summary" contains "$T/stdout_n" "calibration built-in defaults: UNCALIBRATED"
printf 'format = "tacse3-calibration"\nversion = 1\n' > "$T/header.toml"
"$REPLAY" "$T/rec" --calibration "$T/header.toml" --out "$T/x.csv" > "$T/stdout_h" 2> "$T/stderr_h"
check "a header-only calibration is UNCALIBRATED" \
  contains "$T/stderr_h" "UNCALIBRATED: calibration $T/header.toml (sets no sensor keys)"
if [ -n "$TACSE3D" ]; then
  "$TACSE3D" --board sim --check > "$T/check_sim" 2>&1
  check "tacse3d --board sim --check exits 0" test $? -eq 0
  check "the sim board defaults to the simulator's calibration" \
    contains "$T/check_sim" "calibration: .*sim-calibration.toml (the simulator's, the default"
  check "the sim board is not UNCALIBRATED" lacks "$T/check_sim" "UNCALIBRATED"
  "$TACSE3D" --board sim --calibration "$T/header.toml" --check > "$T/check_h" 2>&1
  check "tacse3d with a header-only calibration says UNCALIBRATED" \
    contains "$T/check_h" "calibration: $T/header.toml (sets no sensor keys): UNCALIBRATED"
fi

"$REPLAY" "$T/rec" --out - --method paper --mode displacement --sensors left -q > "$T/o2" 2>&1
check "replay to stdout" test "$(($(wc -l < "$T/o2") - 1))" -eq "$frames"

"$REPLAY" "$T/nope" --out "$T/x.csv" > /dev/null 2> "$T/e1"
check "missing recording exits 1" test $? -eq 1
check "missing recording is named" contains "$T/e1" "$T/nope"

printf 'format = "tacse3-calibration"\nversion = 1\n[sensor]\nc_velocty = 0.01\n' > "$T/bad.toml"
"$REPLAY" "$T/rec" --calibration "$T/bad.toml" --out "$T/x.csv" > /dev/null 2> "$T/e2"
check "bad calibration exits 1" test $? -eq 1
check "bad calibration names file and key" contains "$T/e2" "bad.toml:4: unknown key \"sensor.c_velocty\""

"$REPLAY" "$T/rec" --out "$T/x.csv" --mode fast > /dev/null 2> "$T/e3"
check "bad --mode is refused" test $? -ne 0
check "bad --mode is named" contains "$T/e3" "mode"

"$REPLAY" > /dev/null 2>&1
check "no arguments is an error" test $? -ne 0

# --slip-log on a grasp that ends with the pads opening over 0.2 s (docs/replay.md, dsp.md 4.2b):
# one row per present sensor and frame; 'releasing' only within the release, and there with a
# load falling faster than the default release_load_rate (4/s: a consistency check of the two
# columns, since that is the rule's definition); a 2 deg stick motion never slips.
"$SIM" -q --out "$T/rel" --object sphere --motion rz --magnitude 2 --colour grey \
  --approach-s 0.05 --grasp-s 0.2 --settle-s 0.05 --hold-s 0.1 --release-s 0.2 ||
  { echo "FAIL tacse3-sim --release-s"; exit 1; }
rel_frames=$(($(wc -l < "$T/rel/frames.csv") - 1))
# The release starts 0.2 s before the recording's end, one frame period after its last frame.
t_release=$(tail -1 "$T/rel/frames.csv" | awk -F, '{ print $2 + 8333333 - 200000000 }')
"$REPLAY" "$T/rel" --out "$T/rel.csv" --slip-log "$T/slip.csv" -q
check "replay --slip-log exits 0" test $? -eq 0
slip_header="t_ns,sensor,contact,slipping,onset,stick_confirmed,relax_rate_per_s,shift_m,rate_m_s"
slip_header="$slip_header,load_drop_per_s,releasing,anchor_set,velocity_anchored,points"
slip_header="$slip_header,velocity_points,anchor_overlap_points"
check "slip log header" test "$(head -1 "$T/slip.csv")" = "$slip_header"
check "slip log: a row per sensor and frame" test "$(($(wc -l < "$T/slip.csv") - 1))" -eq $((2 * rel_frames))
# The velocity proxy's region: Ω (velocity_points = points) unless it read Ω ∩ anchor
# (velocity_points = anchor_overlap_points ≤ points); a contact's first frame has no anchor yet
# and sets it (this recording has no frame the pipeline rejects, which keeps the anchor), and
# there is no region without contact.
awk -F, 'NR > 1 { if ($3 == 1 && !was[$2]) { first[$2]++; if ($12 != 1 || $16 != 0) bad++ }
                  was[$2] = $3
                  if ($15 > $14 || $16 > $14 || ($13 == 0 && $15 != $14) ||
                      ($13 == 1 && $15 != $16) || ($3 == 0 && $14 + $16 != 0)) bad++ }
  END { exit !(first["left"] >= 1 && first["right"] >= 1 && bad == 0) }' "$T/slip.csv"
check "slip log: anchor set on first contact, velocity region within Omega" test $? -eq 0
awk -F, -v t0="$t_release" 'NR > 1 && $11 == 1 { n[$2]++; if ($1 < t0 || $10 <= 4) bad++ }
  END { exit !(n["left"] >= 1 && n["right"] >= 1 && bad == 0) }' "$T/slip.csv"
check "slip log: releasing on both pads, only in the release, load falling > 4/s" test $? -eq 0
awk -F, -v t0="$t_release" 'NR > 1 && $1 < t0 && $10 > 4 { bad++ } END { exit bad > 0 }' \
  "$T/slip.csv"
check "slip log: no load falling > 4/s before the release" test $? -eq 0
check "slip log: a 2 deg stick motion never slips" test -z "$(awk -F, 'NR > 1 && $4 != 0' "$T/slip.csv")"

# A FIFO as the calibration file: refused at once (the loader opens without blocking and checks
# what it opened), and left as it is.
mkfifo "$T/fifo.toml"
bounded "$REPLAY" "$T/rec" --calibration "$T/fifo.toml" --out "$T/x.csv" > /dev/null 2> "$T/e5"
check "replay --calibration FIFO exits 1" test $? -eq 1
check "replay --calibration FIFO is named" contains "$T/e5" "$T/fifo.toml: is a FIFO"
if [ -n "$TACSE3D" ]; then
  bounded "$TACSE3D" --board sim --calibration "$T/fifo.toml" --check > /dev/null 2> "$T/e21"
  check "tacse3d --calibration FIFO --check exits 1" test $? -eq 1
  check "tacse3d names the FIFO" contains "$T/e21" "$T/fifo.toml: is a FIFO"
fi
check "the FIFO is still a FIFO" test -p "$T/fifo.toml"

# calibrate --out replaces only a regular file or a new path: a symlink, a FIFO, a directory or
# a device stays as it is (/dev/null is only checked to be refused, never written).
echo original > "$T/real.toml"
ln -s "$T/real.toml" "$T/link.toml"
mkdir "$T/dir.toml"
for target in "$T/link.toml:a symbolic link" "$T/fifo.toml:a FIFO" "$T/dir.toml:a directory" \
              "/dev/null:a character device"; do
  "$CAL" "$T/rec" -q --out "${target%%:*}" > /dev/null 2> "$T/e12"
  check "calibrate --out ${target#*:} exits 1" test $? -eq 1
  check "calibrate --out ${target#*:} is refused" \
    contains "$T/e12" "${target%%:*}: is ${target#*:}; refusing to replace it"
done
check "the symlink is still a symlink" test -L "$T/link.toml"
check "its target is unchanged" test "$(cat "$T/real.toml")" = original
check "the FIFO is still a FIFO after calibrate" test -p "$T/fifo.toml"
check "the directory is still a directory" test -d "$T/dir.toml"
check "/dev/null is still a device" test -c /dev/null
echo original > "$T/fitted.toml"
# One 2 deg rotation about z determines few of the values: --force writes the file anyway.
"$CAL" "$T/rec" -q --force --out "$T/fitted.toml" > /dev/null 2>&1
check "calibrate over a regular file exits 0" test $? -eq 0
check "the regular file was replaced" contains "$T/fitted.toml" 'format = "tacse3-calibration"'
check "no temporary file left" test -z "$(ls -A "$T" | grep 'fitted.toml.tmp')"

# calibrate --out is checked before the fit: a recording that cannot even be opened comes second.
"$CAL" "$T/nope" --out "$T/no-such-dir/cal.toml" > /dev/null 2> "$T/e11"
check "calibrate into a missing directory exits 1" test $? -eq 1
check "the missing directory is named before the fit" \
  contains "$T/e11" "--out: $T/no-such-dir/cal.toml: the directory $T/no-such-dir does not exist"
check "no fit and no recording read" lacks "$T/e11" "nope"

# Recording files that are not regular files: refused at once, naming the file.
cp -r "$T/rec" "$T/recfifo"
rm "$T/recfifo/recording.json"
mkfifo "$T/recfifo/recording.json"
bounded "$REPLAY" "$T/recfifo" --out "$T/x.csv" > /dev/null 2> "$T/e6"
check "replay of a FIFO recording.json exits 1" test $? -eq 1
check "the FIFO recording.json is named" contains "$T/e6" "recfifo/recording.json: is a FIFO"
rm "$T/recfifo/recording.json" "$T/recfifo/frames.csv"
cp "$T/rec/recording.json" "$T/recfifo/recording.json"
ln -s /dev/zero "$T/recfifo/frames.csv"
bounded "$REPLAY" "$T/recfifo" --out "$T/x.csv" > /dev/null 2> "$T/e7"
check "replay with frames.csv -> /dev/zero exits 1" test $? -eq 1
check "frames.csv -> /dev/zero is named" contains "$T/e7" "recfifo/frames.csv: is a character device"

# An empty path is a usage error naming the option, never "no file".
for opt in --calibration --dump-fields --can-log --slip-log --out; do
  "$REPLAY" "$T/rec" --out "$T/x.csv" "$opt" '' > /dev/null 2> "$T/e8"
  check "replay $opt '' exits 2" test $? -eq 2
  check "replay $opt '' is named" contains "$T/e8" "$opt: empty path"
done
for opt in --start --out; do
  "$CAL" "$T/rec" --out "$T/cal.toml" "$opt" '' > /dev/null 2> "$T/e9"
  check "calibrate $opt '' exits 2" test $? -eq 2
  check "calibrate $opt '' is named" contains "$T/e9" "$opt: empty path"
done
"$SIM" -q --out '' > /dev/null 2> "$T/e10"
check "sim --out '' exits 2" test $? -eq 2
check "sim --out '' is named" contains "$T/e10" "--out: empty path"
if [ -n "$TACSE3D" ]; then
  for opt in --calibration --record --can-iface --can-socket; do
    "$TACSE3D" --board sim --check "$opt" '' > /dev/null 2> "$T/e20"
    check "tacse3d $opt '' exits 2" test $? -eq 2
    check "tacse3d $opt '' is named" contains "$T/e20" "tacse3d: $opt needs"
    "$TACSE3D" --board sim --check "$opt=" > /dev/null 2> "$T/e20"
    check "tacse3d $opt= exits 2" test $? -eq 2
  done
fi

# A CAN log that cannot be written (/dev/full: ENOSPC, as a full disk) stops the daemon with exit
# 1 and one message naming the file and the cause.
if [ -n "$TACSE3D" ]; then
  bounded "$TACSE3D" --board sim --seconds 2 --can-log /dev/full > /dev/null 2> "$T/e22"
  check "tacse3d --can-log /dev/full exits 1" test $? -eq 1
  check "tacse3d names the CAN log and the cause" \
    contains "$T/e22" "CAN log /dev/full: write failed: No space left on device"
  check "the CAN log error is said once" test "$(grep -c 'write failed' "$T/e22")" -eq 1
fi

# --can-socket: one CAN backend at a time (usage, exit 2); a path that is a file is never replaced.
if [ -n "$TACSE3D" ]; then
  "$TACSE3D" --board sim --check --can-log - --can-socket "$T/can.sock" > /dev/null 2> "$T/e27"
  check "tacse3d --can-log with --can-socket exits 2" test $? -eq 2
  check "tacse3d names both backend options" contains "$T/e27" "--can-log and --can-socket"
  echo keep > "$T/plain"
  bounded "$TACSE3D" --board sim --seconds 1 --can-socket "$T/plain" > /dev/null 2> "$T/e28"
  check "tacse3d --can-socket on a file exits 1" test $? -eq 1
  check "tacse3d names the file it will not replace" \
    contains "$T/e28" "$T/plain' exists and is not a socket"
  check "the file is kept" test "$(cat "$T/plain")" = keep
fi

# --check refuses a [sim] object the simulator has no preset for, as the run would.
if [ -n "$TACSE3D" ]; then
  sed 's/^object = .*/object = "banana"/' "$(dirname "$0")/../../boards/sim/board.toml" \
    > "$T/banana.toml"
  "$TACSE3D" --board "$T/banana.toml" --check > /dev/null 2> "$T/e26"
  check "tacse3d --check with object banana exits 1" test $? -eq 1
  check "tacse3d names sim.object and banana" contains "$T/e26" 'key "sim.object" must be one of'
fi

# Results on a full standard output are an error, not exit 0.
"$REPLAY" "$T/rec" --out - > /dev/full 2> "$T/e14"
check "replay --out - > /dev/full exits 1" test $? -eq 1
check "replay names the stdout write error" \
  contains "$T/e14" "tacse3-replay: error: standard output: write error"
"$REPLAY" "$T/rec" --out "$T/x.csv" > /dev/full 2> "$T/e15"
check "replay summary to /dev/full exits 1" test $? -eq 1
# The fit and --check print their reports through the same checked stdout: --check, which
# replays once instead of fitting, shows it (a fit under the sanitizers takes a minute).
"$CAL" --check "$T/fitted.toml" "$T/rec" > /dev/full 2> "$T/e13"
check "calibrate report to /dev/full exits 1" test $? -eq 1
check "calibrate names the stdout write error" contains "$T/e13" "standard output: write error"
"$SIM" --out "$T/full" --object sphere --motion rz --magnitude 2 --colour grey --approach-s 0.05 \
  --grasp-s 0.1 --settle-s 0.05 --hold-s 0.05 > /dev/full 2> "$T/e16"
check "sim summary to /dev/full exits 1" test $? -eq 1
check "sim names the stdout write error" contains "$T/e16" "standard output: write error"
if [ -x "$CANMON" ]; then
  "$REPLAY" "$T/rec" --out "$T/x.csv" --can-log "$T/can.log" -q
  "$CANMON" --log "$T/can.log" --format csv > /dev/full 2> "$T/e17"
  check "canmon to /dev/full exits 1" test $? -eq 1
  check "canmon names the stdout write error" contains "$T/e17" "standard output: write error"
fi

# Too short a recording for a fit: refused, naming the recording and its frame count.
cp -r "$T/rec" "$T/rec1"
head -2 "$T/rec/frames.csv" > "$T/rec1/frames.csv"
find "$T/rec1" -name '*.png' ! -name 000000.png -delete
"$CAL" "$T/rec1" --out "$T/cal1.toml" > /dev/null 2> "$T/e18"
check "calibrate on a 1-frame recording exits 1" test $? -eq 1
check "the short recording and its count are named" \
  contains "$T/e18" "$T/rec1: 1 frame(s); calibration needs at least 16"
check "no calibration from a 1-frame recording" test ! -e "$T/cal1.toml"

# A finger separation outside the board files' range (1 .. 250 mm) is refused by replay.
cp -r "$T/rec" "$T/recw"
sed 's/"finger_separation_mm": [0-9.]*/"finger_separation_mm": 1e-9/' "$T/rec/recording.json" \
  > "$T/recw/recording.json"
"$REPLAY" "$T/recw" --out "$T/x.csv" > /dev/null 2> "$T/e19"
check "replay with a 1e-9 mm finger separation exits 1" test $? -eq 1
check "the separation and the range are named" \
  contains "$T/e19" "rig.finger_separation_mm 1e-09 is outside 1 .. 250 mm"

# Values in messages are %g: 1e300 and 1e-300 read as such, not as 300 digits or 0.000000.
for pitch in 1e300 1e-300; do
  sed "s/\"pixel_pitch_mm\": [0-9.e+-]*/\"pixel_pitch_mm\": $pitch/" "$T/rec/recording.json" \
    > "$T/recw/recording.json"
  "$REPLAY" "$T/recw" --out "$T/x.csv" > /dev/null 2> "$T/e23"
  check "replay with a $pitch mm pitch exits 1" test $? -eq 1
  check "the $pitch mm pitch is written as %g" \
    contains "$T/e23" "rig.pixel_pitch_mm $(printf '%g' "$pitch") is outside 0.001 .. 0.2 mm"
done
# A pitch twice the calibration's doubles c_velocity 80 to 160: the gain is blamed, not the pitch.
sed 's/"pixel_pitch_mm": [0-9.e+-]*/"pixel_pitch_mm": 0.15/' "$T/rec/recording.json" \
  > "$T/recw/recording.json"
printf 'format = "tacse3-calibration"\nversion = 1\n[sensor]\nc_velocity = 80\n' > "$T/cv80.toml"
"$REPLAY" "$T/recw" --calibration "$T/cv80.toml" --out "$T/x.csv" > /dev/null 2> "$T/e24"
check "replay with c_velocity 80 at twice the pitch exits 1" test $? -eq 1
check "the rescaled c_velocity is blamed" contains "$T/e24" "rescales its c_velocity 80 to 160"
check "the pitch itself is not called out of range" lacks "$T/e24" "is outside 0.001"
if [ -n "$TACSE3D" ]; then
  bounded "$TACSE3D" --board sim --seconds 1 --can-log /dev/null --record "$T/rec" \
    > /dev/null 2> "$T/e25"
  check "tacse3d --record into a recording exits 1" test $? -eq 1
  check "tacse3d --record asks for a new directory" contains "$T/e25" "give a new or empty directory"
  check "tacse3d --record offers no overwrite option" lacks "$T/e25" "overwrite"
fi

rm "$T/rec/truth.csv"
"$CAL" "$T/rec" --out "$T/cal.toml" > /dev/null 2> "$T/e4"
check "calibrate without truth exits 1" test $? -eq 1
check "calibrate names truth.csv" contains "$T/e4" "truth.csv"
check "no calibration file written" test ! -e "$T/cal.toml"

[ "$fails" -eq 0 ] || { echo "$fails check(s) failed"; exit 1; }
echo "all CLI checks passed"
