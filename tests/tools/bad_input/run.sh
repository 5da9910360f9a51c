#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The bad-input table (cases.txt): every program, fed each class of broken file and argument,
# must exit with the listed code, say the listed fragment on stderr, return within 20 s (a FIFO
# or device is refused, never waited on) and leave nothing at @OUT@ (no partial output).
#
# Usage: run.sh BUILD_DIR [--probe]
#   --probe: print what each case does (exit code, first stderr line) instead of checking.
# Placeholders in cases.txt are the fixtures made below (@REC@ a good recording, ...); @OUT@ is a
# fresh output path per case.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
src="$(cd "$here/../../.." && pwd)"
B="${1:?usage: run.sh BUILD_DIR [--probe]}"
probe="${2:-}"
T=$(mktemp -d "${TMPDIR:-/tmp}/tacse3-bad-input.XXXXXX")
trap 'rm -rf "$T"' EXIT

declare -A prog=(
  [tacse3d]="$B/firmware/tacse3d"
  [replay]="$B/tools/replay/tacse3-replay"
  [calibrate]="$B/tools/calibrate/tacse3-calibrate"
  [sim]="$B/tools/sim/tacse3-sim"
  [bench]="$B/tools/bench_accuracy/tacse3-bench-accuracy"
  [canmon]="$B/tools/canmon/tacse3-canmon"
  [ctl]="$B/tools/ctl/tacse3-ctl"
  [dbcgen]="$B/tools/dbcgen/tacse3-dbcgen"
  [calkeys]="$B/tools/calkeys/tacse3-calkeys"
  [demo]="$B/tools/demo/tacse3-demo"
)
for p in "${!prog[@]}"; do
  [ -x "${prog[$p]}" ] || { echo "FAIL: ${prog[$p]} not built" >&2; exit 1; }
done

# --- fixtures ---------------------------------------------------------------------------------
F="$T/f"
mkdir -p "$F/dir" "$F/out" "$F/dir.svg"
ln -s /dev/full "$F/full.png"
"${prog[sim]}" -q --out "$F/rec" --object sphere --motion rz --magnitude 2 --colour grey \
  --approach-s 0.02 --grasp-s 0.1 --settle-s 0.02 --hold-s 0.02 ||
  { echo "FAIL: tacse3-sim could not make the fixture recording" >&2; exit 1; }
mkfifo "$F/fifo"
truncate -s 200M "$F/big"                      # sparse: too large for every reader
printf 'not toml [\n' >"$F/syntax.toml"
: >"$F/empty"
cal() { printf 'format = "tacse3-calibration"\nversion = 1\n%b' "$1"; }
cal '[left]\nc_velocty = 1.0\n' >"$F/cal_unknown.toml"
cal '[left]\nc_velocity = -1.0\n' >"$F/cal_range.toml"
cal '[left]\nc_velocity = "fast"\n' >"$F/cal_type.toml"
cal '\xc3\xa9 = 1\n' >"$F/cal_nonascii.toml"
head -c 30 "$src/packaging/calibration.toml" >"$F/cal_truncated.toml"
board_sim="$src/boards/sim/board.toml"
sed 's/^fps = 120/fps = 100000/' "$board_sim" >"$F/board_range.toml"
sed 's/^name = "sim"/nmae = "sim"/' "$board_sim" >"$F/board_unknown.toml"
head -c 200 "$board_sim" >"$F/board_truncated.toml"
printf '(1.000000) can0 021#D202964900005948\n(garbage\n' >"$F/can_bad.log"
printf '(1.000000) can0 021#D202964900005948\n(1.008333) can0 021#D2029' >"$F/can_short.log"  # cut mid-frame
# Recordings broken one file at a time.
mkrec() { rm -rf "${F:?}/${1:?}"; cp -r "$F/rec" "$F/$1"; }
mkrec rec_nojson; rm "$F/rec_nojson/recording.json"
mkrec rec_badjson; printf '{"format": "tacse3-recording", "version": 1,' >"$F/rec_badjson/recording.json"
mkrec rec_jsonrange; sed -i 's/"width": 320/"width": -5/' "$F/rec_jsonrange/recording.json"
mkrec rec_nocsv; rm "$F/rec_nocsv/frames.csv"
mkrec rec_badcsv; printf 'index,t_ns\n0,100\n1,50\n' >"$F/rec_badcsv/frames.csv"
mkrec rec_csvdir; rm "$F/rec_csvdir/frames.csv"; mkdir "$F/rec_csvdir/frames.csv"
mkrec rec_csvfifo; rm "$F/rec_csvfifo/frames.csv"; mkfifo "$F/rec_csvfifo/frames.csv"
mkrec rec_csvbig; truncate -s 200M "$F/rec_csvbig/frames.csv"
mkrec rec_nopng; rm "$F/rec_nopng/left/000003.png"
mkrec rec_badpng; head -c 100 "$F/rec/left/000003.png" >"$F/rec_badpng/left/000003.png"
mkrec rec_pngsize   # a whole 16x16 grey PNG where a 320x240 frame belongs
python3 -c '
import struct, sys, zlib
def chunk(k, d): return struct.pack(">I", len(d)) + k + d + struct.pack(">I", zlib.crc32(k + d))
rows = b"".join(b"\0" + bytes(16) for _ in range(16))
sys.stdout.buffer.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 16, 8, 0, 0, 0, 0))
                        + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))' >"$F/rec_pngsize/left/000000.png"
