#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Every C and C++ file git tracks is formatted as .clang-format says; prints the files that are
# not, and the command that fixes them. Usage: scripts/check-format.sh [CLANG_FORMAT]
set -eu
cd "$(dirname "$0")/.."
clang_format="${1:-clang-format}"
files=$(git ls-files '*.c' '*.h' '*.cpp' '*.hpp')
bad=""
for f in $files; do
  if ! "$clang_format" --dry-run --Werror "$f" >/dev/null 2>&1; then bad="$bad $f"; fi
done
if [ -n "$bad" ]; then
  echo "check-format: not formatted as .clang-format says:$bad"
  echo "check-format: fix with: $clang_format -i$bad"
  exit 1
fi
echo "check-format: $(echo "$files" | wc -l) files formatted"
