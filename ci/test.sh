#!/usr/bin/env bash
# The test command: install what is missing, check formatting, build Release and run every
# non-slow test, then build the asan preset and run the property tests under sanitizers.
# Exits non-zero on any failure. Ends with one line "tests: N passed, M failed".
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
# ctest runs $jobs tests at once: keep BLAS/OpenMP single-threaded so they don't oversubscribe.
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
logdir=build/ci-logs
mkdir -p "$logdir"

ci/install-deps.sh

echo "== clang-format check"
ci/check-format.sh
echo "== module order (lib/README.md)"
ci/check-module-order.sh

# counts "N passed, M failed" from a ctest log ("x% tests passed, M tests failed out of T")
count() {
  sed -nE 's/.*tests passed, ([0-9]+) tests? failed out of ([0-9]+).*/\2 \1/p' "$1" |
    awk '{ t = $1; f = $2 } END { if (t == "") { t = 0; f = 0 }; print t - f, f }'
}

echo "== release build"
cmake --preset release >/dev/null
cmake --build --preset release -j"$jobs"
echo "== release tests (excluding label 'slow')"
status=0
ctest --preset release 2>&1 | tee "$logdir/release.log" || status=1
read -r p1 f1 < <(count "$logdir/release.log")

p2=0 f2=0
if [ "${INCISE_SKIP_ASAN:-0}" != "1" ]; then
  echo "== asan build (property tests)"
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j"$jobs"
  echo "== asan property tests"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --preset asan-property 2>&1 | tee "$logdir/asan.log" || status=1
  read -r p2 f2 < <(count "$logdir/asan.log")
fi
echo "tests: $((p1 + p2)) passed, $((f1 + f2)) failed"
exit $status
