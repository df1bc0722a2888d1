#!/usr/bin/env python3
"""Where AMG stops paying: SuperLU against AMG on the same Newton systems of
generated fracture networks, by mesh size, fracture count and tip.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=$PWD python benchmarks/auto_choice.py \
        --mesh 100 --counts 1,10,30,100 --tips ramp,branch [--steps 2] \
        [--runs 2] [--max-systems 8] [--json out.json] [--source dfn|build]
    python benchmarks/auto_choice.py --merge a.json b.json ... \
        --markdown docs/performance/auto_choice.md

Case: the 20-realization sweep's network (cases/sweeps/dfn_realizations.toml,
seed 1, two sets, lengths 0.12-0.4 m) with `count` generated fractures on
mesh x mesh cells, the stress path of benchmarks/network_solve.py (in-situ
sigma_xx = -20, sigma_yy = -40 MPa, then sigma_xx to -8 MPa in --steps steps)
so that fractures slip and Newton iterates.  With --source build: the
seed-6 network of benchmarks/network_build.py (straight fractures of
0.08-0.25 m, uniform orientations) on its own stress path (1 load step).

For each configuration the model is built once and run with
linear_solver = "superlu", recording every Newton system (K_ff + K_c, r) it
solves (at most --max-systems: the run is stopped after them, the machine is
shared).  That sequence is then solved --runs times by a fresh LinearSolver of
each method, interleaved (superlu, amg, superlu, amg, ...), and the median CPU
time (time.process_time, single-threaded BLAS) of the whole sequence is
printed: for amg it includes the AMG set-up, the band LUs and GMRES, for
superlu the factorizations and the kept-factorization GMRES.  Printed with it
are the inputs "auto" can see before the first solve: free dofs, the enriched
share of them, and the share of the AMG band (enriched dofs and
AMG_BAND_LAYERS matrix neighbours), and what choose("auto", ...) picks.
"""

from __future__ import annotations

import argparse
import json
import logging
import re
import statistics
import sys
import time
from pathlib import Path

import mdtable
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from network_solve import case_text as _network_text  # noqa: E402

MARK = {"yes": "", "stopped": "+", "failed": " (run failed)"}


class _Enough(Exception):
    pass


def case_text(mesh: int, count: int, tip: str, steps: int, source="dfn") -> str:
    if source == "build":  # the seed-6 network of network_build.py, 1 step
        import network_build

        text = network_build.case_text(network_build.network(count), mesh, tip)
        return text + '[solver]\nlinear_solver = "superlu"\n'
    text = _network_text(mesh, tip, "superlu", steps)
    return re.sub(r"count = \d+", f"count = {count}", text, count=1)


def record(text: str, max_systems: int):
    """Build, run with SuperLU; the Newton systems (Kc, r) and model facts."""
    from xfemslip.case import loads_case
    from xfemslip.errors import ConvergenceError
    from xfemslip.simulation import build_model, newton_solver
    from xfemslip.solve import linear as linsolve

    spec = loads_case(text, "auto_choice.toml")
    t0 = time.process_time()
    model = build_model(spec)
    t1 = time.process_time()
    ns = newton_solver(model)
    systems = []
    solve = ns.linear.solve

    def rec(Kc, r):
        x = solve(Kc, r)  # a singular system raises: not recorded
        systems.append((None if Kc is None else sp.csr_matrix(Kc), r.copy()))
        if len(systems) >= max_systems:
            raise _Enough
        return x

    ns.linear.solve = rec
    try:
        ns.run(spec.loading.steps)
        finished = "yes"
    except _Enough:
        finished = "stopped"
    except ConvergenceError:  # the systems solved until then still count
        finished = "failed"
    node_xy = model.problem.node_xy
    facts = linsolve.system_facts(ns.K_ff, ns.free, node_xy)
    return (
        ns,
        systems,
        {
            "build": t1 - t0,
            "fractures": len(model.fractures),
            "n_free": int(ns.free.size),
            "enriched_share": facts["enriched_share"],
            "band_share": facts["band_share"],
            "auto": linsolve.choose("auto", ns.free.size, node_xy, facts["band_share"]),
            "systems": len(systems),
            "run_finished": finished,
        },
    )


def replay(ns, systems, method: str) -> dict:
    from xfemslip.solve.linear import LinearSolver

    t0 = time.process_time()
    ls = LinearSolver(ns.K_ff, method, ns.free, ns.p.node_xy)
    for Kc, r in systems:
        ls.solve(Kc, r)
    st = ls.stats
    return {
        "cpu": time.process_time() - t0,
        "factorizations": st["factorizations"],
        "krylov": st["krylov_iterations"],
        "amg_fallbacks": st.get("amg_fallbacks", 0),
        "method_end": st["method"],
    }


