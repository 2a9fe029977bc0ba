#!/usr/bin/env bash
# Fails when any tracked C++ file differs from .clang-format (clang-format 14).
set -euo pipefail
cd "$(dirname "$0")/.."
fmt=$(command -v clang-format-14 || command -v clang-format)
files=$(git ls-files '*.cpp' '*.hpp' 2>/dev/null || find lib property_tests verification benchmarks -name '*.[ch]pp')
bad=0
for f in $files; do
  if ! "$fmt" --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f (run: $fmt -i $f)"
    bad=1
  fi
done
exit $bad
