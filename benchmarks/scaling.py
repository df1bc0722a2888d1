#!/usr/bin/env python3
"""Scaling of the reservoir case (cases/reservoir_depletion.toml with [mesh]
elements = [n, n]) against the floors, whole processes, in the same run.

    MKL_NUM_THREADS=2 OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=2 \\
    python benchmarks/scaling.py --sizes 50 100 200 400 --runs 3 --json a.json
    python benchmarks/scaling.py --sizes 700 1000 --runs 1 --json b.json
    python benchmarks/scaling.py --merge a.json b.json --plot scaling.png \
        --markdown docs/performance/scaling.md

Per size, each in its own process (python -c ..., wall time from the parent
from start to exit, CPU time and peak memory (ru_maxrss) of that child alone,
os.wait4):

- default: ``xfemslip run`` of the cracked case as installed without the mkl
  extra (pypardiso hidden from the child: sys.modules["pypardiso"] = None),
  linear_solver "auto"; results written (h5 + vtu) as a user's run does;
- pardiso: the same run with the extra installed ("auto" takes PARDISO);
- floor PARDISO: the uncracked case's model built by xfemslip (mesh,
  assembly), then ONE factorize-and-solve of K_ff u = F by pypardiso in SPD
  mode (mtype 2, upper triangle), imports included;
- floor SuperLU: the same with scipy's SuperLU (minimum degree on A^T + A,
  symmetric mode), up to --superlu-max n.

Times are medians of --runs runs, the configurations alternated within each
run (run 1 of every configuration and size, then run 2, ...); memory is the
largest of the runs.  xfemslip's sources are byte-compiled first (as an
installed package is), and a warm-up run of each configuration at the
smallest size compiles and caches the Numba kernels.  The thread counts of the
children are those of this process's environment (say which in the report).
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "reservoir_depletion.toml"
CONFIGS = ("default", "pardiso", "floor_pardiso", "floor_superlu")


def case_text(n: int, cracked: bool, out: str) -> str:
    from xfemslip.case import build

    keys = {"mesh.elements": [n, n], "output.directory": out}
    if not cracked:
        keys["fractures"] = None
    return build.case_text(build.file_case(CASE, **keys))


RUN = """
import sys
{hide}
from xfemslip.cli import main
sys.argv = ["xfemslip", "run", "-q", "--overwrite", {case!r}]
main()
"""

FLOOR = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np, scipy.sparse as sp
from xfemslip.case import load_case
from xfemslip.simulation import build_model
model = build_model(load_case({case!r}))
p = model.problem
free = np.ones(p.n_dofs, bool); free[p.fixed] = False
K = p.K[free][:, free].tocsr()
F = np.asarray(p.F_unit)[free]
t1 = time.perf_counter()
if {solver!r} == "pardiso":
    import pypardiso
    s = pypardiso.PyPardisoSolver(mtype=2)
    A = sp.triu(K, format="csr"); A.sort_indices()
    x = s.solve(A, F)
else:
    from scipy.sparse.linalg import splu
    lu = splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={{"SymmetricMode": True}})
    x = lu.solve(F)
t2 = time.perf_counter()
r = np.abs(K @ x - F).max() / np.abs(F).max()
print(json.dumps(dict(dofs=int(K.shape[0]), build=t1 - t0, solve=t2 - t1,
                      residual=float(r))))
"""


def child(n: int, config: str, work: Path, timeout: float) -> dict:
    cracked = not config.startswith("floor")
    case = work / f"{config}_{n}.toml"
    case.write_text(case_text(n, cracked, str(work / f"out_{config}_{n}")))
    if cracked:
        hide = 'sys.modules["pypardiso"] = None' if config == "default" else ""
        code = RUN.format(hide=hide, case=str(case))
    else:
        code = FLOOR.format(case=str(case), solver=config.split("_")[1])
    log = work / "child.log"
    start = time.perf_counter()
    with open(log, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-c", code], stdout=fh, stderr=subprocess.STDOUT, cwd=work
        )
        timer = threading.Timer(timeout, proc.kill)
        timer.start()
        # wait4: the exit status and the resource usage of this child alone
        _, status, usage = os.wait4(proc.pid, 0)
        timer.cancel()
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    out = log.read_text()
    if proc.returncode != 0:
        return {"error": out.strip().splitlines()[-1:] or ["killed"]}
    row = {
        "wall": wall,
        "cpu": usage.ru_utime + usage.ru_stime,
        "maxrss_mib": usage.ru_maxrss / 1024.0,
    }
    if not cracked:
        row.update(json.loads(out.strip().splitlines()[-1]))
    else:
        import h5py

        with h5py.File(work / f"out_{config}_{n}" / "result.h5", "r") as f:
            row["dofs"] = int(f.attrs["n_dofs"])
            row["newton_its"] = int(f.attrs["newton_iterations"])
    return row


