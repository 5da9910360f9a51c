# SPDX-License-Identifier: Apache-2.0
# Shared settings and helpers for the VM test scripts (sourced, not executed).
# shellcheck shell=bash

VM_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
REPO_ROOT="$(cd "$VM_DIR/../.." && pwd)"
VM_BUILD="${TACSE3_VM_BUILD:-$REPO_ROOT/build/vm}"
# Seconds after which the private apt lists are refreshed (older ABIs vanish from the mirror).
VM_APT_MAX_AGE="${TACSE3_VM_APT_MAX_AGE:-3600}"

vm_log() { printf '[vm %(%H:%M:%S)T] %s\n' -1 "$*" >&2; }
vm_die() { printf '[vm] ERROR: %s\n' "$*" >&2; exit 1; }

# vm_arch_vars ARCH: sets DEB_ARCH, KFLAVOUR, TRIPLET, QEMU_BIN for aarch64 or x86_64.
vm_arch_vars() {
  case "$1" in
    aarch64) DEB_ARCH=arm64; KFLAVOUR=arm64; TRIPLET=aarch64-linux-gnu; QEMU_BIN=qemu-system-aarch64 ;;
    x86_64)  DEB_ARCH=amd64; KFLAVOUR=amd64; TRIPLET=x86_64-linux-gnu;  QEMU_BIN=qemu-system-x86_64 ;;
    *) vm_die "unknown VM architecture '$1' (use aarch64 or x86_64)" ;;
  esac
}

# A private apt state (lists, cache, status) under build/vm/apt that knows amd64 and arm64.
# The host's dpkg architectures and package state are never changed; its sources.list and
# apt.conf.d (mirror, proxy) are reused. Everything apt-related below runs with APT_CONFIG set.
vm_apt_setup() {
  local root="$VM_BUILD/apt"
  mkdir -p "$root/lists/partial" "$root/cache/archives/partial" "$VM_BUILD/debs"
  [ -f "$root/status" ] || : >"$root/status"
  cat >"$root/apt.conf" <<CONF
Dir::State::Lists "$root/lists";
Dir::State::status "$root/status";
Dir::Cache "$root/cache";
APT::Architecture "amd64";
APT::Architectures { "amd64"; "arm64"; };
Acquire::Retries "5";
Acquire::Languages "none";
Acquire::http::Timeout "30";
APT::Sandbox::User "root";
Debug::NoLocking "true";
CONF
  export APT_CONFIG="$root/apt.conf"
  local stamp="$root/updated" now age
  now=$(date +%s)
  age=$(( now - $(stat -c %Y "$stamp" 2>/dev/null || echo 0) ))
  if [ "${TACSE3_VM_OFFLINE:-0}" = 1 ]; then
    [ -f "$stamp" ] || vm_die "TACSE3_VM_OFFLINE=1 but no apt lists in $root yet"
  elif [ "$age" -ge "$VM_APT_MAX_AGE" ]; then
    vm_log "apt-get update (private lists for amd64+arm64 in $root)"
    local try
    # A mirror mid-sync can serve one index with the wrong size (it broke CI once): retry with
    # growing pauses, then continue with the lists apt did get (a package that is really missing
    # then fails the download, naming it).
    for try in 1 2 3 4; do
      if apt-get -q update >"$root/update.log" 2>&1 && ! grep -qE '^(E:|W: Failed to fetch)' "$root/update.log"; then
        touch "$stamp"; return 0
      fi
      vm_log "apt-get update attempt $try failed:"; tail -5 "$root/update.log" >&2
      [ "$try" -lt 4 ] && sleep $((try * 15))
    done
    if compgen -G "$root/lists/*_Packages*" >/dev/null; then
      vm_log "apt-get update still reports errors; continuing with the package lists it got (see $root/update.log)"
      return 0
    fi
    vm_die "apt-get update failed and no package lists exist (see $root/update.log)"
  fi
}

