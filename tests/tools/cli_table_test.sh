#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The command-line contract every tacse3 program keeps (docs/troubleshooting.md):
#   an unknown option           -> exit 2, a message on stderr pointing at --help, nothing on
#                                  stdout
#   --help                      -> exit 0, the usage on stdout, and nothing run (no output files,
#                                  no demo, no waiting on a bus)
#   --version                   -> exit 0, exactly "NAME VERSION" on stdout
# Usage: cli_table_test.sh VERSION PROGRAM...   (paths of the built programs)
set -u
VERSION="$1"
shift
T="${TMPDIR:-/tmp}/tacse3_cli_table.$$"
mkdir -p "$T"
trap 'rm -rf "$T"' EXIT
fails=0
check() {  # check WHAT CONDITION...
  what="$1"; shift
  if "$@"; then echo "ok   $what"; else echo "FAIL $what"; fails=$((fails + 1)); fi
}
for prog in "$@"; do
  prog="$(cd "$(dirname "$prog")" && pwd)/$(basename "$prog")"
  name=$(basename "$prog")
  # Run in an empty folder: --help must create nothing there.
  mkdir -p "$T/$name"
  (cd "$T/$name" && timeout 20 "$prog" --no-such-option > "$T/$name.out" 2> "$T/$name.err")
  rc=$?
  check "$name: an unknown option exits 2 (got $rc)" test "$rc" -eq 2
  # CLI11 reports a missing required option before an unknown one: either is a usage error, and
  # the message points at --help.
  check "$name: the usage error is explained on stderr" grep -q -- "--help" "$T/$name.err"
  check "$name: nothing on stdout after a usage error" test ! -s "$T/$name.out"

  (cd "$T/$name" && timeout 20 "$prog" --help > "$T/$name.out" 2> "$T/$name.err")
  rc=$?
  check "$name: --help exits 0 (got $rc)" test "$rc" -eq 0
  check "$name: --help prints the usage" grep -qi "usage" "$T/$name.out"
  check "$name: --help lists --version" grep -q -- "--version" "$T/$name.out"
  check "$name: --help writes nothing to stderr" test ! -s "$T/$name.err"
  check "$name: --help creates no files" test -z "$(ls -A "$T/$name")"

  (cd "$T/$name" && timeout 20 "$prog" --version > "$T/$name.out" 2> "$T/$name.err")
  rc=$?
  check "$name: --version exits 0 (got $rc)" test "$rc" -eq 0
  check "$name: --version prints \"$name $VERSION\"" test "$(cat "$T/$name.out")" = "$name $VERSION"
done
# The demo's run prints one "estimated (x, y, z) deg" line per case; --help must not run them.
for prog in "$@"; do
  case "$(basename "$prog")" in
    tacse3-demo)
      "$prog" --help > "$T/demo.out" 2>&1
      check "tacse3-demo --help does not run the demo" sh -c "! grep -q 'estimated (' '$T/demo.out'" ;;
  esac
done
echo "$fails failure(s)"
test "$fails" -eq 0
