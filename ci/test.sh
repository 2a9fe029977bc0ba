#!/usr/bin/env bash
# The test command: install what is missing, check formatting and the module order, build
# Release and run every non-slow test, then (with INCISE_WITH_SLOW=1) the `slow` label, then
# build the asan preset and run the property tests under sanitizers. Prints each stage's
# duration. Exits non-zero on any failure. Ends with one line "tests: N passed, M failed".
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

t0=$SECONDS
echo "== release build"
cmake --preset release >/dev/null
cmake --build --preset release -j"$jobs"
echo "== release tests (excluding label 'slow')"
status=0
ctest --preset release 2>&1 | tee "$logdir/release.log" || status=1
read -r p1 f1 < <(count "$logdir/release.log")
echo "== stage time: build + non-slow tests $((SECONDS - t0)) s"

p3=0 f3=0
if [ "${INCISE_WITH_SLOW:-0}" = "1" ]; then
  t1=$SECONDS
  echo "== release tests, label 'slow'"
  ctest --test-dir build/release -L slow -j"$jobs" --output-on-failure 2>&1 |
    tee "$logdir/slow.log" || status=1
  read -r p3 f3 < <(count "$logdir/slow.log")
  echo "== stage time: slow label $((SECONDS - t1)) s"
fi

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
echo "== total time $SECONDS s"
echo "tests: $((p1 + p2 + p3)) passed, $((f1 + f2 + f3)) failed"
exit $status