mkrec rec_notruth; rm -f "$F/rec_notruth/truth.csv"
mkrec rec_badtruth; printf 't_ns,qw,qx,qy,qz,px,py,pz\n0,0.5,0,0,0,0,0,0\n' >"$F/rec_badtruth/truth.csv"

# --- the table --------------------------------------------------------------------------------
subst() {
  local s="$1"
  s="${s//@OUT@/$out}"
  s="${s//@F@/$F}"
  s="${s//@SRC@/$src}"
  printf '%s' "$s"
}
n=0 fails=0
while IFS='|' read -r name p args code fragment; do
  name="${name//[[:space:]]/}"
  [ -z "$name" ] || [ "${name:0:1}" = "#" ] && continue
  p="${p//[[:space:]]/}"; code="${code//[[:space:]]/}"
  fragment="${fragment#"${fragment%%[![:space:]]*}"}"; fragment="${fragment%"${fragment##*[![:space:]]}"}"
  out="$F/out/$name"
  args="$(subst "$args")"; fragment="$(subst "$fragment")"
  # Arguments split at spaces; '' is an empty argument.
  argv=()
  eval "argv=($args)"
  timeout 20 "${prog[$p]}" "${argv[@]}" </dev/null >"$T/stdout" 2>"$T/stderr"
  rc=$?
  n=$((n + 1))
  if [ "$probe" = --probe ]; then
    printf '%-28s %-9s rc=%-3s %s\n' "$name" "$p" "$rc" "$(grep -v '^\s*$' "$T/stderr" | head -1 | cut -c1-150)"
    continue
  fi
  why=""
  [ "$rc" = 124 ] && why="did not return within 20 s"
  [ -z "$why" ] && [ "$rc" != "$code" ] && why="exit $rc, expected $code"
  [ -z "$why" ] && ! grep -qF -- "$fragment" "$T/stderr" && why="stderr lacks '$fragment'"
  [ -z "$why" ] && [ -e "$out" ] && why="left a partial output at @OUT@"
  if [ -n "$why" ]; then
    fails=$((fails + 1))
    echo "FAIL $name ($p $args): $why"
    sed 's/^/    | /' "$T/stderr" | head -5
  else
    echo "ok   $name"
  fi
done <"$here/cases.txt"
[ "$probe" = --probe ] && exit 0
echo "bad-input table: $n cases, $((n - fails)) passed, $fails failed"
[ "$n" -gt 0 ] && [ "$fails" -eq 0 ]
