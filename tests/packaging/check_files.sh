#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 packaging tests: the unit, sysusers, udev, networkd and maintainer files, checked offline.
#
# Usage: tests/packaging/check_files.sh <case>     (cases: the functions named case_*; "all" runs all)
# Each case prints what it checked and exits non-zero with the file and line of the first problem.
set -euo pipefail
SRC="$(cd "$(dirname "$0")/../.." && pwd)"
PKG="$SRC/packaging"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# systemd-analyze verify on the unit (ExecStart pointed at an existing binary, since the daemon is
# not installed here): any message is a failure, as verify reports unknown keys only as warnings.
# Then the settings the service contract needs, by value.
case_unit() {
  command -v systemd-analyze >/dev/null || fail "systemd-analyze not installed (Debian package systemd)"
  mkdir -p "$TMP/unit"
  sed 's#^ExecStart=/usr/bin/tacse3d #ExecStart=/bin/true #' "$PKG/tacse3d.service" >"$TMP/unit/tacse3d.service"
  grep -q '^ExecStart=/bin/true ' "$TMP/unit/tacse3d.service" || fail "tacse3d.service: no ExecStart=/usr/bin/tacse3d line"
  local out want
  out=$(cd "$TMP/unit" && SYSTEMD_LOG_LEVEL=warning systemd-analyze verify ./tacse3d.service 2>&1) ||
    fail "systemd-analyze verify: $out"
  [ -z "$out" ] || fail "systemd-analyze verify reported: $out"
  # The live view's drop-in (not enabled by the package) verifies with the unit.
  mkdir -p "$TMP/unit/tacse3d.service.d"
  cp "$PKG/viewer-network.conf" "$TMP/unit/tacse3d.service.d/"
  out=$(cd "$TMP/unit" && SYSTEMD_LOG_LEVEL=warning systemd-analyze verify ./tacse3d.service 2>&1) ||
    fail "systemd-analyze verify with viewer-network.conf: $out"
  [ -z "$out" ] || fail "systemd-analyze verify with viewer-network.conf reported: $out"
  for want in 'RestrictAddressFamilies=AF_INET' 'IPAddressAllow=localhost'; do
    grep -qxF -- "$want" "$PKG/viewer-network.conf" || fail "viewer-network.conf lacks '$want'"
  done
  rm -r "$TMP/unit/tacse3d.service.d"
  local n=0
  while IFS= read -r want; do
    grep -qxF -- "$want" "$PKG/tacse3d.service" || fail "tacse3d.service lacks the line '$want'"
    n=$((n + 1))
  done <<'EOF'
Type=notify
NotifyAccess=main
WatchdogSec=2s
EnvironmentFile=-/etc/tacse3/tacse3d.conf
ExecStart=/usr/bin/tacse3d --board ${TACSE3_BOARD} --calibration ${TACSE3_CALIBRATION} $TACSE3_ARGS
ExecReload=/bin/kill -HUP $MAINPID
StandardOutput=null
Restart=on-failure
User=tacse3
SupplementaryGroups=video gpio
AmbientCapabilities=CAP_SYS_NICE CAP_IPC_LOCK
CapabilityBoundingSet=CAP_SYS_NICE CAP_IPC_LOCK
NoNewPrivileges=yes
ProtectSystem=strict
ProtectHome=yes
PrivateTmp=yes
LimitRTPRIO=99
LimitMEMLOCK=infinity
RestrictAddressFamilies=AF_CAN AF_UNIX AF_NETLINK
DevicePolicy=closed
SystemCallFilter=@system-service
SystemCallFilter=~@privileged
IPAddressDeny=any
ProtectProc=invisible
ProcSubset=pid
UMask=0077
StateDirectory=tacse3
WantedBy=multi-user.target
EOF
  # The unit's defaults and the shipped conffile must name the same board and calibration.
  local board cal
  board=$(sed -n 's/^TACSE3_BOARD=//p' "$PKG/tacse3d.conf")
  cal=$(sed -n 's/^TACSE3_CALIBRATION=//p' "$PKG/tacse3d.conf")
  grep -q "^Environment=TACSE3_BOARD=$board TACSE3_CALIBRATION=$cal$" "$PKG/tacse3d.service" ||
    fail "tacse3d.service Environment= defaults differ from tacse3d.conf (board '$board', calibration '$cal')"
  [ -f "$SRC/boards/$board/board.toml" ] || fail "tacse3d.conf: default board '$board' has no boards/$board/board.toml"
  # The exposure figure systemd-analyze gives the unit as shipped (0 = fully locked, 10 = none).
  local exposure
  out=$(cd "$TMP/unit" && systemd-analyze security --offline=true --no-pager ./tacse3d.service 2>&1) ||
    fail "systemd-analyze security: $out"
  exposure=$(sed -n 's/.*Overall exposure level for tacse3d.service: \([0-9.]*\).*/\1/p' <<<"$out")
  [ -n "$exposure" ] || fail "systemd-analyze security printed no exposure level: $out"
  awk -v e="$exposure" 'BEGIN { exit !(e <= 2.0) }' ||
    fail "systemd-analyze security rates tacse3d.service $exposure, above 2.0: $(grep '✗' <<<"$out")"
  echo "unit: systemd-analyze verify clean; exposure $exposure (<= 2.0); $n required settings present; default board $board"
}