def measure(sizes, runs, superlu_max, timeout, log):
    configs = {
        n: [c for c in CONFIGS if c != "floor_superlu" or n <= superlu_max]
        for n in sizes
    }
    samples = {(n, c): [] for n in sizes for c in configs[n]}
    # an installed package is byte-compiled (pip does it); an editable one
    # under PYTHONDONTWRITEBYTECODE=1 would compile xfemslip's sources in
    # every child (0.2 s), which neither a user nor the floor pays
    compileall.compile_dir(str(ROOT / "xfemslip"), quiet=1)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for c in CONFIGS:  # warm-up: Numba's cache, the OS file cache
            child(min(sizes), c, work, timeout)
        for k in range(runs):
            for n in sizes:
                for c in configs[n]:
                    row = child(n, c, work, timeout)
                    row["load"] = mdtable.load()
                    samples[(n, c)].append(row)
                    log(f"run {k + 1} n={n} {c}: {row}")
    out = []
    for (n, c), rows in samples.items():
        ok = [r for r in rows if "error" not in r]
        if not ok:
            out.append({"n": n, "config": c, "error": str(rows[0]["error"])})
            continue
        entry = {"n": n, "config": c, "runs": len(ok), "dofs": ok[0]["dofs"]}
        for key in ("wall", "cpu", "build", "solve", "newton_its"):
            if key in ok[0]:
                entry[key] = statistics.median(r[key] for r in ok)
        entry["maxrss_mib"] = max(r["maxrss_mib"] for r in ok)
        entry["loads"] = [r["load"] for r in ok]
        entry["threads"] = thread_settings()
        out.append(entry)
    return out


def thread_settings() -> str:
    return ", ".join(
        f"{k}={os.environ.get(k, 'unset')}"
        for k in ("MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")
    )


HEADER = [
    "n x n",
    "dofs",
    "default [s]",
    "pardiso [s]",
    "floor PARDISO [s]",
    "floor SuperLU [s]",
    "default / floor P",
    "pardiso / floor P",
    "default / floor S",
    "CPU default / pardiso / floor P [s]",
    "peak RSS default / pardiso / floor P [MiB]",
]


def table(results) -> str:
    """The table of docs/performance/scaling.md, with its note (runs,
    threads, machine, the load averages sampled after each child)."""
    by = {(r["n"], r["config"]): r for r in results}
    sizes = sorted({r["n"] for r in results})
    rows = []

    def g(n, c, key, fmt="{:.2f}"):
        r = by.get((n, c))
        if r is None or key not in r:
            return "-" if r is None or "error" not in r else r["error"][:20]
        return fmt.format(r[key])

    def ratio(n, a, b):
        ra, rb = by.get((n, a)), by.get((n, b))
        if not ra or not rb or "wall" not in ra or "wall" not in rb:
            return "-"
        return f"{ra['wall'] / rb['wall']:.2f}"

    for n in sizes:
        dofs = next(r["dofs"] for r in results if r["n"] == n and "dofs" in r)
        rows.append(
            [
                n,
                f"{dofs:,}",
                g(n, "default", "wall"),
                g(n, "pardiso", "wall"),
                g(n, "floor_pardiso", "wall"),
                g(n, "floor_superlu", "wall"),
                ratio(n, "default", "floor_pardiso"),
                ratio(n, "pardiso", "floor_pardiso"),
                ratio(n, "default", "floor_superlu"),
                f"{g(n, 'default', 'cpu', '{:.1f}')} / "
                f"{g(n, 'pardiso', 'cpu', '{:.1f}')} / "
                f"{g(n, 'floor_pardiso', 'cpu', '{:.1f}')}",
                f"{g(n, 'default', 'maxrss_mib', '{:.0f}')} / "
                f"{g(n, 'pardiso', 'maxrss_mib', '{:.0f}')} / "
                f"{g(n, 'floor_pardiso', 'maxrss_mib', '{:.0f}')}",
            ]
        )
    runs = sorted({r["runs"] for r in results if "runs" in r})
    threads = sorted({r["threads"] for r in results if "threads" in r})
    loads = [x for r in results for x in r.get("loads", [])]
    how = (
        f"Medians of {'/'.join(map(str, runs))} whole processes per configuration, "
        f"alternated; peak RSS the largest of the runs; {'; '.join(threads)}"
    )
    return mdtable.table(HEADER, rows) + mdtable.note(how, loads)


def plot(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    labels = {
        "default": "xfemslip run, default install",
        "pardiso": "xfemslip run, mkl extra (PARDISO)",
        "floor_pardiso": "floor: PARDISO SPD factor + solve, uncracked",
        "floor_superlu": "floor: SuperLU factor + solve, uncracked",
    }
    for c in CONFIGS:
        rows = sorted(
            (r for r in results if r["config"] == c and "wall" in r),
            key=lambda r: r["dofs"],
        )
        if rows:
            ax.loglog(
                [r["dofs"] for r in rows],
                [r["wall"] for r in rows],
                "o-" if c in ("default", "pardiso") else "s--",
                label=labels[c],
            )
    ax.set_xlabel("dofs")
    ax.set_ylabel("whole process wall time [s]")
    ax.set_title("Reservoir case, 50 x 50 to 1000 x 1000")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 200, 400])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--superlu-max", type=int, default=700)
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--merge", nargs="+", help="JSON files to merge (no runs)")
    ap.add_argument("--plot", help="write a log-log plot here")
    mdtable.add_option(ap, "docs/performance/scaling.md")
    a = ap.parse_args()
    if a.merge:
        results = [r for f in a.merge for r in json.loads(Path(f).read_text())]
    else:
        threads = {
            k: os.environ.get(k, "unset")
            for k in ("MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")
        }
        print(f"threads: {threads}; load: {os.getloadavg()}", flush=True)
        results = measure(
            a.sizes,
            a.runs,
            a.superlu_max,
            a.timeout,
            lambda s: print(s, file=sys.stderr, flush=True),
        )
        print(f"load after: {os.getloadavg()}", flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(results, indent=1))
    mdtable.write(a.markdown, table(results))
    if a.plot:
        plot(results, a.plot)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
