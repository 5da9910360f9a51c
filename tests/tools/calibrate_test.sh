#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# tacse3-calibrate's refusals, self-check and --check on short simulated recordings
# (docs/calibration.md): exit codes, the messages that name what to fix, and that a refused or
# failed fit writes no file.
# Usage: calibrate_test.sh BIN_DIR (the build's tools/ folder)
set -u
BIN="$1"
SIM="$BIN/sim/tacse3-sim"
CAL="$BIN/calibrate/tacse3-calibrate"
COMMITTED="$(cd "$(dirname "$0")/../../tools/replay/data" && pwd)/sim-calibration.toml"
T="${TMPDIR:-/tmp}/tacse3_calibrate_test.$$"
mkdir -p "$T"
trap 'rm -rf "$T"' EXIT
# Recordings by short relative names: the report's tables cut longer names.
cd "$T" || exit 1
fails=0
check() {  # check NAME CONDITION...
  name="$1"; shift
  if "$@"; then echo "ok   $name"; else echo "FAIL $name"; fails=$((fails + 1)); fi
}
contains() { grep -q -- "$2" "$1"; }  # a basic regular expression

# The set: one recording per line of --plan's CSV (axis, magnitude, regime and motion duration
# as planned; the pads open for 0.05 s, close in 0.2 s, settle 0.05 s and hold 0.2 s, shorter
# than planned to keep the test short). Named by axis and magnitude: rx20 ... tx0.5.
"$CAL" --plan --format csv > "plan.csv"
check "--plan csv: exit 0" test $? -eq 0
check "--plan csv: the header" test "$(head -n 1 plan.csv)" = \
  "axis,magnitude,unit,regime,duration_s,pads_open_s,hold_s,determines"
short="--colour grey --approach-s 0.05 --grasp-s 0.2 --settle-s 0.05 --hold-s 0.2 -j 1 -q"
set --
while IFS=, read -r axis mag unit regime dur rest; do
  [ "$axis" = "axis" ] && continue
  "$SIM" $short --out "$axis$mag" --object sphere --motion "$axis" --magnitude "$mag" \
    --regime "$regime" --motion-s "$dur" || { echo "FAIL tacse3-sim $axis $mag"; exit 1; }
  set -- "$@" "$axis$mag"
done < "plan.csv"
check "--plan: six motions" test $# -eq 6
plan_set="$*"

# The plan without any one line is refused before the fit, naming what to record; nothing is
# written.
for drop in $plan_set; do
  rest=""
  for r in $plan_set; do [ "$r" = "$drop" ] || rest="$rest $r"; done
  # shellcheck disable=SC2086
  "$CAL" $rest -q --out "drop.toml" > /dev/null 2> "e0"
  check "plan without $drop: exit 1" test $? -eq 1
  case "$drop" in
    rx*) what="a rotation about x" ;;
    ry*) what="a rotation about y" ;;
    rz*) what="a rotation about z" ;;
    tx0.5) what="a translation along x or y of 0.2-1.0 mm without rotation" ;;
    tx*) what="a translation along x of 1 mm" ;;
    ty*) what="a translation along y of 1 mm" ;;
  esac
  check "plan without $drop: refused" contains "e0" "error: refused: the recordings do not determine"
  check "plan without $drop: names $what" contains "e0" "^  record $what"
  check "plan without $drop: no file" test ! -e "drop.toml"
done

# Only translations: refused before the fit, naming the three missing rotations.
"$CAL" "tx10" "ty10" "tx0.5" -q --out "tr.toml" > /dev/null 2> "e1"
check "only translations: exit 1" test $? -eq 1
for ax in x y z; do
  check "only translations: names the rotation about $ax" contains "e1" "record a rotation about $ax"
done
check "only translations: no file" test ! -e "tr.toml"

