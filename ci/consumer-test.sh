#!/usr/bin/env bash
# The consumer test (docs/install.md; stage "2b" of ci/test.sh): installs a built tree to a fresh
# prefix and uses it the ways a user would, each step required to succeed:
#   1. cmake --install BUILD --prefix build/consumer-test/staging, then the tree moved to
#      build/consumer-test/prefix (relocatable); no installed CMake package file nor incise.pc
#      names the source tree (raw source or build paths)
#   2. ci/consumer/ configured with find_package(incise CONFIG REQUIRED COMPONENTS scene),
#      built, and its ctest run: the shipped cantilever scene from <prefix>/share/incise solved
#      (converged, finite, tip deflection below beam theory)
#   3. pkg-config --cflags --libs incise with PKG_CONFIG_PATH=<prefix>/<libdir>/pkgconfig, and the
#      same program compiled and linked with those flags alone, then run
#   4. the installed examples/ built standalone against the prefix, and their ctest run
#   5. the installed program, run from / with INCISE_DATA_DIR unset, finds <prefix>/share/incise
# Usage: ci/consumer-test.sh [BUILD_DIR]   (default build/release; it must be built)
# Prints each step's duration; exits non-zero at the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build=${1:-build/release}
jobs=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)
work=$root/build/consumer-test  # fixed path: ccache (base_dir /work) hits across runs
prefix=$work/prefix
rm -rf "$work"
mkdir -p "$work"
unset INCISE_DATA_DIR
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
t=$SECONDS
step() { echo "consumer-test: $* ($((SECONDS - t)) s)"; }
# quiet LOG COMMAND...: runs COMMAND with its output in $work/LOG, shown when it fails.
quiet() {
  local log=$work/$1
  shift
  if ! "$@" >"$log" 2>&1; then
    tail -n 40 "$log"
    echo "consumer-test: FAILED: $* (log: $log)" >&2
    exit 1
  fi
}

# Installed to one folder and used from another: nothing installed may store the prefix.
quiet install.log cmake --install "$build" --prefix "$work/staging"
mv "$work/staging" "$prefix"
step "installed $build to $work/staging, moved to $prefix: $(find "$prefix" -type f | wc -l) files"
# The installed package names no source or build path (include directories are
# $<INSTALL_INTERFACE:include>, incise.pc is relative to itself).
if grep -rl -e "$root" "$prefix/lib/cmake" "$(find "$prefix" -name incise.pc)"; then
  echo "consumer-test: FAILED: the installed package files above name $root" >&2
  exit 1
fi

quiet cmake-configure.log cmake -S ci/consumer -B "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release "${launcher[@]}"
quiet cmake-build.log cmake --build "$work/cmake" -j"$jobs"
quiet cmake-ctest.log ctest --test-dir "$work/cmake" --output-on-failure -V
grep -E '^[0-9]+: (Test command|.*consumer)|tests passed' "$work/cmake-ctest.log"
step "find_package(incise) consumer built and passed"

pcfile=$(find "$prefix" -name incise.pc)
PKG_CONFIG_PATH=$(dirname "$pcfile")
export PKG_CONFIG_PATH
flags=$(pkg-config --cflags --libs incise)
echo "consumer-test: pkg-config --cflags --libs incise: $flags"
# shellcheck disable=SC2086  # the flags are words
${launcher:+ccache} c++ -std=c++17 -O2 ci/consumer/main.cpp -o "$work/incise_consumer_pc" $flags
"$work/incise_consumer_pc" "$prefix/share/incise/scenes/cantilever.json"
step "pkg-config consumer built and passed"

quiet examples-configure.log cmake -S examples -B "$work/examples" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release "${launcher[@]}"
quiet examples-build.log cmake --build "$work/examples" -j"$jobs"
quiet examples-ctest.log ctest --test-dir "$work/examples" --output-on-failure
grep -E 'tests passed' "$work/examples-ctest.log"
step "examples built standalone and passed"

out=$(cd / && "$prefix/bin/incise" certify --quick --filter '^box_volume$' --out "$work/certify")
echo "$out" | grep -q "reference data $prefix/share/incise\$" ||
  { echo "$out"; echo "consumer-test: the installed incise did not use $prefix/share/incise" >&2; exit 1; }
"$prefix/bin/incise" version
step "installed incise found its data in $prefix/share/incise"
echo "consumer-test: passed in $((SECONDS - t)) s"
