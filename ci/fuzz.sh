#!/usr/bin/env bash
# Builds the libFuzzer harnesses (preset `fuzz`: clang++, ASan + UBSan) and runs each from the
# seeds in reference_data/fuzz/<target>/ (read only) and the inputs found so far, kept in
# build/fuzz-corpus/<target>/.
#   ci/fuzz.sh [SECONDS] [TARGET...]   run each target for SECONDS (default 60)
#   ci/fuzz.sh --runs N [TARGET...]    run each target for N executions (the longer run)
# Targets: medit tetgen gmsh off sweep scene (default: all). Prints one line per target with its
# executions; exits non-zero at the first finding, leaving the input in
# build/fuzz-corpus/<target>-crash-* (or -leak-, -timeout-, -oom-) and the log in
# build/fuzz-logs/<target>.log. Reproduce with build/fuzz/fuzz/fuzz_<target> <input>.
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

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j"$(nproc 2>/dev/null || echo 2)" \
  --target "${targets[@]/#/fuzz_}" >/dev/null
mkdir -p build/fuzz-corpus build/fuzz-logs
for t in "${targets[@]}"; do
  [ -d "reference_data/fuzz/$t" ] || { echo "fuzz: no seed folder reference_data/fuzz/$t"; exit 2; }
  mkdir -p "build/fuzz-corpus/$t"
  log=build/fuzz-logs/$t.log
  dict=()
  [ -f "fuzz/fuzz_$t.dict" ] && dict=(-dict="fuzz/fuzz_$t.dict")
  start=$SECONDS
  if ! "build/fuzz/fuzz/fuzz_$t" "${limit[@]}" "${dict[@]}" -rss_limit_mb=2048 -timeout=20 \
      -print_final_stats=1 \
      -artifact_prefix="build/fuzz-corpus/$t-" "build/fuzz-corpus/$t" "reference_data/fuzz/$t" \
      >"$log" 2>&1; then
    echo "fuzz_$t: FINDING (log $log)"
    grep -E "incise fuzz finding|ERROR:|SUMMARY:|artifact_prefix|Test unit written" "$log" | head -20
    exit 1
  fi
  runs=$(sed -nE 's/^stat::number_of_executed_units: *([0-9]+).*/\1/p' "$log" | tail -1)
  cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1)
  echo "fuzz_$t: ${runs:-?} executions in $((SECONDS - start)) s, $cov, no finding"
done
