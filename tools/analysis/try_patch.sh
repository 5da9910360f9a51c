#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: build a pipeline variant kept as a patch (benchmark and replay) and benchmark it.
#
# Usage: tools/analysis/try_patch.sh PATCH WORK_DIR [tacse3-bench-accuracy options...]
# (no options: build only)
# Checks out HEAD into WORK_DIR/src (a detached git worktree of this repository), applies PATCH
# there, builds tacse3-bench-accuracy and tacse3-replay with the host preset (log:
# WORK_DIR/build.log) and runs the benchmark with the given options, for example
#   -j 2 --friction 1.5 --calibration-out WORK_DIR/cal.toml --markdown WORK_DIR/tables.md
# The variant's replay stays at WORK_DIR/src/build/host/tools/replay/tacse3-replay, for runs on
# single recordings (--slip-log, --dump-fields).
# The main checkout's files and build folder are not touched (git records the worktree under
# .git/worktrees). The worktree stays for inspection, also when a step fails; remove it with
#   git worktree remove --force WORK_DIR/src
# The patches in tools/analysis/experiments/ are variants that were measured and not adopted
# (docs/accuracy.md item 2 (f) and (g) say which and why); each patch's header says whether it
# changes the double reference too (if not, the benchmark's fixed−ref columns do not apply to it).
set -euo pipefail
usage="usage: $0 PATCH WORK_DIR [tacse3-bench-accuracy options...] (none: build only)"
[ $# -ge 2 ] || { echo "$usage" >&2; exit 2; }

root="$(cd "$(dirname "$0")/../.." && pwd)"
[ -f "$1" ] || { echo "$0: $1: no such patch" >&2; exit 1; }
patch="$(realpath "$1")"
work="$(realpath -m "$2")"
shift 2
src="$work/src"
[ ! -e "$src" ] || { echo "$0: $src exists: use a fresh WORK_DIR" >&2; exit 1; }
mkdir -p "$work"
git -C "$root" worktree add --detach -q "$src" HEAD
fail() {
  echo "$0: $1; the worktree stays at $src (git worktree remove --force \"$src\")" >&2
  exit 1
}
git -C "$src" apply --check "$patch" ||
  fail "$patch does not apply to $(git -C "$root" rev-parse --short HEAD) (above)"
git -C "$src" apply "$patch"
targets=(tacse3-bench-accuracy tacse3-replay)
if ! (cd "$src" && cmake --preset host && cmake --build --preset host --target "${targets[@]}") \
    > "$work/build.log" 2>&1; then
  tail -n 30 "$work/build.log" >&2
  fail "the build failed (whole log: $work/build.log)"
fi
if [ $# -eq 0 ]; then
  echo "$0: built $src/build/host/tools/replay/tacse3-replay and the benchmark beside it"
  exit 0
fi
exec "$src/build/host/tools/bench_accuracy/tacse3-bench-accuracy" "$@"
