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
COMMITTED="$(dirname "$0")/../../tools/replay/data/sim-calibration.toml"
T="${TMPDIR:-/tmp}/tacse3_calibrate_test.$$"
mkdir -p "$T"
trap 'rm -rf "$T"' EXIT
fails=0
check() {  # check NAME CONDITION...
  name="$1"; shift
  if "$@"; then echo "ok   $name"; else echo "FAIL $name"; fails=$((fails + 1)); fi
}
contains() { grep -q -- "$2" "$1"; }  # a basic regular expression

# A set that covers every rule: slides about x and y and along x and y, a stick torsion; each
# starts with the pads open (0.05 s), closes in 0.2 s, settles 0.05 s and holds 0.2 s.
short="--colour grey --approach-s 0.05 --grasp-s 0.2 --settle-s 0.05 --hold-s 0.2 -j 1 -q"
for m in "rx 20" "ry 20" "rz 3" "tx 3" "ty 3"; do
  set -- $m
  "$SIM" $short --out "$T/$1$2" --object sphere --motion "$1" --magnitude "$2" ||
    { echo "FAIL tacse3-sim $m"; exit 1; }
done
set -- "$T/rx20" "$T/ry20" "$T/rz3" "$T/tx3" "$T/ty3"

# Only translations: refused before the fit, naming the three missing rotations.
"$CAL" "$T/tx3" "$T/ty3" -q --out "$T/tr.toml" > /dev/null 2> "$T/e1"
check "only translations: exit 1" test $? -eq 1
for ax in x y z; do
  check "only translations: names the rotation about $ax" contains "$T/e1" "record a rotation about $ax"
done
check "only translations: no file" test ! -e "$T/tr.toml"

# A recording that starts mid-contact: the same torsion without its first 36 frames (approach,
# grasp and settle), so its reference frame holds the contact.
mid="$T/mid"
cp -r "$T/rz3" "$mid"
rm -f "$mid/sim_labels.csv"
n=$(($(wc -l < "$T/rz3/frames.csv") - 1))
t0=$(awk -F, 'NR == 38 { print $2 }' "$T/rz3/frames.csv")
for s in left right; do
  rm "$mid/$s"/*.png
  i=36
  while [ $i -lt $n ]; do
    cp "$T/rz3/$s/$(printf '%06d' $i).png" "$mid/$s/$(printf '%06d' $((i - 36))).png"
    i=$((i + 1))
  done
done
awk -F, 'NR == 1 { print; next } NR >= 38 { printf "%d,%s\n", NR - 38, $2 }' \
  "$T/rz3/frames.csv" > "$mid/frames.csv"
awk -F, -v t0="$t0" 'NR == 1 || $1 >= t0' "$T/rz3/truth.csv" > "$mid/truth.csv"
"$CAL" "$mid" -q --force --out "$T/mid.toml" > /dev/null 2> "$T/e2"
check "mid-contact: exit 1" test $? -eq 1
check "mid-contact: says so and what to do" contains "$T/e2" \
  "$mid: no contact forms before the motion starts (frame [0-9]*): the recording starts mid-contact"
check "mid-contact: asks for open pads" contains "$T/e2" "record frames with the pads open first"
check "mid-contact: no file" test ! -e "$T/mid.toml"

# --check: the committed simulator calibration explains these recordings; the same with both
# proxy gains tripled reads every motion three times over and explains none of them.
"$CAL" --check "$COMMITTED" "$T/rx20" "$T/tx3" > "$T/o3" 2> "$T/e3"
check "--check committed: exit 0" test $? -eq 0
check "--check committed: the report" contains "$T/o3" "check: 2 of 2 recording(s) explained"
sed -e 's/^c_velocity = .*/c_velocity = 0.0157/' -e 's/^c_displacement = .*/c_displacement = 0.000616/' \
  "$COMMITTED" > "$T/x3.toml"
"$CAL" --check "$T/x3.toml" "$T/rx20" "$T/tx3" > "$T/o4" 2> "$T/e4"
check "--check gains x3: exit 1" test $? -eq 1
check "--check gains x3: names rx20" contains "$T/e4" "not explained by $T/x3.toml: $T/rx20: rotation off by"
check "--check gains x3: names tx3" contains "$T/e4" "not explained by $T/x3.toml: $T/tx3: translation off by"
"$CAL" --check "$T/x3.toml" "$T/rx20" --out "$T/o.toml" > /dev/null 2>&1
check "--check with --out: usage error 2" test $? -eq 2
"$CAL" "$T/rx20" > /dev/null 2>&1
check "neither --out nor --check: usage error 2" test $? -eq 2

# The covering set: fitted, self-checked, written; the file passes --check on the same set.
"$CAL" "$@" --out "$T/fit.toml" > "$T/o5" 2> "$T/e5"
rc=$?
check "fit: exit 0" test $rc -eq 0
[ $rc -eq 0 ] || cat "$T/e5"
check "fit: file written" test -s "$T/fit.toml"
check "fit: the report has the check" contains "$T/o5" "check: 5 of 5 recording(s) explained"
"$CAL" --check "$T/fit.toml" "$@" -q > /dev/null 2>&1
check "fit: --check of the written file exits 0" test $? -eq 0

# A truth that says the translation along x was 20 times what it was: its translation scale
# stops at its bound, which is an error naming the field and the recording; nothing is written.
# --force writes the file anyway, with the warnings.
big="$T/txbig"
cp -r "$T/tx3" "$big"
awk -F, 'BEGIN { OFS = "," } NR > 1 { $6 = sprintf("%.12f", $6 * 20) } { print }' \
  "$T/tx3/truth.csv" > "$big/truth.csv"
"$CAL" "$T/rx20" "$T/ry20" "$T/rz3" "$big" "$T/ty3" -q --out "$T/big.toml" > /dev/null 2> "$T/e6"
check "bound: exit 1" test $? -eq 1
check "bound: names the field" contains "$T/e6" "error: translation_scale x: the fit asks for"
check "bound: names the recording" contains "$T/e6" "driven by $big"
check "bound: not written" contains "$T/e6" "not written: $T/big.toml"
check "bound: no file" test ! -e "$T/big.toml"
"$CAL" "$T/rx20" "$T/ry20" "$T/rz3" "$big" "$T/ty3" -q --force --out "$T/big.toml" > /dev/null \
  2> "$T/e7"
check "--force: exit 0" test $? -eq 0
check "--force: file written" test -s "$T/big.toml"
check "--force: the bound is a warning" contains "$T/e7" "warning: translation_scale x: the fit asks for"
check "--force: says not to install it" contains "$T/e7" "fails its check: do not install it"

[ "$fails" -eq 0 ] || { echo "$fails check(s) failed"; exit 1; }
echo "all calibrate checks passed"
