#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the VM test scenarios on real kernel drivers in qemu (TCG) and checks the returned logs.
# Usage: tests/vm/run.sh [options] [aarch64|x86_64|all] [SCENARIO...]
#   (no arch: all; no scenario: every scenario of the arch whose header lacks "vm-default: no")
# Options:
#   --bin ARCH=PATH   project files for the ARCH guest (repeatable), see build-overlay.sh; also
#                     from TACSE3_VM_BINS="aarch64=build/aarch64/bin/tacse3d x86_64=..."
#   --list            list the scenarios and their architectures, then exit
#   --sequential      boot the VMs one after the other (default: in parallel for "all")
#   -q, --quiet       keep the guest consoles out of the terminal (they are in console.log)
# Exit status: 0 when every selected scenario passed in the VM and in its host check.
# Logs: build/vm/logs/<arch>/{console.log,summary.txt,timing.txt,dmesg-boot.log}
#       build/vm/logs/<arch>/<scenario>/{vm.log,rc,dmesg.log,host.log,<files the scenario saved>}
# Env: TACSE3_VM_BUILD (default build/vm), TACSE3_VM_MEM (MiB, default 1024), TACSE3_VM_SMP
#      (vCPUs; default 2 on aarch64, 1 on x86_64), TACSE3_VM_EXTRA_PACKAGES,
#      TACSE3_VM_EXTRA_MODULES, TACSE3_VM_OFFLINE=1 (use cached apt lists), TACSE3_HOST_BIN
#      (host tools for host.sh, default build/host/bin), TACSE3_VM_SCENARIO_PATH (more scenario
#      directories, colon-separated), TACSE3_VM_REQUIRE_ALL=1 (a skipped scenario fails the suite).
#      Scenarios exit 77 to skip (e.g. tacse3d not in the guest). See docs/testing.md.
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
T_START=$(date +%s.%N)

arches=(); names=(); bins=(); list=0; parallel=1; quiet=0
read -r -a env_bins <<<"${TACSE3_VM_BINS:-}"
bins+=("${env_bins[@]}")
while [ $# -gt 0 ]; do
  case "$1" in
    --bin) bins+=("$2"); shift 2 ;;
    --bin=*) bins+=("${1#--bin=}"); shift ;;
    --list) list=1; shift ;;
    --sequential) parallel=0; shift ;;
    -q|--quiet) quiet=1; shift ;;
    -h|--help) sed -n '3,21s/^# \{0,1\}//p' "$0"; exit 0 ;;
    aarch64|x86_64) arches+=("$1"); shift ;;
    all) arches+=(aarch64 x86_64); shift ;;
    -*) vm_die "unknown option $1" ;;
    *) names+=("$1"); shift ;;
  esac
