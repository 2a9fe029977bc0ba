#!/usr/bin/env bash
# Installs the Debian packages incise needs, only those missing. Idempotent; runs as root or
# through sudo. Also makes OpenBLAS the BLAS that libblas.so.3 resolves to at run time (CHOLMOD's
# supernodal factorization is several times faster with it than with the reference BLAS).
set -euo pipefail
# clang + libclang-rt-14-dev (the sanitizer and libFuzzer runtimes, only recommended by clang, so
# not pulled in with --no-install-recommends): the asan preset that ci/test.sh builds. doxygen:
# the API reference (target incise_docs), built by ci/test.sh. pybind11 + Debian's python3 with
# NumPy, pytest and Matplotlib: the Python module, its tests and example (docs/python.md).
# libbenchmark-tools (Google Benchmark's compare.py) with python3-scipy (its U test imports it
# and NumPy): `incise bench --compare` and the test cli_bench_compare_py. libcli11-dev
# (header-only): the command line of the `incise` program (lib/cli/). zlib1g-dev: the VTU
# writer's compressed binary data; python3-vtk9: VTK's own reader in the test io_vtk_readback
# (label vtk, docs/mesh_formats.md).
packages=(
  build-essential cmake ccache pkg-config clang-format clang libclang-rt-14-dev
  libeigen3-dev libsuitesparse-dev libfftw3-dev nlohmann-json3-dev libopenblas-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev doxygen
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  libbenchmark-tools python3-scipy libcli11-dev zlib1g-dev python3-vtk9
)
# Headless Chromium (large) only on request, for the `slow` render test of the certification
# report and the benchmark dashboard (verification/scene/render_pages.sh).
if [ "${INCISE_WITH_CHROMIUM:-0}" = "1" ]; then
  packages+=(chromium)
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  # apt/dpkg progress goes to a log, shown only when the install fails.
  log=$(mktemp)
  if ! { $SUDO apt-get update -qq &&
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
      "${missing[@]}"; } >"$log" 2>&1; then
    cat "$log" >&2
    echo "install-deps: apt-get failed (output above)" >&2
    rm -f "$log"
    exit 1
  fi
  rm -f "$log"
  echo "install-deps: installed ${#missing[@]} packages"
else
  echo "install-deps: all ${#packages[@]} packages present"
fi
# OpenBLAS as the run-time BLAS (Debian alternatives).
arch=$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)
alt="libblas.so.3-${arch}"
openblas="/usr/lib/${arch}/openblas-pthread/libblas.so.3"
if [ -e "$openblas" ]; then
  current=$(update-alternatives --query "$alt" 2>/dev/null | awk '/^Value:/ {print $2}')
  if [ "$current" != "$openblas" ]; then
    $SUDO update-alternatives --set "$alt" "$openblas"
  fi
  echo "install-deps: run-time BLAS is $openblas"
else
  echo "install-deps: WARNING OpenBLAS not found at $openblas; reference BLAS in use" >&2
fi
