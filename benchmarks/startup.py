#!/usr/bin/env python3
"""Whole-process wall time of `xfemslip run` on a shipped case: first run after
install (empty Numba and bytecode caches: a case on the Numba kernels compiles
them) and warm runs (caches filled).  Medians of several runs, one
row per kernel backend (``--kernels auto numba``: "numba" forces the Numba
kernels through XFEMSLIP_KERNELS; a small case gets the NumPy ones under
"auto", xfemslip.kernels.choose).

    python benchmarks/startup.py [--case cases/reservoir_depletion.toml] [--runs 5]
        [--kernels auto numba] [--markdown docs/performance/startup.md]

A cold run gets a fresh, empty NUMBA_CACHE_DIR; warm runs share one that a
first run has filled.  The same holds for Python's bytecode cache
(PYTHONPYCACHEPREFIX, one per cold run, one shared by the warm runs):
without it, an environment with PYTHONDONTWRITEBYTECODE=1 (as on the machine
of docs/performance.md) compiles every xfemslip module from source in
every run, 0.05-0.07 s that an installed package does not pay.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from pathlib import Path

import mdtable
from xfem_process import timed_run as run_process

CPU: list[float] = []  # CPU time (user + system) of every timed run, in order


def timed_run(
    case: str,
    cache_dir: str,
    out: Path,
    tree: str | None = None,
    kernels: str = "auto",
) -> float:
    """Wall time of one `xfemslip run`; its CPU time is appended to CPU.
    ``tree``: a source tree put first on PYTHONPATH (None: the environment's);
    ``kernels``: XFEMSLIP_KERNELS ("auto": the case's own choice)."""
    env = dict(
        os.environ,
        **({"PYTHONPATH": tree} if tree else {}),
        **({"XFEMSLIP_KERNELS": kernels} if kernels != "auto" else {}),
        NUMBA_CACHE_DIR=cache_dir,
        PYTHONPYCACHEPREFIX=str(Path(cache_dir) / "pycache"),
    )
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    wall, cpu = run_process(case, out, env, command=("xfemslip",))
    CPU.append(cpu)
    return wall


def markdown(case: str, runs: int, rows: dict[str, dict], loads) -> str:
    """The table of docs/performance/startup.md: per backend, the first run
    after install and warm runs, medians with (min, max), and warm CPU."""

    def cell(v: list[float]) -> str:
        return f"{statistics.median(v):.2f} s ({min(v):.2f}, {max(v):.2f})"

    names = {"auto": "auto (the default)", "numba": "numba (forced)"}
    text = mdtable.table(
        [
            "kernels",
            "first run (empty Numba and bytecode caches)",
            "warm run",
            "warm CPU",
        ],
        [
            [
                names.get(k, k),
                cell(r["cold"]),
                cell(r["warm"]),
                f"{statistics.median(r['warm_cpu']):.2f} s",
            ]
            for k, r in rows.items()
        ],
    )
    return text + mdtable.note(
        f"Whole-process time of `xfemslip run {case}`, medians of {runs} runs "
        "(min, max)",
        loads,
    )


def measure(case: str, runs: int, kernels: str, tmp: str) -> dict:
    out = Path(tmp) / "out"
    del CPU[:]
    cold = [
        timed_run(case, str(Path(tmp) / f"cold{kernels}{i}"), out, kernels=kernels)
        for i in range(runs)
    ]
    warm_cache = str(Path(tmp) / f"warm{kernels}")
    timed_run(case, warm_cache, out, kernels=kernels)  # fill the cache
    del CPU[:]
    warm = [timed_run(case, warm_cache, out, kernels=kernels) for _ in range(runs)]
    return {"cold": cold, "warm": warm, "warm_cpu": CPU[:]}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="cases/reservoir_depletion.toml")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument(
        "--kernels", nargs="+", default=["auto"], choices=("auto", "numpy", "numba")
    )
    ap.add_argument(
        "--trees",
        nargs="+",
        help="only warm runs, of each of these source trees (PYTHONPATH) in turn, "
        "interleaved run by run",
    )
    mdtable.add_option(ap, "docs/performance/startup.md")
    args = ap.parse_args()
    if args.trees:
        return compare(args)
    rows, loads = {}, [mdtable.load()]
    with tempfile.TemporaryDirectory() as tmp:
        for kernels in args.kernels:
            rows[kernels] = measure(args.case, args.runs, kernels, tmp)
            loads.append(mdtable.load())
    mdtable.write(args.markdown, markdown(args.case, args.runs, rows, loads))
    return 0


def compare(args) -> int:
    """Warm runs of several source trees, interleaved (each its own caches)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        caches = {t: str(Path(tmp) / f"warm{i}") for i, t in enumerate(args.trees)}
        for t in args.trees:
            timed_run(args.case, caches[t], out, t)  # fill the caches
        wall = {t: [] for t in args.trees}
        cpu = {t: [] for t in args.trees}
        for _ in range(args.runs):
            for t in args.trees:
                del CPU[:]
                wall[t].append(timed_run(args.case, caches[t], out, t))
                cpu[t].append(CPU[0])
    print(f"case {args.case}, warm runs, {args.runs} each, interleaved")
    for t in args.trees:
        print(
            f"{t}: wall median {statistics.median(wall[t]):.2f} s "
            f"(min {min(wall[t]):.2f}, max {max(wall[t]):.2f}); CPU median "
            f"{statistics.median(cpu[t]):.2f} s (min {min(cpu[t]):.2f})"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