done
[ ${#arches[@]} -gt 0 ] || arches=(aarch64 x86_64)
mapfile -t arches < <(printf '%s\n' "${arches[@]}" | awk '!seen[$0]++')

# Scenario directories: tests/vm/scenarios, then those in TACSE3_VM_SCENARIO_PATH (colon-separated),
# so other parts of the tree can keep their own VM scenarios. The first directory with a name wins.
SCEN_DIRS=("$VM_DIR/scenarios")
IFS=: read -r -a extra_dirs <<<"${TACSE3_VM_SCENARIO_PATH:-}"
for d in "${extra_dirs[@]}"; do [ -n "$d" ] && SCEN_DIRS+=("$(cd "$d" && pwd)"); done
scen_path() {
  local d
  for d in "${SCEN_DIRS[@]}"; do [ -f "$d/$1/vm.sh" ] && { echo "$d/$1"; return 0; }; done
  return 1
}
header() { sed -n "s/^# $2: *//p" "$(scen_path "$1")/vm.sh" | head -1; }
# The smoke scenarios (Debian's tools only) come first: they load modules with their own parameters
# and create their own configfs objects, which the later project scenarios reuse or tolerate.
all_scenarios() {
  local d s
  for d in "${SCEN_DIRS[@]}"; do for s in "$d"/*/vm.sh; do [ -f "$s" ] && basename "$(dirname "$s")"; done; done |
    awk '!seen[$0]++' | awk '/^smoke-/ { print; next } { rest[n++] = $0 } END { for (i = 0; i < n; i++) print rest[i] }'
}

if [ "$list" = 1 ]; then
  for s in $(all_scenarios); do
    printf '%-24s %-16s %s\n' "$s" "$(header "$s" vm-arch)" \
      "$([ "$(header "$s" vm-default)" = no ] && echo '(only when named)')"
  done
  exit 0
fi
for n in "${names[@]}"; do
  scen_path "$n" >/dev/null || vm_die "no scenario '$n' (tests/vm/scenarios/$n/vm.sh); see --list"
done

# scenarios_for ARCH: the selected scenarios that run on ARCH.
scenarios_for() {
  local s
  if [ ${#names[@]} -gt 0 ]; then
    for s in "${names[@]}"; do
      [[ " $(header "$s" vm-arch) " == *" $1 "* ]] && echo "$s"
    done
  else
    for s in $(all_scenarios); do
      [[ " $(header "$s" vm-arch) " == *" $1 "* ]] && [ "$(header "$s" vm-default)" != no ] && echo "$s"
    done
  fi
  return 0
}

for b in "${bins[@]}"; do
  case "$b" in aarch64=*|x86_64=*) ;; *) vm_die "--bin wants ARCH=PATH, got '$b'" ;; esac
done

vm_lock
# ---- phase 1: build (sequential: one apt state) ----
declare -A KDIR CPIO SCEN TLIMIT
run_arches=()
for a in "${arches[@]}"; do
  mapfile -t sl < <(scenarios_for "$a")
  if [ ${#names[@]} -gt 0 ] && [ ${#arches[@]} -eq 1 ]; then
    for n in "${names[@]}"; do
      [[ " ${sl[*]} " == *" $n "* ]] || vm_die "scenario $n does not run on $a (vm-arch: $(header "$n" vm-arch))"
    done
  fi
  if [ ${#sl[@]} -eq 0 ]; then vm_log "$a: no scenario selected, skipping"; continue; fi
  run_arches+=("$a")
  SCEN[$a]="${sl[*]}"
  t0=$(date +%s)
  base=$("$VM_DIR/build-initramfs.sh" "$a")
  D=$(dirname "$base")
  KDIR[$a]="$D/kernel"
  ov=(); for b in "${bins[@]}"; do [ "${b%%=*}" = "$a" ] && ov+=(--bin "${b#*=}"); done
  sdirs=(); total=0
  for s in "${sl[@]}"; do
    sdirs+=("$(scen_path "$s")")
    t=$(header "$s" vm-timeout); total=$((total + ${t:-120} + 5))
  done
  "$VM_DIR/build-overlay.sh" "$a" "$D/overlay.cpio" "${base%.cpio}.manifest" "${ov[@]}" "${sdirs[@]}"
  cat "$base" "$D/overlay.cpio" >"$D/initrd.cpio"
  CPIO[$a]="$D/initrd.cpio"
  TLIMIT[$a]=$((total + 180))      # boot, module loading and log transfer included
  vm_log "$a: initramfs ready in $(( $(date +%s) - t0 ))s: ${sl[*]}"
done
[ ${#run_arches[@]} -gt 0 ] || vm_die "nothing to run"

# ---- phase 2: boot ----
boot() {
  local a=$1 logdir="$VM_BUILD/logs/$1" k="${KDIR[$1]}" rc=0
  # aarch64 gets 2 vCPUs (MTTCG: one host thread each; the target has 4 cores and two vivid
  # streams keep up better), x86_64 one.
  local mem="${TACSE3_VM_MEM:-1024}" smp="${TACSE3_VM_SMP:-$([ "$1" = aarch64 ] && echo 2 || echo 1)}"
  rm -rf "$logdir"; mkdir -p "$logdir"
  truncate -s 512M "$logdir/out.img"
  # x86_64 boots the unpacked ELF vmlinux through its PVH entry when build-kernel.sh made one.
  local kernel="$k/vmlinuz"
  [ -f "$k/vmlinux" ] && kernel="$k/vmlinux"
  local common=(-accel tcg -m "$mem" -smp "$smp" -nodefaults -display none -no-reboot
                -serial stdio -monitor none -kernel "$kernel" -initrd "${CPIO[$a]}"
                -drive "if=none,id=out,format=raw,file=$logdir/out.img"
                -device virtio-blk-pci,drive=out)
  local append="rdinit=/init panic=-1 loglevel=4 printk.devkmsg=on"
  local cmd
  vm_arch_vars "$a"
  case "$a" in
    aarch64) cmd=("$QEMU_BIN" -M virt -cpu cortex-a72 "${common[@]}"
                  -append "console=ttyAMA0 $append") ;;
    x86_64)  cmd=("$QEMU_BIN" -M pc "${common[@]}"
                  -device isa-debug-exit,iobase=0xf4,iosize=0x04
                  -append "console=ttyS0 $append") ;;
  esac
  printf '%q ' "${cmd[@]}" >"$logdir/qemu-cmd.txt"; echo >>"$logdir/qemu-cmd.txt"
  local t0 t1
  t0=$(date +%s.%N)
  if [ "$quiet" = 1 ]; then
    timeout -k 10 "${TLIMIT[$a]}" "${cmd[@]}" </dev/null >"$logdir/console.log" 2>&1 || rc=$?
  elif [ "${#run_arches[@]}" -gt 1 ] && [ "$parallel" = 1 ]; then
    { timeout -k 10 "${TLIMIT[$a]}" "${cmd[@]}" </dev/null 2>&1 || echo "qemu-exit $?" >"$logdir/qemu-rc"; } |
      tee "$logdir/console.log" | sed -u "s/^/[$a] /"
    [ -f "$logdir/qemu-rc" ] && rc=$(cut -d' ' -f2 "$logdir/qemu-rc")
  else
    { timeout -k 10 "${TLIMIT[$a]}" "${cmd[@]}" </dev/null 2>&1 || echo "qemu-exit $?" >"$logdir/qemu-rc"; } |
      tee "$logdir/console.log"
    [ -f "$logdir/qemu-rc" ] && rc=$(cut -d' ' -f2 "$logdir/qemu-rc")
  fi
  t1=$(date +%s.%N)
  echo "$rc" >"$logdir/qemu-rc"
  awk -v a="$t0" -v b="$t1" 'BEGIN{printf "qemu_wall_s %.1f\n", b-a}' >"$logdir/host-timing.txt"
}

if [ "$parallel" = 1 ] && [ ${#run_arches[@]} -gt 1 ]; then
  pids=()
  for a in "${run_arches[@]}"; do boot "$a" & pids+=($!); done
  for p in "${pids[@]}"; do wait "$p" || true; done
else
  for a in "${run_arches[@]}"; do boot "$a"; done
fi

# ---- phase 3: collect the logs and run the host checks ----
pass=0; fail=0; skipped=0; report=()
for a in "${run_arches[@]}"; do
  logdir="$VM_BUILD/logs/$a"
  qrc=$(cat "$logdir/qemu-rc")
  tar -xf "$logdir/out.img" -C "$logdir" 2>/dev/null || true
  rm -f "$logdir/out.img"
  vmres=$(cut -d' ' -f1 "$logdir/result" 2>/dev/null || echo NONE)
  note=""
  case "$qrc" in
    124|137) note="qemu timed out after ${TLIMIT[$a]}s" ;;
  esac
  if [ "$a" = x86_64 ] && [ -z "$note" ]; then
    # isa-debug-exit: 1 = guest wrote 0 (pass), 3 = guest wrote 1 (fail)
    case "$qrc:$vmres" in
      1:PASS|3:FAIL) ;;
      *) note="qemu exit $qrc does not match the guest result $vmres" ;;
    esac
  elif [ "$a" = aarch64 ] && [ -z "$note" ] && [ "$qrc" != 0 ]; then
    note="qemu exit $qrc"
  fi
  consres=$(sed -n 's/.*TACSE3-VM-RESULT: \([A-Z]*\).*/\1/p' "$logdir/console.log" 2>/dev/null | tail -1 || true)
  [ -n "$note" ] || [ "$consres" = "$vmres" ] || note="console says '${consres:-nothing}', log disk says $vmres"
  {
    echo "arch $a"; echo "kernel $(cat "${KDIR[$a]}/release")"
    echo "qemu_exit $qrc"; echo "guest_result $vmres"
    [ -n "$note" ] && echo "problem $note"
  } >"$logdir/summary.txt"
  for s in ${SCEN[$a]}; do
    sd="$logdir/$s"; mkdir -p "$sd"
    vrc=$(cat "$sd/rc" 2>/dev/null || echo missing)
    status=PASS; why=""
    if [ "$vrc" = 77 ]; then
      # The scenario's driver bring-up passed, then it found something it needs missing (tacse3d).
      status=SKIP; why=$(sed -n 's/^SKIP: //p' "$sd/vm.log" | tail -1)
      [ "${TACSE3_VM_REQUIRE_ALL:-0}" = 1 ] && { status=FAIL; why="skipped, and TACSE3_VM_REQUIRE_ALL=1: $why"; }
    elif [ "$vrc" != 0 ]; then
      status=FAIL; why="in VM: rc=$vrc (see $sd/vm.log)"
      { echo "--- $a/$s: last lines of vm.log"; tail -n 12 "$sd/vm.log" 2>/dev/null | sed 's/^/    | /' || true; } >&2
    elif [ -f "$(scen_path "$s")/host.sh" ]; then
      if TACSE3_VM_LOGDIR="$sd" TACSE3_VM_ARCH="$a" TACSE3_REPO="$REPO_ROOT" \
         TACSE3_HOST_BIN="${TACSE3_HOST_BIN:-$REPO_ROOT/build/host/bin}" \
         bash "$(scen_path "$s")/host.sh" >"$sd/host.log" 2>&1; then
        :
      else
        status=FAIL; why="host check failed (see $sd/host.log)"
        { echo "--- $a/$s: last lines of host.log"; tail -n 12 "$sd/host.log" | sed 's/^/    | /' || true; } >&2
      fi
    fi
    secs=$(awk -v s="$s" '$1=="scenario_s" && $2==s {print $3}' "$logdir/timing.txt" 2>/dev/null || true)
    echo "$s $status ${secs:-?}s $why" >>"$logdir/summary.txt"
    report+=("$(printf '%-8s %-7s %-26s %6ss  %s' "$status" "$a" "$s" "${secs:-?}" "$why")")
    case "$status" in
      PASS) pass=$((pass + 1)) ;;
      SKIP) skipped=$((skipped + 1)) ;;
      *) fail=$((fail + 1)) ;;
    esac
  done
  if [ -n "$note" ]; then
    report+=("$(printf '%-8s %-7s %s' PROBLEM "$a" "$note (console: $logdir/console.log)")")
    fail=$((fail + 1))
  fi
  boot_s=$(awk '$1=="boot_s"{print $2}' "$logdir/timing.txt" 2>/dev/null || true)
  end_s=$(awk '$1=="end_s"{print $2}' "$logdir/timing.txt" 2>/dev/null || true)
  report+=("$(printf '%-8s %-7s kernel up %ss, scenarios done at %ss guest uptime, qemu %s' \
    timing "$a" "${boot_s:-?}" "${end_s:-?}" "$(cut -d' ' -f2 "$logdir/host-timing.txt")s wall")")
done

T_END=$(date +%s.%N)
echo "=== VM suite ($(awk -v a="$T_START" -v b="$T_END" 'BEGIN{printf "%.0f", b-a}')s, logs in ${VM_BUILD#"$REPO_ROOT/"}/logs/) ==="
printf '%s\n' "${report[@]}"
echo "vm: $pass passed, $fail failed, $skipped skipped"
[ "$fail" = 0 ]
