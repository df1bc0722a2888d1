#!/usr/bin/env python3
"""Scaling of the reservoir case (cases/reservoir_depletion.toml with [mesh]
elements = [n, n]) against the floor: ONE factorize-and-solve of the uncracked
system on the same mesh, measured in the same run.

    python benchmarks/scaling.py --sizes 50 100 200 400 --solvers superlu amg \
        --runs 3 --json a.json
    python benchmarks/scaling.py --sizes 700 1000 --solvers amg --runs 1 --json b.json
    python benchmarks/scaling.py --merge a.json b.json --plot benchmarks/scaling.png

A solver name with the suffix "/nopred" (e.g. superlu/nopred) runs Newton
without the stick/slip predictor (xfemslip/contact/predictor.py), against the same
floor as the plain solver.

Every measurement runs in its own subprocess so that the peak memory
(resource.getrusage maxrss) belongs to it alone.  For each size and linear
solver: the cracked run (build = mesh, fractures, enrichment, assembly, contact;
Newton = every load step, every linear solve) and the floor (the same mesh
without the fracture: assembly, then one solve of K u = F with the same linear
solver).  Times are the median of --runs runs (each a fresh process, the
configurations interleaved run by run); memory is the largest maxrss of those
runs.  Output files are not written.  Set OPENBLAS_NUM_THREADS=1 on a shared
machine (see benchmarks/RESULTS.md).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "reservoir_depletion.toml"


def case_text(n: int, cracked: bool) -> str:
    from xfemslip.case import build

    keys = {"mesh.elements": [n, n]}
    if not cracked:
        keys["fractures"] = None
    return build.case_text(build.file_case(CASE, **keys))


def one(n: int, solver: str, cracked: bool) -> dict:
    """Measure in this process; returns a dict (printed as JSON)."""
    import resource

    import numpy as np

    from xfemslip.case import loads_case
    from xfemslip.simulation import build_model
    from xfemslip.solve.newton import NewtonSolver

    solver, _, flag = solver.partition("/")
    spec = loads_case(case_text(n, cracked), CASE)
    t0, c0 = time.perf_counter(), time.process_time()
    model = build_model(spec)
    t1, c1 = time.perf_counter(), time.process_time()
    newton = NewtonSolver(
        model.problem,
        spec.solver.tolerance,
        spec.solver.max_iterations,
        spec.solver.tangent,
        solver,
        predictor=flag != "nopred",
    )
    t2, c2 = time.perf_counter(), time.process_time()
    out = {"n": n, "solver": solver + (f"/{flag}" if flag else ""), "cracked": cracked}
    if cracked:
        newton.run(spec.loading.steps)
        res = newton.completed[-1]
        out["iterations"] = [r.iterations for r in newton.completed]
        out["predicted"] = [r.predicted for r in newton.completed]
        out["max_slip"] = float(np.max(np.abs(res.contact.gt)))
        out["contact_dofs"] = int(np.unique(newton.c_dofs[newton.c_dofs >= 0]).size)
    else:
        p = model.problem
        u = np.zeros(p.n_dofs)
        u[p.fixed] = p.fixed_values
        rhs = (p.F_unit - p.K @ u)[newton.free]
        x = newton.linear.solve(None, rhs)
        err = np.linalg.norm(newton.K_ff @ x - rhs) / np.linalg.norm(rhs)
        out["residual"] = float(err)
    t3, c3 = time.perf_counter(), time.process_time()
    st = newton.linear.stats
    out.update(
        dofs=int(model.problem.n_dofs),
        method=st["method"],
        build=t1 - t0,
        setup=t2 - t1,
        solve=t3 - t2,
        total=t3 - t0,
        build_cpu=c1 - c0,
        solve_cpu=c3 - c2,
        factorizations=st["factorizations"],
        factor_time=st["factor_time"],
        amg_setup=st["setup_time"],
        krylov_iterations=st["krylov_iterations"],
        maxrss_mib=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    )
    return out


def run_once(n, solver, cracked, timeout):
    cmd = [sys.executable, __file__, "--one", str(n), solver]
    cmd += ["cracked" if cracked else "floor"]
    base = {"n": n, "solver": solver, "cracked": cracked}
    try:
        proc = subprocess.run(
            cmd, capture_output=True, text=True, timeout=timeout, env=os.environ
        )
    except subprocess.TimeoutExpired:
        return dict(base, error=f"timeout ({timeout:.0f} s)")
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1:] or [f"exit {proc.returncode}"]
        return dict(base, error=tail[0][:80])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def measure(n, configs, runs, timeout):
    """Median of `runs` runs of each (solver, cracked) config; the configs are
    interleaved run by run so that a change of machine load hits all alike."""
    rows = {c: [] for c in configs}
    for _ in range(runs):
        for c in configs:
            if rows[c] and "error" in rows[c][-1]:
                continue
            rows[c].append(run_once(n, *c, timeout))
    out = []
    for c in configs:
        ok = [r for r in rows[c] if "error" not in r]
        if not ok:
            out.append(rows[c][-1])
            continue
        med = dict(ok[0])
        keys = ("build", "setup", "solve", "total", "factor_time", "amg_setup")
        for key in keys + ("build_cpu", "solve_cpu"):
            med[key] = statistics.median(r[key] for r in ok)
        med["maxrss_mib"] = max(r["maxrss_mib"] for r in ok)
        med["runs"] = len(ok)
        out.append(med)
    return out


def table(results) -> str:
    """Markdown table; ratios on CPU time (robust to a shared machine), wall
    times in parentheses."""
    lines = [
        "| n x n | dofs | linear solver | build [s] | Newton [s] | Newton its | "
        "factorizations / Krylov its | peak RSS [MiB] | floor [s] | "
        "floor RSS [MiB] | Newton / floor | Newton / SuperLU floor | "
        "(build + Newton) / (build + floor) |",
        "| " + " | ".join(["---"] * 13) + " |",
    ]
    floors = {(r["n"], r["solver"]): r for r in results if not r["cracked"]}
    for r in results:
        if not r["cracked"]:
            continue
        f = floors.get((r["n"], r["solver"].partition("/")[0]), {})
        f_lu = floors.get((r["n"], "superlu"), {})
        if "error" in r:
            lines.append(f"| {r['n']} | | {r['solver']} | {r['error']} |" + " |" * 9)
            continue
        fl = f.get("solve_cpu")
        ratio = f"{r['solve_cpu'] / fl:.2f}" if fl else "-"
        ratio_lu = (
            f"{r['solve_cpu'] / f_lu['solve_cpu']:.2f}"
            if f_lu.get("solve_cpu")
            else "-"
        )
        whole = (
            f"{(r['build_cpu'] + r['solve_cpu']) / (f['build_cpu'] + fl):.2f}"
            if fl
            else "-"
        )
        floor = f"{fl:.2f} ({f['solve']:.2f})" if fl else f.get("error", "-")
        floor_rss = f"{f['maxrss_mib']:.0f}" if fl else "-"
        flag = r["solver"].partition("/")[2]  # "nopred": without the predictor
        method = r["method"] + (f"/{flag}" if flag else "")
        lines.append(
            f"| {r['n']} | {r['dofs']:,} | {method} | {r['build_cpu']:.2f} | "
            f"{r['solve_cpu']:.2f} ({r['solve']:.2f}) | {sum(r['iterations'])} | "
            f"{r['factorizations']} / {r['krylov_iterations']} | "
            f"{r['maxrss_mib']:.0f} | {floor} | {floor_rss} | {ratio} | {ratio_lu} | "
            f"{whole} |"
        )
    return "\n".join(lines)


def plot(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.0, 3.6), dpi=90)
    styles = {True: "-o", False: "--s"}
    for solver in sorted({r["solver"] for r in results}):
        for cracked in (True, False):
            rows = [
                r
                for r in results
                if r["solver"] == solver
                and r["cracked"] == cracked
                and "error" not in r
            ]
            if not rows:
                continue
            label = f"{solver}: " + ("Newton solve" if cracked else "floor (1 solve)")
            ax.loglog(
                [r["dofs"] for r in rows],
                [r["solve_cpu"] for r in rows],
                styles[cracked],
                label=label,
            )
    ax.set_xlabel("dofs")
    ax.set_ylabel("CPU time [s]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 200])
    ap.add_argument("--solvers", nargs="+", default=["auto", "superlu"])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--timeout", type=float, default=3600.0)
    ap.add_argument("--json", type=Path, help="append the results to this file")
    ap.add_argument("--plot", type=Path, help="write a log-log plot (PNG)")
    ap.add_argument(
        "--merge",
        type=Path,
        nargs="+",
        help="measure nothing: table (and --plot) of these --json files",
    )
    ap.add_argument("--one", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        n, solver, kind = args.one
        print(json.dumps(one(int(n), solver, kind == "cracked")))
        return 0
    if args.merge:
        results = [r for path in args.merge for r in json.loads(path.read_text())]
        results.sort(key=lambda r: (r["n"], r["solver"], not r["cracked"]))
        print(table(results))
        if args.plot:
            plot(results, args.plot)
        return 0
    results = []
    if args.json and args.json.exists():
        results = json.loads(args.json.read_text())
    for n in args.sizes:
        # one floor per linear solver ("x/nopred" shares the floor of "x")
        bases = dict.fromkeys(s.partition("/")[0] for s in args.solvers)
        configs = [(s, False) for s in bases] + [(s, True) for s in args.solvers]
        for r in measure(n, configs, args.runs, args.timeout):
            key = (r["n"], r["solver"], r["cracked"])
            results = [x for x in results if (x["n"], x["solver"], x["cracked"]) != key]
            results.append(r)
            print(json.dumps(r), flush=True)
        if args.json:
            args.json.write_text(json.dumps(results, indent=1))
    results.sort(key=lambda r: (r["n"], r["solver"], not r["cracked"]))
    print(table(results))
    if args.plot:
        plot(results, args.plot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