# systemd-sysusers into an empty root: tacse3 exists, is in video and gpio, and gpio is created.
case_sysusers() {
  command -v systemd-sysusers >/dev/null || fail "systemd-sysusers not installed (Debian package systemd)"
  local root="$TMP/root"
  mkdir -p "$root/etc" "$root/usr/lib/sysusers.d"
  printf 'root:x:0:0:root:/root:/bin/bash\n' >"$root/etc/passwd"
  printf 'root:x:0:\nvideo:x:44:\n' >"$root/etc/group"
  : >"$root/etc/shadow"
  : >"$root/etc/gshadow"
  cp "$PKG/tacse3d.sysusers" "$root/usr/lib/sysusers.d/tacse3d.conf"
  systemd-sysusers --root="$root" >/dev/null 2>"$TMP/sysusers.err" || fail "systemd-sysusers: $(cat "$TMP/sysusers.err")"
  grep -q '^tacse3:x:[0-9]*:[0-9]*:tacse3 gripper firmware daemon:/var/lib/tacse3:/usr/sbin/nologin$' "$root/etc/passwd" ||
    fail "no tacse3 system user in passwd: $(cat "$root/etc/passwd")"
  local uid
  uid=$(awk -F: '$1 == "tacse3" { print $3 }' "$root/etc/passwd")
  if [ "$uid" -le 0 ] || [ "$uid" -ge 1000 ]; then fail "tacse3 uid $uid is not a system uid (1..999)"; fi
  grep -q '^video:x:44:tacse3$' "$root/etc/group" || fail "tacse3 not added to the existing video group: $(grep ^video "$root/etc/group")"
  grep -q '^gpio:x:[0-9]*:tacse3$' "$root/etc/group" || fail "gpio group not created with tacse3 in it: $(cat "$root/etc/group")"
  echo "sysusers: tacse3 uid $uid, in video (existing, gid 44) and gpio (created)"
}

