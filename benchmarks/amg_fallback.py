#!/usr/bin/env python3
"""What a failed AMG attempt costs before the fall-back to SuperLU.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/amg_fallback.py \
        [--h 0.0125] [--runs 2]

Case: the graded mesh of benchmarks/ogs_compare.py (cells of size h around
the 2 m crack, growing by 1.3 per cell to a 20 m box: cells up to 146:1 at
h = 0.0125, 58k dofs), on which the AMG-preconditioned GMRES does not
converge.  The run is solved with linear_solver = "amg" forced, with and
without the stall stop (linsolve.AMG_STALL_STOP), and with "superlu",
interleaved; printed are the CPU times (time.process_time) of the whole
Newton run, its wall time, and the wall time of the AMG attempt that was
thrown away (set-up, band LU, Krylov iterations: stats["amg_fallback_time"],
which like every linsolve time is wall time), medians of --runs.
"""

from __future__ import annotations

import argparse
import logging
import statistics
import time

from xfemslip.reference.peer import case_table


def one(spec, method: str, stall_stop: bool) -> dict:
    from xfemslip.simulation import build_model
    from xfemslip.solve import linear as linsolve
    from xfemslip.solve.newton import NewtonSolver

    linsolve.AMG_STALL_STOP = stall_stop
    model = build_model(spec)
    opt = spec.solver
    t0, w0 = time.process_time(), time.perf_counter()
    ns = NewtonSolver(
        model.problem, opt.tolerance, opt.max_iterations, opt.tangent, method
    )
    steps = ns.run(spec.loading.steps)
    cpu, wall = time.process_time() - t0, time.perf_counter() - w0
    st = ns.linear.stats
    return {
        "cpu": cpu,
        "wall": wall,
        "wasted": st["amg_fallback_time"],
        "fallbacks": st["amg_fallbacks"],
        "krylov": st["krylov_iterations"],
        "factor": st["factor_time"],
        "factorizations": st["factorizations"],
        "newton": sum(s.iterations for s in steps),
        "dofs": int(ns.free.size),
        "aspect": linsolve.cell_aspect_ratio(model.problem.node_xy),
    }


def main(argv=None) -> int:
    from xfemslip.case import build, loads_case

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, default=0.0125)
    ap.add_argument("--runs", type=int, default=2)
    args = ap.parse_args(argv)
    logging.disable(logging.WARNING)
    spec = loads_case(build.case_text(case_table(args.h)), "graded.toml")
    variants = [("amg", True), ("amg", False), ("superlu", True)]
    one(spec, "superlu", True)  # warm-up
    runs = {v: [] for v in variants}
    for _ in range(args.runs):
        for v in variants:
            runs[v].append(one(spec, *v))
    r0 = runs[variants[-1]][0]
    print(
        f"graded mesh h = {args.h}: {r0['dofs']:,} free dofs, cells up to "
        f"{r0['aspect']:.0f}:1; {args.runs} interleaved runs, CPU s (median)"
    )
    print(
        "| linear solver | stall stop | Newton its | AMG fall-backs | Krylov its "
        "| AMG time lost, wall [s] | factorizations | run, wall [s] | run, CPU [s] |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for (method, stop), rs in runs.items():
        a = rs[0]
        print(
            f"| {method} | {'yes' if stop else 'no'} | {a['newton']} | "
            f"{a['fallbacks']} | {a['krylov']} | "
            f"{statistics.median(r['wasted'] for r in rs):.2f} | "
            f"{a['factorizations']} | {statistics.median(r['wall'] for r in rs):.2f} | "
            f"{statistics.median(r['cpu'] for r in rs):.2f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
