#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tacse3 tools: build a pipeline variant kept as a patch and run the accuracy benchmark with it.
#
# Usage: tools/analysis/try_patch.sh PATCH WORK_DIR [tacse3-bench-accuracy options...]
# Checks out HEAD into WORK_DIR/src (a detached git worktree), applies PATCH there, builds
# tacse3-bench-accuracy with the host preset and runs it with the given options (for example
# -j 2 --friction 1.5 --calibration-out WORK_DIR/cal.toml --markdown WORK_DIR/tables.md). The
# main checkout and its build folder are not touched. The worktree stays for inspection; remove
# it with `git worktree remove --force WORK_DIR/src`.
# The patches in tools/analysis/experiments/ are variants that were measured and not adopted
# (docs/accuracy.md says which and why); they change the fixed-point path only, so the
# benchmark's fixed−ref columns do not apply to them.
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 PATCH WORK_DIR [tacse3-bench-accuracy options...]" >&2; exit 2; }

root="$(cd "$(dirname "$0")/../.." && pwd)"
patch="$(realpath -e "$1")" || { echo "$0: $1: no such patch" >&2; exit 1; }
work="$(realpath -m "$2")"
shift 2
src="$work/src"
[ ! -e "$src" ] || { echo "$0: $src exists: use a fresh WORK_DIR" >&2; exit 1; }
mkdir -p "$work"
git -C "$root" worktree add --detach -q "$src" HEAD
git -C "$src" apply --check "$patch" 2>/dev/null ||
  { echo "$0: $patch does not apply to $(git -C "$root" rev-parse --short HEAD)" >&2; exit 1; }
git -C "$src" apply "$patch"
(cd "$src" && cmake --preset host >/dev/null &&
   cmake --build --preset host --target tacse3-bench-accuracy >/dev/null)
exec "$src/build/host/tools/bench_accuracy/tacse3-bench-accuracy" "$@"
