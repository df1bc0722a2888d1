#!/usr/bin/env python3
"""Build and solve time of a 30-fracture random network (realization 1 of
cases/sweeps/dfn_realizations.toml) with branch and ramp tips, SuperLU and
AMG linear solvers.

    PYTHONPATH=$PWD python benchmarks/network_solve.py [--mesh 100] [--runs 3]
        [--steps 4] [--tips branch,ramp] [--solvers superlu,amg]

The network is that of the sweep (seed 1, two sets, 30 fractures, 60 tips);
the stress path is that of cases/fracture_network.toml (in-situ stress
sigma_xx = -20, sigma_yy = -40 MPa before step 1, sigma_xx then drops to
-12 MPa in --steps steps) so that fractures slip and Newton iterates.  The
variants are run interleaved (variant A, B, ..., A, B, ...) after one warm-up
build and solve of each, and the medians of CPU time (process_time: the
machine is shared) are printed with the dofs, the enriched functions, the
largest number of enrichment slots of a cell, the Newton iterations and the
linear solver's factorizations.
"""

from __future__ import annotations

import argparse
import logging
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def case_text(mesh: int, tip: str, solver: str, steps: int) -> str:
    from xfemslip.case import build

    sweep = build.file_case(ROOT / "cases" / "sweeps" / "dfn_realizations.toml")
    keys = {
        "name": "dfn-solve",
        "network.tip": tip,
        "mesh.elements": [mesh, mesh],
        "loading.initial_stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0},
        "loading.stress": {"xx": -8.0e6, "yy": -40.0e6, "xy": 0.0},
        "loading.steps": steps,
        "solver.linear_solver": solver,
    }
    return build.case_text(build.with_keys(sweep["base"], **keys))


def one_run(text: str) -> dict:
    from xfemslip.case import loads_case
    from xfemslip.simulation import build_model, newton_solver

    spec = loads_case(text)
    t0 = time.process_time()
    model = build_model(spec)
    t1 = time.process_time()
    ns = newton_solver(model)
    results = ns.run(spec.loading.steps)
    t2 = time.process_time()
    st = ns.linear.stats
    return {
        "build": t1 - t0,
        "solve": t2 - t1,
        "factor": st["factor_time"],
        "factorizations": st["factorizations"],
        "krylov": st["krylov_iterations"],
        "newton": sum(r.iterations for r in results),
        "dofs": model.problem.n_dofs,
        "enriched": model.bulk.dofmap.n_enriched_functions,
        "S": model.ec.slot_cand.shape[1],
        "method": st["method"],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=int, default=100)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--tips", default="branch,ramp")
    ap.add_argument("--solvers", default="superlu,amg")
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    variants = [
        (tip, solver)
        for tip in args.tips.split(",")
        for solver in args.solvers.split(",")
    ]
    texts = {v: case_text(args.mesh, *v, args.steps) for v in variants}
    for v in variants:
        one_run(texts[v])  # warm-up: Numba kernels, imports
    runs = {v: [] for v in variants}
    for _ in range(args.runs):
        for v in variants:
            runs[v].append(one_run(texts[v]))
    print(
        f"realization 1 (30 fractures), {args.mesh} x {args.mesh} cells, "
        f"{args.steps} steps, {args.runs} interleaved runs, CPU s (median)"
    )
    print(
        f"{'tips':7s} {'solver':8s} {'dofs':>7s} {'enr fn':>7s} {'S':>3s} "
        f"{'newton':>6s} {'facts':>5s} {'krylov':>6s} {'build':>7s} "
        f"{'factor':>7s} {'solve':>7s}"
    )
    for (tip, _solver), rs in runs.items():
        r0 = rs[0]

        def med(key, rs=rs):
            return statistics.median(r[key] for r in rs)

        print(
            f"{tip:7s} {r0['method']:8s} {r0['dofs']:7d} {r0['enriched']:7d} "
            f"{r0['S']:3d} {r0['newton']:6d} {r0['factorizations']:5d} "
            f"{r0['krylov']:6d} {med('build'):7.2f} {med('factor'):7.2f} "
            f"{med('solve'):7.2f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
