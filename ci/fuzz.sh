#!/usr/bin/env bash
# Builds the libFuzzer harnesses (preset `asan`: clang++, ASan + UBSan, the same build as the
# sanitized tests) and runs each from the seeds in reference_data/fuzz/<target>/ (read only) and
# the inputs found so far, kept in build/fuzz-corpus/<target>/.
#   ci/fuzz.sh [SECONDS] [TARGET...]   run each target for SECONDS (default 60)
#   ci/fuzz.sh --runs N [TARGET...]    run each target for N executions (the longer run)
# Targets: medit tetgen gmsh off sweep scene (default: all). INCISE_FUZZ_JOBS targets run at once
# (default: the number of cores; each fuzzer is one process on one core); INCISE_FUZZ_PREBUILT=1
# skips the build (ci/test.sh has just built the tree). Prints one line per target with its
# executions; exits non-zero if any target has a finding, leaving the input in
# build/fuzz-corpus/<target>-crash-* (or -leak-, -timeout-, -oom-) and the log in
# build/fuzz-logs/<target>.log. Reproduce with build/asan/fuzz/fuzz_<target> <input>.
set -euo pipefail
cd "$(dirname "$0")/.."
limit=(-max_total_time=60)
if [ "${1:-}" = "--runs" ]; then
  limit=(-runs="$2")
  shift 2
elif [ $# -gt 0 ] && [[ $1 =~ ^[0-9]+$ ]]; then
  limit=(-max_total_time="$1")
  shift
fi
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(medit tetgen gmsh off sweep scene)
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
# getconf, not nproc: nproc honours OMP_NUM_THREADS (exported as 1 above and by ci/test.sh), which
# made the harnesses run one at a time.
cores=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)
jobs=${INCISE_FUZZ_JOBS:-$cores}

if [ "${INCISE_FUZZ_PREBUILT:-0}" != "1" ]; then  # ci/test.sh has just built the asan tree
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j"$cores" --target "${targets[@]/#/fuzz_}" >/dev/null
fi
mkdir -p build/fuzz-corpus build/fuzz-logs
for t in "${targets[@]}"; do
  [ -d "reference_data/fuzz/$t" ] || { echo "fuzz: no seed folder reference_data/fuzz/$t"; exit 2; }
done

# Runs one target; prints its line; returns 1 on a finding.
run_one() {
  local t=$1 log=build/fuzz-logs/$1.log start=$SECONDS dict=()
  mkdir -p "build/fuzz-corpus/$t"
  [ -f "fuzz/fuzz_$t.dict" ] && dict=(-dict="fuzz/fuzz_$t.dict")
  if ! "build/asan/fuzz/fuzz_$t" "${limit[@]}" "${dict[@]}" -rss_limit_mb=2048 -timeout=20 \
      -print_final_stats=1 \
      -artifact_prefix="build/fuzz-corpus/$t-" "build/fuzz-corpus/$t" "reference_data/fuzz/$t" \
      >"$log" 2>&1; then
    echo "fuzz_$t: FINDING (log $log)"
    grep -E "incise fuzz finding|ERROR:|SUMMARY:|artifact_prefix|Test unit written" "$log" | head -20
    return 1
  fi
  local runs cov
  runs=$(sed -nE 's/^stat::number_of_executed_units: *([0-9]+).*/\1/p' "$log" | tail -1)
  cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1)
  echo "fuzz_$t: ${runs:-?} executions in $((SECONDS - start)) s, $cov, no finding"
}

status=0
running=0
for t in "${targets[@]}"; do
  if [ "$running" -ge "$jobs" ]; then
    wait -n || status=1
    running=$((running - 1))
  fi
  run_one "$t" &
  running=$((running + 1))
done
while [ "$running" -gt 0 ]; do
  wait -n || status=1
  running=$((running - 1))
done
exit $status
