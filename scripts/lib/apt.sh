# SPDX-License-Identifier: Apache-2.0
# tacse3: apt helpers sourced by scripts/setup.sh and tests/vm/setup-host.sh (expects $SUDO).
# shellcheck shell=bash

# apt_update WHO: a Debian mirror mid-sync can serve one index with the wrong size (seen: the
# armhf security list). Retry with a pause; if one list still fails, continue with what apt has:
# the install that follows then fails clearly if a package is truly missing.
apt_update() {
  local who=$1 attempt
  for attempt in 1 2 3 4; do
    if $SUDO apt-get update -o Acquire::Retries=5; then return 0; fi
    echo "$who: apt-get update failed (attempt $attempt); retrying in $((attempt * 15)) s" >&2
    sleep $((attempt * 15))
  done
  echo "$who: apt-get update still reports errors; continuing with the package lists it got" >&2
}
