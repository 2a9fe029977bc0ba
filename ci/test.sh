#!/usr/bin/env bash
# The test command: install what is missing, check formatting, build Release and run every
# non-slow test, then build the asan preset and run the property tests under sanitizers.
# Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
jobs=$(nproc 2>/dev/null || echo 2)

ci/install-deps.sh

echo "== clang-format check"
ci/check-format.sh

echo "== release build"
cmake --preset release >/dev/null
cmake --build --preset release -j"$jobs"
echo "== release tests (excluding label 'slow')"
ctest --preset release

if [ "${INCISE_SKIP_ASAN:-0}" != "1" ]; then
  echo "== asan build (property tests)"
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j"$jobs"
  echo "== asan property tests"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --preset asan-property
fi
echo "ci/test.sh: all passed"