# udev rules: bookworm's udevadm has no "verify" (systemd 253+), so a parser of the rules syntax
# (udev(7)): comma-separated KEY[{attr}] OP "value" pairs, match operators only on match keys,
# assignment operators only on assignment keys; then the tacse3 specifics.
check_udev_syntax() {
  local file="$1"
  awk -v F="$file" '
    function die(msg) { printf "FAIL: %s:%d: %s\n", F, NR, msg > "/dev/stderr"; bad = 1; exit 1 }
    /^[ \t]*(#|$)/ { next }
    /\\$/ { die("line continuation not expected") }
    {
      line = $0; n = 0
      while (length(line) > 0) {
        if (!match(line, /^[ \t]*([A-Z_]+)(\{[^}]+\})?[ \t]*(==|!=|\+=|-=|:=|=)[ \t]*"[^"]*"[ \t]*(,|$)/))
          die("cannot parse at: " line)
        pair = substr(line, RSTART, RLENGTH); line = substr(line, RSTART + RLENGTH)
        match(pair, /[A-Z_]+/); key = substr(pair, RSTART, RLENGTH)
        match(pair, /(==|!=|\+=|-=|:=|=)/); op = substr(pair, RSTART, RLENGTH)
        ismatch = (op == "==" || op == "!=")
        if (key ~ /^(ACTION|DEVPATH|KERNEL|KERNELS|NAME|SUBSYSTEM|SUBSYSTEMS|DRIVER|DRIVERS|ATTR|ATTRS|SYSCTL|TAG|TAGS|TEST|PROGRAM|RESULT|ENV|CONST|SYMLINK)$/ && ismatch) { n++; continue }
        if (key ~ /^(NAME|SYMLINK|OWNER|GROUP|MODE|SECLABEL|ATTR|SYSCTL|ENV|TAG|RUN|LABEL|GOTO|IMPORT|OPTIONS)$/ && !ismatch) { n++; continue }
        die("key " key " with operator " op " is not valid udev syntax")
      }
      if (n == 0) die("empty rule")
      rules++
    }
    END { if (!bad) print rules }' "$file"
}

case_udev() {
  local n1 n2
  n1=$(check_udev_syntax "$PKG/udev/60-tacse3-gpio.rules") || exit 1
  n2=$(check_udev_syntax "$PKG/udev/61-tacse3-cameras.rules") || exit 1
  [ "$n1" = 1 ] || fail "60-tacse3-gpio.rules: $n1 rules, expected 1"
  [ "$n2" = 2 ] || fail "61-tacse3-cameras.rules: $n2 rules, expected 2 (left, right)"
  grep -q '^SUBSYSTEM=="gpio", KERNEL=="gpiochip\[0-9\]\*", GROUP="gpio", MODE="0660"$' "$PKG/udev/60-tacse3-gpio.rules" ||
    fail "60-tacse3-gpio.rules: gpiochip rule not for group gpio, mode 0660"
  local side
  for side in left right; do
    local upper
    upper=$(tr '[:lower:]' '[:upper:]' <<<"$side")
    grep -E "^SUBSYSTEM==\"video4linux\", .*ATTR\{index\}==\"0\", ATTRS\{serial\}==\"SET-$upper-SERIAL\", SYMLINK\+=\"tacse3-$side\", GROUP=\"video\"" \
      "$PKG/udev/61-tacse3-cameras.rules" >/dev/null || fail "61-tacse3-cameras.rules: no index-0 rule linking tacse3-$side by serial"
  done
  # The parser must refuse what udev refuses (the parser is only worth something if it can fail).
  printf 'SUBSYSTEM="video4linux", SYMLINK+="x"\n' >"$TMP/bad1.rules"
  printf 'SUBSYSTEM=="video4linux" SYMLINK+="x"\n' >"$TMP/bad2.rules"
  printf 'SUBSYSTEM=="video4linux", GROUP=="video"\n' >"$TMP/bad3.rules"
  local bad
  for bad in "$TMP"/bad1.rules "$TMP"/bad2.rules "$TMP"/bad3.rules; do
    if check_udev_syntax "$bad" >/dev/null 2>&1; then fail "udev parser accepted the bad rule $(cat "$bad")"; fi
  done
  echo "udev: 3 rules parse; gpiochip -> gpio 0660; tacse3-left/right by serial on index 0; 3 bad rules refused"
}

# networkd .network files: every section/key is one systemd-networkd knows. The list comes from
# the installed systemd-networkd binary (its configuration parser's "Section.Key" table), so the
# check follows the systemd version the package targets (bookworm: 252).
case_network() {
  local networkd=/lib/systemd/systemd-networkd
  [ -x "$networkd" ] || fail "$networkd not installed (Debian package systemd)"
  strings "$networkd" | grep -E '^[A-Z][A-Za-z]*\.[A-Z][A-Za-z0-9]*$' | sort -u >"$TMP/keys"
  grep -qx 'CAN.BitRate' "$TMP/keys" || fail "could not read the key table from $networkd"
  local f section key value
  for f in "$PKG"/network/*.network; do
    section=""
    while IFS= read -r line; do
      case "$line" in
        '' | '#'*) continue ;;
        '['*']') section=${line#[}; section=${section%]} ;;
        *=*)
          key=${line%%=*}; value=${line#*=}
          [ -n "$section" ] || fail "$f: '$line' outside a section"
          grep -qx "$section.$key" "$TMP/keys" || fail "$f: systemd-networkd has no [$section] $key="
          [ -n "$value" ] || fail "$f: empty value for $key"
          ;;
        *) fail "$f: cannot parse '$line'" ;;
      esac
    done <"$f"
  done
  # Bitrates: the classic file matches the boards that use classic CAN, the FD file the FD board.
  grep -qx 'Name=can0' "$PKG/network/80-tacse3-can0.network" || fail "80-tacse3-can0.network does not match can0"
  grep -qx 'BitRate=500K' "$PKG/network/80-tacse3-can0.network" || fail "80-tacse3-can0.network: not 500 kbit/s"
  if grep -q '^FDMode' "$PKG/network/80-tacse3-can0.network"; then fail "80-tacse3-can0.network must be classic CAN"; fi
  grep -qx 'FDMode=yes' "$PKG/network/80-tacse3-can0-fd.network" || fail "80-tacse3-can0-fd.network: FDMode=yes missing"
  grep -qx 'DataBitRate=2M' "$PKG/network/80-tacse3-can0-fd.network" || fail "80-tacse3-can0-fd.network: DataBitRate=2M missing"
  local board bitrate mode dbr
  for board in "$SRC"/boards/*/board.toml; do
    [ -e "$board" ] || continue
    # [can] keys of the board file (contract B); defaults: classic, 500000.
    bitrate=$(awk '/^\[/{s=$0} s=="[can]" && /^bitrate *=/{gsub(/[^0-9]/,"",$3); print $3}' "$board")
    mode=$(awk '/^\[/{s=$0} s=="[can]" && /^mode *=/{gsub(/"/,"",$3); print $3}' "$board")
    dbr=$(awk '/^\[/{s=$0} s=="[can]" && /^data_bitrate *=/{gsub(/[^0-9]/,"",$3); print $3}' "$board")
    bitrate=${bitrate:-500000}; mode=${mode:-classic}
    if [ "$bitrate" != 500000 ]; then fail "$board: [can] bitrate $bitrate, but the .network files set 500K"; fi
    if [ "$mode" = fd ] && [ "${dbr:-2000000}" != 2000000 ]; then
      fail "$board: [can] data_bitrate $dbr, but 80-tacse3-can0-fd.network sets 2M"
    fi
  done
  echo "network: every key known to $(basename "$networkd") ($(wc -l <"$TMP/keys") keys); bitrates match the board files"
}

# Maintainer scripts: POSIX sh syntax, executable, set -e, and shellcheck when present.
case_scripts() {
  local s
  for s in postinst prerm postrm; do
    [ -x "$PKG/deb/$s" ] || fail "packaging/deb/$s is not executable"
    sh -n "$PKG/deb/$s" || fail "packaging/deb/$s: syntax error"
    grep -qx 'set -e' "$PKG/deb/$s" || fail "packaging/deb/$s: no 'set -e'"
  done
  if command -v shellcheck >/dev/null; then
    shellcheck -s sh "$PKG"/deb/postinst "$PKG"/deb/prerm "$PKG"/deb/postrm || fail "shellcheck on the maintainer scripts"
    shellcheck "$SRC/scripts/package.sh" "$SRC/scripts/package-sdk.sh" "$SRC/scripts/make-sysroot.sh" "$0" \
      "$SRC/tests/packaging/test_sdk.sh" "$SRC/tests/packaging/test_sdk_checker.sh" || fail "shellcheck on the packaging scripts"
  fi
  echo "scripts: postinst, prerm, postrm pass sh -n$(command -v shellcheck >/dev/null && echo ' and shellcheck')"
}

# The soname table: one package per soname, one constraint per package (Depends must not carry
# two different versions of one package).
case_shlibs() {
  awk '/^[^#]/ && NF >= 2 {
         so = $1; pkg = $2; $1 = ""; $2 = ""; c = $0; gsub(/^ +| +$/, "", c)
         if (so in seen) { printf "FAIL: shlibs.txt: %s listed twice\n", so > "/dev/stderr"; exit 1 }
         seen[so] = 1
         if ((pkg in con) && con[pkg] != c) { printf "FAIL: shlibs.txt: %s has constraints \"%s\" and \"%s\"\n", pkg, con[pkg], c > "/dev/stderr"; exit 1 }
         con[pkg] = c; n++
       }
       END { print "shlibs: " n " sonames, one constraint per package" }' "$PKG/deb/shlibs.txt"
}