# vm_kernel_release ARCH: prints the kernel release (e.g. 6.1.0-56-arm64) that the
# linux-image-<flavour> metapackage currently depends on.
vm_kernel_release() {
  vm_arch_vars "$1"
  local dep
  dep=$(apt-cache show --no-all-versions "linux-image-$KFLAVOUR:$DEB_ARCH" 2>/dev/null |
        sed -n 's/^Depends: //p' | grep -o "linux-image-[0-9][^ ,:(]*-$KFLAVOUR" | head -1)
  [ -n "$dep" ] || vm_die "cannot resolve the kernel ABI from linux-image-$KFLAVOUR:$DEB_ARCH"
  echo "${dep#linux-image-}"
}

# vm_fetch PKG[:ARCH]...: downloads the .debs into $VM_BUILD/debs (apt-get download skips files
# already there) and prints their paths, one a line, in argument order.
vm_fetch() {
  local names show try ok=0 p f
  show=$(apt-cache show --no-all-versions "$@") || vm_die "apt-cache show $* failed"
  # apt-get download names files NAME_VERSION_ARCH.deb with the epoch colon as %3a.
  names=$(printf '%s\n\n' "$show" | awk '
    /^Package: /{p=$2} /^Version: /{v=$2} /^Architecture: /{a=$2}
    /^$/{ if (p != "") { gsub(":", "%3a", v); print p ":" a " " p "_" v "_" a ".deb" }; p="" }')
  local missing=()
  for p in "$@"; do
    f=$(printf '%s\n' "$names" | awk -v q="$p" '
          $1 == q || (index(q, ":") == 0 && index($1, q ":") == 1) {print $2; exit}')
    [ -n "$f" ] && [ -f "$VM_BUILD/debs/$f" ] || missing+=("$p")
  done
  [ ${#missing[@]} -gt 0 ] || ok=1
  for try in 1 2 3; do
    [ "$ok" = 1 ] && break
    if (cd "$VM_BUILD/debs" && apt-get -q download "${missing[@]}" >"$VM_BUILD/debs/.download.log" 2>&1); then
      ok=1; break
    fi
    vm_log "apt-get download attempt $try failed:"; tail -5 "$VM_BUILD/debs/.download.log" >&2
    sleep $((try * 5))
  done
  [ "$ok" = 1 ] || vm_die "apt-get download $* failed"
  for p in "$@"; do
    f=$(printf '%s\n' "$names" | awk -v q="$p" '
          $1 == q || (index(q, ":") == 0 && index($1, q ":") == 1) {print $2; exit}')
    [ -n "$f" ] && [ -f "$VM_BUILD/debs/$f" ] || vm_die "apt-get download did not produce $p"
    echo "$VM_BUILD/debs/$f"
  done
}

# vm_extract DEB: unpacks DEB once (dpkg -x) under $VM_BUILD/x/ and prints the directory.
vm_extract() {
  local deb="$1" dir
  [ -f "$deb" ] || vm_die "vm_extract: no such package file '$deb'"
  dir="$VM_BUILD/x/$(basename "$deb" .deb)"
  if [ ! -f "$dir/.extracted" ]; then
    rm -rf "$dir" "$dir.tmp"
    mkdir -p "$dir.tmp"
    dpkg -x "$deb" "$dir.tmp"
    touch "$dir.tmp/.extracted"
    mv "$dir.tmp" "$dir"
  fi
  echo "$dir"
}

# vm_lock: one VM build/run at a time per build directory (waits up to 30 min for another one).
# The scripts run by a locked script inherit the lock (TACSE3_VM_LOCKED) and do not take it again.
vm_lock() {
  [ "${TACSE3_VM_LOCKED:-}" = "$VM_BUILD" ] && return 0
  mkdir -p "$VM_BUILD"
  exec 9>"$VM_BUILD/.lock"
  if ! flock -n 9; then
    vm_log "another tests/vm run holds $VM_BUILD/.lock; waiting"
    flock -w 1800 9 || vm_die "timed out waiting for $VM_BUILD/.lock"
  fi
  export TACSE3_VM_LOCKED="$VM_BUILD"
}

# vm_hash FILE...: a short content hash of the given files (cache keys).
vm_hash() { cat "$@" | sha256sum | cut -c1-16; }
