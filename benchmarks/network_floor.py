#!/usr/bin/env python3
"""The 100-fracture network on 200 x 200 cells with branch tips (the network
of benchmarks/network_build.py, seed 6) against the PARDISO floor: one SPD
factorize-and-solve of the uncracked mesh, assembly included.

    MKL_NUM_THREADS=2 OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=2 \\
    PYTHONPATH=$PWD python benchmarks/network_floor.py [--count 100] [--n 200] \\
        [--solvers superlu,pardiso]

Each configuration runs in its own process (build, Newton over the load
step, no output written), the configurations one after the other; printed
per configuration: wall and CPU time of build and Newton, Newton iterations,
linear solves, PARDISO and SuperLU factorizations, the time in
factorizations (factor_time) and in all linear solves (solve_time), and
peak memory.  The floor is the same mesh without fractures.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
import json, resource, sys, time
sys.path.insert(0, {bench!r})
t0 = time.perf_counter(); c0 = time.process_time()
import numpy as np
from network_build import case_text, network
from xfemslip.case import loads_case
from xfemslip.simulation import build_model, newton_solver
count, n, solver = {count}, {n}, {solver!r}
fracs = network(count) if solver != "floor" else []
text = case_text(fracs, n, "branch")
text += '\\n[solver]\\nlinear_solver = "' + (
    "pardiso" if solver == "floor" else solver) + '"\\n'
spec = loads_case(text, "network.toml")
model = build_model(spec)
t1 = time.perf_counter(); c1 = time.process_time()
out = dict(dofs=int(model.problem.n_dofs))
if solver == "floor":
    import pypardiso, scipy.sparse as sp
    p = model.problem
    free = np.ones(p.n_dofs, bool); free[p.fixed] = False
    K = p.K[free][:, free].tocsr()
    A = sp.triu(K, format="csr"); A.sort_indices()
    x = pypardiso.PyPardisoSolver(mtype=2).solve(A, np.asarray(p.F_unit)[free])
else:
    s = newton_solver(model)
    res = s.run(spec.loading.steps)
    st = s.linear.stats
    out.update(newton_its=sum(r.iterations for r in res),
               stats={{k: v for k, v in st.items() if v}})
t2 = time.perf_counter(); c2 = time.process_time()
out.update(build_wall=t1 - t0, build_cpu=c1 - c0, solve_wall=t2 - t1,
           solve_cpu=c2 - c1,
           maxrss_mib=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
print(json.dumps(out))
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--solvers", default="floor,superlu,pardiso")
    a = ap.parse_args()
    for solver in a.solvers.split(","):
        code = CHILD.format(
            bench=str(ROOT / "benchmarks"), count=a.count, n=a.n, solver=solver
        )
        with tempfile.TemporaryDirectory() as tmp:
            proc = subprocess.run(
                [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp
            )
        if proc.returncode != 0:
            print(solver, "failed:", proc.stderr.strip().splitlines()[-1:])
            continue
        row = json.loads(proc.stdout.strip().splitlines()[-1])
        print(solver, json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
