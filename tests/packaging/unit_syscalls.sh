#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Prints the system calls a unit's SystemCallFilter= lines allow, one a line, with the sets
# (@system-service, ...) expanded by the installed systemd-analyze, so the list is the one that
# systemd version enforces. A first line without "~" is the allow list; "~" lines remove from it.
#
# Usage: tests/packaging/unit_syscalls.sh UNIT_FILE
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 UNIT_FILE" >&2; exit 2; }
command -v systemd-analyze >/dev/null || { echo "$0: systemd-analyze not installed (Debian package systemd)" >&2; exit 1; }

expand() { # expand <@set|name>: the system calls, sets expanded recursively
  case "$1" in
    @*)
      local out
      out=$(systemd-analyze syscall-filter "$1") || { echo "$0: unknown system-call set $1" >&2; exit 1; }
      awk 'NR > 1 && $1 !~ /^#/ && NF { print $1 }' <<<"$out" | while read -r s; do expand "$s"; done
      ;;
    *) echo "$1" ;;
  esac
}

allow="" deny=""
while IFS= read -r value; do
  for word in $value; do
    case "$word" in
      '~'*) deny+=" ${word#\~}" ;;
      *) [ -z "$deny" ] || { echo "$0: allow entries after a ~ line are not handled" >&2; exit 1; }
         allow+=" $word" ;;
    esac
  done
done < <(sed -n 's/^SystemCallFilter=//p' "$1")
[ -n "$allow" ] || { echo "$0: $1 has no SystemCallFilter= allow list" >&2; exit 1; }
# shellcheck disable=SC2086  # word lists on purpose
comm -23 <(for s in $allow; do expand "$s"; done | sort -u) <(for s in $deny; do expand "$s"; done | sort -u)
