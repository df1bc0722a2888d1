#!/usr/bin/env python3
"""Whole-process wall time of `xfemslip run` on a shipped case: first run after
install (empty Numba and bytecode caches: a case on the Numba kernels compiles
them) and warm runs (caches filled).  Medians of several runs; results go to
docs/performance.md (*Start-up*) by hand, with the machine they were
measured on.
`XFEMSLIP_KERNELS=numba python benchmarks/startup.py` forces the Numba kernels
(a small case gets the NumPy ones: xfemslip.kernels.choose).

    python benchmarks/startup.py [--case cases/reservoir_depletion.toml] [--runs 5]

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

from xfem_process import timed_run as run_process

CPU: list[float] = []  # CPU time (user + system) of every timed run, in order


def timed_run(case: str, cache_dir: str, out: Path, tree: str | None = None) -> float:
    """Wall time of one `xfemslip run`; its CPU time is appended to CPU.
    ``tree``: a source tree put first on PYTHONPATH (None: the environment's)."""
    env = dict(
        os.environ,
        **({"PYTHONPATH": tree} if tree else {}),
        NUMBA_CACHE_DIR=cache_dir,
        PYTHONPYCACHEPREFIX=str(Path(cache_dir) / "pycache"),
    )
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    wall, cpu = run_process(case, out, env, command=("xfemslip",))
    CPU.append(cpu)
    return wall


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="cases/reservoir_depletion.toml")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument(
        "--trees",
        nargs="+",
        help="only warm runs, of each of these source trees (PYTHONPATH) in turn, "
        "interleaved run by run",
    )
    args = ap.parse_args()
    if args.trees:
        return compare(args)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        cold = [
            timed_run(args.case, str(Path(tmp) / f"cold{i}"), out)
            for i in range(args.runs)
        ]
        cold_cpu = CPU[:]
        warm_cache = str(Path(tmp) / "warm")
        timed_run(args.case, warm_cache, out)  # fill the cache
        del CPU[:]
        warm = [timed_run(args.case, warm_cache, out) for _ in range(args.runs)]
        warm_cpu = CPU[:]
    print(f"case {args.case}, {args.runs} runs each")
    print(
        f"first run (empty caches): median {statistics.median(cold):.2f} s "
        f"(min {min(cold):.2f}, max {max(cold):.2f})"
    )
    print(
        f"warm run (cached):       median {statistics.median(warm):.2f} s "
        f"(min {min(warm):.2f}, max {max(warm):.2f})"
    )
    print(
        f"CPU time (user + system): first run median "
        f"{statistics.median(cold_cpu):.2f} s, warm run median "
        f"{statistics.median(warm_cpu):.2f} s"
    )
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
