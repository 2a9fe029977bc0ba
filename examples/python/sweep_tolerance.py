#!/usr/bin/env python3
"""Speed versus accuracy of linear CG on the thesis cantilever (Table 3.1 geometry), swept over
mesh size and stopping tolerance, from Python (docs/python.md).

For each mesh (nx = 4k, ny = nz = k cells of 6 tetrahedra) and each tolerance, runs the scene with
the incise module and records iterations, solver time and the tip deflection; the error of each
run is measured against the same mesh's run at the tightest tolerance (the discretisation error
against beam theory is printed beside it). Writes sweep.csv and sweep.png (error vs solver time,
one line per mesh) to --out.

    PYTHONPATH=build/release/python python3 examples/python/sweep_tolerance.py --out out/sweep
"""

import argparse
import csv
import os

import incise

BEAM_THEORY = 8.64e-3  # Euler-Bernoulli tip deflection of the Table 3.1 beam (m)


def scene(k, tolerance):
    return {
        "version": 1,
        "name": "cantilever %dx%dx%d, tolerance %g" % (4 * k, k, k, tolerance),
        "mesh": {"type": "box", "nx": 4 * k, "ny": k, "nz": k, "lx": 1.2, "ly": 0.2, "lz": 0.3,
                 "split": "six"},
        "material": {"model": "linear", "E": 1.0e6, "nu": 0.0},
        "fixed": [{"type": "plane", "axis": "x", "value": 0.0}],
        "loads": [{"type": "nodal", "region": {"type": "plane", "axis": "x", "value": 1.2},
                   "total_force": [0.0, -3.0, 0.0]}],
        "solver": {"method": "cg", "tolerance": tolerance, "max_iterations": 100000},
        "outputs": {"probes": [{"name": "tip",
                                "region": {"type": "plane", "axis": "x", "value": 1.2}}]},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[2, 4, 8])
    ap.add_argument("--tolerances", type=float, nargs="+", default=[1e-2, 1e-4, 1e-6, 1e-8])
    ap.add_argument("--out", default="out/sweep")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    tolerances = sorted(args.tolerances, reverse=True)
    rows = []
    for k in args.sizes:
        runs = [incise.run_scene(scene(k, t)) for t in tolerances]
        for t, r in zip(tolerances, runs):
            if not r.converged:
                raise SystemExit("k=%d tolerance %g: %s" % (k, t, r.summary["message"]))
        best = -runs[-1].summary["probes"][0]["displacement"][1]
        for t, r in zip(tolerances, runs):
            tip = -r.summary["probes"][0]["displacement"][1]
            rows.append({"k": k, "tets": r.summary["mesh"]["tetrahedra"], "tolerance": t,
                         "iterations": r.summary["iterations"],
                         "solver_seconds": r.summary["solver_seconds"], "tip_m": tip,
                         "error_vs_tightest": abs(tip - best) / best,
                         "error_vs_beam_theory": abs(tip - BEAM_THEORY) / BEAM_THEORY})
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print("k=%(k)d tets=%(tets)d tol=%(tolerance)g it=%(iterations)d "
              "t=%(solver_seconds).4f s err=%(error_vs_tightest).2e "
              "(beam theory %(error_vs_beam_theory).3f)" % r)
    import matplotlib
    matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    for k in args.sizes:
        pts = [r for r in rows if r["k"] == k and r["error_vs_tightest"] > 0]
        if pts:
            ax.loglog([r["solver_seconds"] for r in pts], [r["error_vs_tightest"] for r in pts],
                      "o-", label="%d tets" % pts[0]["tets"])
    ax.set_xlabel("solver time (s, CPU of this machine)")
    ax.set_ylabel("tip error vs tightest tolerance")
    ax.set_title("linear CG: speed vs accuracy (cantilever)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "sweep.png"), dpi=100)
    print("wrote", os.path.join(args.out, "sweep.csv"), "and", os.path.join(args.out, "sweep.png"))


if __name__ == "__main__":
    main()