HEADER = [
    "network",
    "cells",
    "tips",
    "fractures",
    "free dofs",
    "enriched",
    "band",
    "systems",
    "SuperLU",
    "AMG",
    "AMG / SuperLU",
    "SuperLU factorizations",
    "AMG Krylov its",
]


def markdown(rows: list[dict]) -> str:
    """The table of docs/performance/auto_choice.md from the rows of one or
    more runs (their --json files): CPU seconds of the whole sequence of
    Newton systems, medians of the interleaved replays."""
    cells = [
        [
            r["source"],
            f"{r['mesh']}²",
            r["tip"],
            r["fractures"],
            f"{r['n_free']:,}",
            f"{r['enriched_share']:.1%}".replace("%", " %"),
            f"{r['band_share']:.1%}".replace("%", " %"),
            f"{r['systems']}{MARK[r['run_finished']]}",
            f"{r['superlu']:.2f} s",
            f"{r['amg']:.2f} s",
            f"{r['ratio']:.2f}",
            r["superlu_factorizations"],
            f"{r['amg_krylov']}" + (", fell back" if r["amg_fallbacks"] else ""),
        ]
        for r in rows
    ]
    replays = sorted({len(r["runs"]["amg"]) for r in rows})
    loads = [x for r in rows for x in r.get("loads", [])]
    counts = f"{replays[0]}" + (f"-{replays[-1]}" if len(replays) > 1 else "")
    how = (
        "CPU time (process_time, one BLAS thread) of the recorded Newton systems "
        f"(+: the run was stopped there), median of {counts} interleaved replays"
    )
    return mdtable.table(HEADER, cells) + mdtable.note(how, loads)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=int, default=100)
    ap.add_argument("--counts", default="1,10,30,100")
    ap.add_argument("--tips", default="ramp,branch")
    ap.add_argument("--steps", type=int, default=2)
    ap.add_argument("--runs", type=int, default=2)
    ap.add_argument("--max-systems", type=int, default=8)
    ap.add_argument("--json", type=Path)
    ap.add_argument(
        "--merge", nargs="+", type=Path, help="JSON files to merge (no runs)"
    )
    mdtable.add_option(ap, "docs/performance/auto_choice.md")
    ap.add_argument(
        "--source",
        choices=("dfn", "build"),
        default="dfn",
        help="dfn: the sweep's generated network; build: network_build.py's "
        "seed-6 network (its own stress path, 1 step)",
    )
    args = ap.parse_args(argv)
    if args.merge:
        rows = [r for f in args.merge for r in json.loads(f.read_text())]
        mdtable.write(args.markdown, markdown(rows))
        return 0
    logging.disable(logging.WARNING)
    rows = []
    print(
        f"{args.source} network, {args.mesh} x {args.mesh} cells, "
        f"{args.steps if args.source == 'dfn' else 1} steps, <= "
        f"{args.max_systems} Newton systems, {args.runs} interleaved replays, "
        "CPU s (median)",
        flush=True,
    )
    print(
        "| tips | fractures | free dofs | enriched | band | auto | systems "
        "| superlu [s] | amg [s] | amg / superlu | superlu facts | amg Krylov its |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|", flush=True)
    for tip in args.tips.split(","):
        for count in map(int, args.counts.split(",")):
            text = case_text(args.mesh, count, tip, args.steps, args.source)
            ns, systems, row = record(text, args.max_systems)
            out = {"superlu": [], "amg": []}
            replay(ns, systems[:1], "amg")  # warm-up (imports)
            for _ in range(args.runs):
                for method in out:
                    out[method].append(replay(ns, systems, method))
            med = {m: statistics.median(r["cpu"] for r in rs) for m, rs in out.items()}
            row.update(
                mesh=args.mesh,
                tip=tip,
                count=count,
                source=args.source,
                superlu=med["superlu"],
                amg=med["amg"],
                ratio=med["amg"] / med["superlu"],
                runs={m: [r["cpu"] for r in rs] for m, rs in out.items()},
                superlu_factorizations=out["superlu"][0]["factorizations"],
                amg_krylov=out["amg"][0]["krylov"],
                amg_fallbacks=out["amg"][0]["amg_fallbacks"],
                loads=[mdtable.load()],
            )
            rows.append(row)
            print(
                f"| {tip} | {row['fractures']} | {row['n_free']:,} | "
                f"{row['enriched_share']:.1%} | {row['band_share']:.1%} | "
                f"{row['auto']} | {row['systems']}{MARK[row['run_finished']]} | "
                f"{med['superlu']:.2f} | {med['amg']:.2f} | {row['ratio']:.2f} | "
                f"{row['superlu_factorizations']} | {row['amg_krylov']}"
                f"{' (fell back)' if row['amg_fallbacks'] else ''} |",
                flush=True,
            )
            del ns, systems
            if args.json:
                args.json.write_text(json.dumps(rows, indent=1))
    if args.markdown:
        mdtable.write(args.markdown, markdown(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