# A recording that starts mid-contact: the same torsion without its first 36 frames (approach,
# grasp and settle), so its reference frame holds the contact.
mid=mid
cp -r "rz3" "$mid"
rm -f "$mid/sim_labels.csv"
n=$(($(wc -l < "rz3/frames.csv") - 1))
t0=$(awk -F, 'NR == 38 { print $2 }' "rz3/frames.csv")
for s in left right; do
  rm "$mid/$s"/*.png
  i=36
  while [ $i -lt $n ]; do
    cp "rz3/$s/$(printf '%06d' $i).png" "$mid/$s/$(printf '%06d' $((i - 36))).png"
    i=$((i + 1))
  done
done
awk -F, 'NR == 1 { print; next } NR >= 38 { printf "%d,%s\n", NR - 38, $2 }' \
  "rz3/frames.csv" > "$mid/frames.csv"
awk -F, -v t0="$t0" 'NR == 1 || $1 >= t0' "rz3/truth.csv" > "$mid/truth.csv"
"$CAL" "$mid" -q --force --out "mid.toml" > /dev/null 2> "e2"
check "mid-contact: exit 1" test $? -eq 1
check "mid-contact: says so and what to do" contains "e2" \
  "$mid: no contact forms before the motion starts (frame [0-9]*): the recording starts mid-contact"
check "mid-contact: asks for open pads" contains "e2" "record frames with the pads open first"
check "mid-contact: no file" test ! -e "mid.toml"

# --check: the committed simulator calibration explains these recordings; the same with its
# joint-fusion rotation and translation scales tripled reads every motion three times over and
# explains none of them.
"$CAL" --check "$COMMITTED" "rx20" "tx10" > "o3" 2> "e3"
check "--check committed: exit 0" test $? -eq 0
check "--check committed: the report" contains "o3" "check: 2 of 2 recording(s) explained"
sed -e 's/^rotation_scale = \[1.097, 1.097, 0.8305\]/rotation_scale = [3.291, 3.291, 2.4915]/' \
  -e 's/^translation_scale = \[1.003, 0.9843, 1.0\]/translation_scale = [3.009, 2.9529, 3.0]/' \
  "$COMMITTED" > "x3.toml"
check "the tripled file differs in two lines" test "$(diff "$COMMITTED" x3.toml | grep -c '^>')" -eq 2
"$CAL" --check "x3.toml" "rx20" "tx10" > "o4" 2> "e4"
check "--check gains x3: exit 1" test $? -eq 1
check "--check gains x3: names rx20" contains "e4" "not explained by x3.toml: rx20: rotation off by"
check "--check gains x3: names tx10" contains "e4" "not explained by x3.toml: tx10: translation off by"
"$CAL" --check "x3.toml" "rx20" --out "o.toml" > /dev/null 2>&1
check "--check with --out: usage error 2" test $? -eq 2
"$CAL" "rx20" > /dev/null 2>&1
check "neither --out nor --check: usage error 2" test $? -eq 2

# The covering set: fitted and self-checked. The plan's set explains itself on the simulator:
# exit 0, and the written file passes --check on the same set. (An unexplained recording's
# error line and the unwritten file are checked with the tripled gains above and the bound below.)
"$CAL" "$@" --out "fit.toml" > "o5" 2> "e5"
rc=$?
check "fit: a check row per recording" test "$(grep -c '^  .*  \(ok\|FAILED\)$' "o5")" -eq 6
check "fit: the plan's set covers every rule" test "$(grep -c 'do not determine' "e5")" -eq 0
check "fit: reports the fitted pitch" contains "o5" "^pixel pitch: fitted 0.0[0-9]* mm/px .* from 1 stick translation(s); replaces the recordings' rig.pixel_pitch_mm 0.1 (fitted / claimed "
grep 'FAILED$' "o5"
check "fit: every recording explained" test "$(grep -c 'FAILED$' "o5")" -eq 0
check "fit: the box's fit passes, so the file keeps the box" \
  contains "o5" "^working image: 2x2 box (antialias_filter 0)"
check "fit: explained, exit 0" test $rc -eq 0
check "fit: file written" test -s "fit.toml"
"$CAL" --check "fit.toml" "$@" -q > /dev/null 2>&1
check "fit: --check of the written file exits 0" test $? -eq 0

# The sanitizer build stops here (TACSE3_CALIBRATE_TEST_ONE_FIT, set by tests/tools/CMakeLists.txt):
# the two fits below repeat the one above on a changed truth, and a fit there costs minutes.
if [ -n "${TACSE3_CALIBRATE_TEST_ONE_FIT:-}" ]; then
  [ "$fails" -eq 0 ] || { echo "$fails check(s) failed"; exit 1; }
  echo "all calibrate checks passed (the bound and --force fits not run)"
  exit 0
fi

# A truth that says the translation along x was 20 times what it was: its translation scale
# stops at its bound, which is an error naming the field and the recording; nothing is written.
# --force writes the file anyway, with the warnings.
big=txbig
cp -r "tx10" "$big"
awk -F, 'BEGIN { OFS = "," } NR > 1 { $6 = sprintf("%.12f", $6 * 20) } { print }' \
  "tx10/truth.csv" > "$big/truth.csv"
"$CAL" "rx20" "ry20" "rz3" "$big" "ty10" "tx0.5" -q --out "big.toml" > /dev/null 2> "e6"
check "bound: exit 1" test $? -eq 1
check "bound: names the field" contains "e6" "error: translation_scale x: the fit asks for"
check "bound: names the recording" contains "e6" "driven by $big"
check "bound: not written" contains "e6" "not written: big.toml"
check "bound: no file" test ! -e "big.toml"
"$CAL" "rx20" "ry20" "rz3" "$big" "ty10" "tx0.5" --force --out "big.toml" > "o7" 2> "e7"
check "--force: exit 0" test $? -eq 0
check "--force: file written" test -s "big.toml"
check "--force: the bound is a warning" contains "e7" "warning: translation_scale x: the fit asks for"
check "--force: says not to install it" contains "e7" "fails its check: do not install it"
# The file holds the pitch the report says was fitted (mm/px in the report, m in the file).
fitted=$(sed -n 's/^pixel pitch: fitted \([0-9.e+-]*\) mm\/px .*/\1/p' "o7")
in_file=$(sed -n 's/^pixel_pitch_m = \([0-9.e+-]*\)$/\1/p' "big.toml" | head -n 1)
check "--force: the file holds the fitted pitch ($fitted mm, $in_file m)" \
  awk -v a="$fitted" -v b="$in_file" 'BEGIN { d = a * 1e-3 - b; exit !(a > 0 && d * d < (1e-3 * b) ^ 2) }' 

[ "$fails" -eq 0 ] || { echo "$fails check(s) failed"; exit 1; }
echo "all calibrate checks passed"
