#!/usr/bin/env bash
# The main job: install what is missing, build Release, install it to build/install (the
# program, the libraries, the CMake and pkg-config package, the data: docs/install.md), and run
# the installed incise: `incise mesh check` on the real liver mesh (VTU written to out/), the
# default scene, the augmented cutting demo and the quick certification report. Ends with the
# line that puts incise on PATH.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)  # not nproc: it honours OMP_NUM_THREADS
ci/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$jobs" --target incise_package  # what the install needs
prefix=$(pwd)/build/install
cmake --install build/release --prefix "$prefix" >/dev/null
echo "demo: installed incise to $prefix (bin/incise, lib/, include/incise/, share/incise/)"
incise=$prefix/bin/incise
mkdir -p out
"$incise" mesh check reference_data/meshes/liver_coarse.mesh --vtu out/liver_coarse.vtu
echo "demo: wrote out/liver_coarse.vtu (open it in ParaView)"

# The default scene: the thesis cantilever (Table 3.1), then the quick certification report.
echo "== demo: incise run reference_data/scenes/cantilever.json"
"$incise" run reference_data/scenes/cantilever.json \
  --summary-json out/cantilever_summary.json
# The augmented-solver cutting demo: the solution is updated after every path segment (a blade
# advance: two sweep triangles cut, then one solve).
echo "== demo: incise run reference_data/scenes/cube_cut_augmented.json"
"$incise" run reference_data/scenes/cube_cut_augmented.json \
  --summary-json out/cube_cut_augmented_summary.json --progress none
# Needle insertion in 2D (thesis ch. 6, §6.8.1 slab): a per-update CSV and a VTU series with its
# ParaView index out/needle_slab.pvd (open it in ParaView and press play).
echo "== demo: incise run reference_data/scenes/needle_slab.json"
"$incise" run reference_data/scenes/needle_slab.json \
  --summary-json out/needle_slab_summary.json --progress none
echo "== demo: incise certify --quick"
certify_status=0
"$incise" certify --quick --out out/certify || certify_status=$?
echo "demo: scene summaries in out/cantilever_summary.json, out/cube_cut_augmented_summary.json," \
  "out/needle_slab_summary.json; needle animation: out/needle_slab.pvd"
echo "demo: certification report in $(pwd)/out/certify/index.html (summary: out/certify/summary.json)"
echo "demo: to put incise on PATH: export PATH=\"$prefix/bin:\$PATH\""
exit "$certify_status"
