#!/usr/bin/env bash
# The main job: install what is missing, build Release, and run incise on the embedded default.
# For now (foundation): `incise mesh check` on the real liver mesh, writing a VTU next to it.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 2)  # not nproc: it honours OMP_NUM_THREADS
ci/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$jobs" --target incise
mkdir -p out
./build/release/lib/cli/incise mesh check reference_data/meshes/liver_coarse.mesh \
  --vtu out/liver_coarse.vtu
echo "demo: wrote out/liver_coarse.vtu (open it in ParaView)"

# The default scene: the thesis cantilever (Table 3.1), then the quick certification report.
echo "== demo: incise run reference_data/scenes/cantilever.json"
./build/release/lib/cli/incise run reference_data/scenes/cantilever.json \
  --summary-json out/cantilever_summary.json
# The augmented-solver cutting demo: the solution is updated after every sweep triangle.
echo "== demo: incise run reference_data/scenes/cube_cut_augmented.json"
./build/release/lib/cli/incise run reference_data/scenes/cube_cut_augmented.json \
  --summary-json out/cube_cut_augmented_summary.json --progress none
# Needle insertion in 2D (thesis ch. 6, §6.8.1 slab): a per-update CSV and a VTU series with its
# ParaView index out/needle_slab.pvd (open it in ParaView and press play).
echo "== demo: incise run reference_data/scenes/needle_slab.json"
./build/release/lib/cli/incise run reference_data/scenes/needle_slab.json \
  --summary-json out/needle_slab_summary.json --progress none
echo "== demo: incise certify --quick"
certify_status=0
./build/release/lib/cli/incise certify --quick --out out/certify || certify_status=$?
echo "demo: scene summaries in out/cantilever_summary.json, out/cube_cut_augmented_summary.json," \
  "out/needle_slab_summary.json; needle animation: out/needle_slab.pvd"
echo "demo: certification report in $(pwd)/out/certify/index.html (summary: out/certify/summary.json)"
exit "$certify_status"
