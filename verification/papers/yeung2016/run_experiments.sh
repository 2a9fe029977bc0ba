#!/usr/bin/env bash
# Runs the Yeung, Crouch & Pothen 2016 §4.3 experiments (beams, bricks, liver; deformation and
# cutting) with benchmarks/linalg/augmented_bench and writes one Markdown table (.md) and one CSV
# per run into OUT; then `yeung2016_plots OUT` draws the SVG figures (README.md).
# Usage: run_experiments.sh BUILD_DIR OUT_DIR [quick|headline]
# Expected runtime: ≈ 15 min on the shared (loaded) 2-core machine, less when idle; quick ≈ 2 min.
# headline: only the runs behind README.md's "Headline" (25,600-node beam, 8 steps, explicit
# H R⁻¹ J; one and two threads on both sides; each configuration twice), ≈ 3 min loaded.
set -euo pipefail
build=${1:?build dir}
out=${2:?output dir}
quick=${3:-}
bench="$build/benchmarks/linalg/augmented_bench"
mkdir -p "$out"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
run() {  # name, args...
  local name=$1
  shift
  echo "== $name: augmented_bench --table $*" >&2
  "$bench" --table "$@" --csv "$out/$name.csv" >"$out/$name.md"
}
if [[ "$quick" == headline ]]; then
  # Thread counts: update T (step 3) / reference refactorization. CHOLMOD's simplicial
  # factorization is serial; the supernodal one gets T OpenBLAS threads (--threads sets both).
  # Each exact run has a --no-exact twin (NAME_upd) for the update times (see twin() below);
  # the supernodal runs share the twin of the simplicial run with the same T.
  for rep in 1 2; do
    for kind in deform cut; do
      for t in 1 2; do
        run "headline_${kind}_t${t}_simplicial_$rep" "$kind" --h 1024 --steps 8 --schur direct \
          --threads "$t"
        run "headline_${kind}_t${t}_upd_$rep" "$kind" --h 1024 --steps 8 --schur direct \
          --threads "$t" --no-exact
      done
      run "headline_${kind}_t2_supernodal_$rep" "$kind" --h 1024 --steps 8 --schur direct \
        --threads 2 --ref-kind supernodal
    done
  done
  echo "done: $out" >&2
  exit 0
fi
if [[ "$quick" == quick ]]; then
  beams=(16 64)
  bricks=(4 8)
  big_steps=8
else
  beams=(16 64 256 1024)
  bricks=(4 8 12 16 20)
  big_steps=32
fi
# A run and its --no-exact twin (NAME_upd): the same steps without the reference
# refactorization in between, whose update times the README's speed-ups use
# (yeung2016_plots --table NAME.csv --update-times NAME_upd.csv).
twin() {  # name, args...
  local name=$1
  shift
  run "$name" "$@"
  run "${name}_upd" "$@" --no-exact --pcg-every 0
}
# The 25,600-node beam (Fig. 5a, 7a, 11b): long runs, Jacobi-PCG every 8th/16th step.
h_big=${beams[-1]}
twin "beam${h_big}_deform" deform --h "$h_big" --steps "$big_steps" --pcg-every 16 --pcg-seconds 20
twin "beam${h_big}_cut" cut --h "$h_big" --steps 16 --pcg-every 8 --pcg-seconds 20
# The ≥ 50× target (README "Targets"): step 3 on two threads, eq. 17 preconditioned by the
# explicit H R⁻¹ J (capacitance form); for comparison the cut with the HSJ and SPAI
# preconditioners.
twin "t2_direct_beam${h_big}_deform" deform --h "$h_big" --steps "$big_steps" --schur direct --threads 2
twin "t2_direct_beam${h_big}_cut" cut --h "$h_big" --steps 16 --schur direct --threads 2
twin "t2_beam${h_big}_cut" cut --h "$h_big" --steps 16 --threads 2
twin "spai_beam${h_big}_cut" cut --h "$h_big" --steps 16 --precond spai
twin "t2_spai_beam${h_big}_cut" cut --h "$h_big" --steps 16 --precond spai --threads 2
# Size series (Fig. 6, 9, 11a): 16 steps, PCG at steps 0, 8, 16.
for h in "${beams[@]}"; do
  [[ "$h" == "$h_big" ]] && continue
  run "beam${h}_deform" deform --h "$h" --steps 16 --pcg-every 8 --pcg-seconds 20
  run "beam${h}_cut" cut --h "$h" --steps 16 --pcg-every 8 --pcg-seconds 20
done
# Bricks 1×1×2 at five resolutions (§4.2 item 2), supernodal reference refactorization.
for n in "${bricks[@]}"; do
  run "brick${n}_deform" deform --brick "$n" --steps 16 --pcg-every 4 --pcg-seconds 20 --ref-kind supernodal
  run "brick${n}_cut" cut --brick "$n" --steps 16 --pcg-every 4 --pcg-seconds 20 --ref-kind supernodal
done
# The liver of reference_data (irregular organ mesh).
run liver_deform deform --mesh liver --steps 16 --pcg-every 4 --pcg-seconds 20 --ref-kind supernodal
run liver_cut cut --mesh liver --steps 16 --pcg-every 4 --pcg-seconds 20 --ref-kind supernodal
# Eq. 17 with the explicit H R⁻¹ J as GMRES preconditioner (SchurSolver::kDirectCached).
if [[ "$quick" != quick ]]; then
  twin direct_beam1024_deform deform --h 1024 --steps 32 --schur direct
  twin direct_beam1024_cut cut --h 1024 --steps 16 --schur direct
  run direct_brick16_deform deform --brick 16 --steps 16 --schur direct --ref-kind supernodal
  run direct_brick16_cut cut --brick 16 --steps 16 --schur direct --ref-kind supernodal
fi
run direct_liver_deform deform --mesh liver --steps 16 --schur direct --ref-kind supernodal
run direct_liver_cut cut --mesh liver --steps 16 --schur direct --ref-kind supernodal
echo "done: $out" >&2