# The .deb checker itself, on small fake packages built here: a correct one passes, and each kind
# of defect it exists to catch makes it fail with the matching message.
case_checker() {
  command -v dpkg-deb >/dev/null || fail "dpkg-deb not installed"
  command -v aarch64-linux-gnu-gcc >/dev/null || fail "aarch64-linux-gnu-gcc not installed"
  local version stage deb
  version=$(sed -n 's/^project(tacse3 VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt")
  printf 'int main(void) { return 0; }\n' >"$TMP/main.c"
  aarch64-linux-gnu-gcc -O1 -s -o "$TMP/a64" "$TMP/main.c"
  gcc -O1 -s -o "$TMP/host" "$TMP/main.c"
  # make_deb <name> <elf binary> <Depends> [skip path] [extra path] [conffiles to drop]
  make_deb() {
    local name="$1" elf="$2" depends="$3" skip="${4:-}" extra="${5:-}" dropconf="${6:-}"
    stage="$TMP/$name/stage"
    mkdir -p "$stage/DEBIAN"
    local kind path
    while read -r kind path; do
      [ "$path" = "$skip" ] && continue
      mkdir -p "$stage$(dirname "$path")"
      if [ "$kind" = elf ]; then install -m 755 "$elf" "$stage$path"; else echo x >"$stage$path"; fi
      if [ "$kind" = conffile ] && [ "$path" != "$dropconf" ]; then echo "$path" >>"$stage/DEBIAN/conffiles"; fi
    done < <("$SRC/scripts/package.sh" --expected arm64)
    if [ -n "$extra" ]; then mkdir -p "$stage$(dirname "$extra")"; echo x >"$stage$extra"; fi
    printf 'Package: tacse3\nVersion: %s\nArchitecture: arm64\nMaintainer: t <t@t>\nDepends: %s\nDescription: t\n' \
      "$version" "$depends" >"$stage/DEBIAN/control"
    for s in postinst prerm postrm; do printf '#!/bin/sh\nexit 0\n' >"$stage/DEBIAN/$s"; chmod 755 "$stage/DEBIAN/$s"; done
    mkdir -p "$TMP/$name/out"
    deb="$TMP/$name/out/tacse3_${version}_arm64.deb"
    dpkg-deb --root-owner-group -Zgzip -b "$stage" "$deb" >/dev/null
  }
  expect_fail() { # expect_fail <what> <message regex>
    if "$SRC/scripts/package.sh" --check "$deb" arm64 >"$TMP/out" 2>&1; then
      fail "checker accepted a package with $1"
    fi
    grep -qE "$2" "$TMP/out" || fail "checker rejected $1 without saying /$2/: $(cat "$TMP/out")"
  }
  make_deb good "$TMP/a64" "libc6 (>= 2.36)"
  "$SRC/scripts/package.sh" --check "$deb" arm64 >"$TMP/out" 2>&1 || fail "checker rejected a correct package: $(cat "$TMP/out")"
  make_deb missing "$TMP/a64" "libc6 (>= 2.36)" /usr/bin/tacse3-ctl
  expect_fail "a missing program" 'missing: /usr/bin/tacse3-ctl'
  make_deb noman "$TMP/a64" "libc6 (>= 2.36)" /usr/share/man/man1/tacse3-ctl.1.gz
  expect_fail "a program without its manual page" 'missing: /usr/share/man/man1/tacse3-ctl.1.gz'
  make_deb extra "$TMP/a64" "libc6 (>= 2.36)" "" /usr/lib/libtacse3_dsp.a
  expect_fail "a static library" 'unexpected file: /usr/lib/libtacse3_dsp.a'
  make_deb wrongarch "$TMP/host" "libc6 (>= 2.36)"
  expect_fail "x86-64 binaries" "file says .*x86-64"
  make_deb nodeps "$TMP/a64" "libstdc++6 (>= 12)"
  expect_fail "a Depends without libc6" "Depends lacks 'libc6 \(>= 2.36\)'.*|Depends has 'libstdc\+\+6"
  make_deb noconf "$TMP/a64" "libc6 (>= 2.36)" "" "" /etc/tacse3/tacse3d.conf
  expect_fail "a conffile not in conffiles" 'not in conffiles: /etc/tacse3/tacse3d.conf'
  echo "checker: a correct fake arm64 package passes; missing file, missing manual page, extra file, wrong architecture, wrong Depends, missing conffile are each refused"
}

run_case() {
  declare -F "case_$1" >/dev/null || fail "unknown case '$1'"
  "case_$1"
}
[ $# -eq 1 ] || fail "usage: $0 <unit|sysusers|udev|network|scripts|shlibs|checker|all>"
if [ "$1" = all ]; then
  for c in unit sysusers udev network scripts shlibs checker; do run_case "$c"; done
else
  run_case "$1"
fi
