#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# The generated bash completion (cmake/tacse3_completion.cmake): for every program, completing
# "--" in bash offers exactly the long options its --help names, and tacse3-ctl's first word
# offers its subcommands.
# Usage: completion_test.sh COMPLETION_DIR PROGRAM...
set -u
DIR="$1"
shift
fails=0
check() {  # check WHAT CONDITION...
  what="$1"; shift
  if "$@"; then echo "ok   $what"; else echo "FAIL $what"; fails=$((fails + 1)); fi
}
complete_words() {  # complete_words NAME WORD... -> the candidates for the last word, sorted
  local name="$1"; shift
  COMP_WORDS=("$name" "$@")
  COMP_CWORD=$#
  COMPREPLY=()
  "$(complete -p "$name" | sed -n 's/.*-F \([^ ]*\) .*/\1/p')"
  printf '%s\n' "${COMPREPLY[@]}" | sort
}
for prog in "$@"; do
  name=$(basename "$prog")
  check "$name: a completion file" test -f "$DIR/$name"
  [ -f "$DIR/$name" ] || continue
  # shellcheck source=/dev/null
  . "$DIR/$name"
  want=$("$prog" --help | grep -o -- '--[a-z][a-z0-9-]*' | sort -u)
  have=$(complete_words "$name" --)
  check "$name: '--' completes to the options of --help" test "$want" = "$have"
  check "$name: --help and --version are among them" \
    sh -c "printf '%s\n' \"\$1\" | grep -qx -- --help && printf '%s\n' \"\$1\" | grep -qx -- --version" _ "$have"
  case "$name" in
    tacse3-ctl)
      check "tacse3-ctl: 'ta' completes to the subcommand tare" test "$(complete_words "$name" ta)" = tare ;;
  esac
done
echo "$fails failure(s)"
test "$fails" -eq 0
