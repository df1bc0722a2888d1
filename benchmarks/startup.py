#!/usr/bin/env python3
"""Whole-process wall time of `xfemslip run` on a shipped case: first run after
install (Numba compiles every kernel) and warm runs (kernels loaded from the
on-disk cache).  Medians of several runs; results go to benchmarks/RESULTS.md
by hand together with the machine they were measured on.

    python benchmarks/startup.py [--case cases/reservoir_depletion.toml] [--runs 5]

A cold run gets a fresh, empty NUMBA_CACHE_DIR; warm runs share one that a
first run has filled.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CPU: list[float] = []  # CPU time (user + system) of every timed run, in order


def timed_run(case: str, cache_dir: str, out: Path) -> float:
    """Wall time of one `xfemslip run`; its CPU time is appended to CPU."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(
        ["xfemslip", "run", "-q", "--overwrite", case, "-o", str(out)],
        env=env,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    CPU.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    if proc.returncode != 0:
        sys.exit(
            f"xfemslip run failed ({proc.returncode}): {proc.stderr.strip()[-500:]}"
        )
    return wall


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="cases/reservoir_depletion.toml")
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        cold = []
        for i in range(args.runs):
            cold.append(timed_run(args.case, str(Path(tmp) / f"cold{i}"), out))
        cold_cpu = CPU[:]
        warm_cache = str(Path(tmp) / "warm")
        timed_run(args.case, warm_cache, out)  # fill the cache
        del CPU[:]
        warm = [timed_run(args.case, warm_cache, out) for _ in range(args.runs)]
        warm_cpu = CPU[:]
    print(f"case {args.case}, {args.runs} runs each")
    print(
        f"first run (JIT compile): median {statistics.median(cold):.2f} s "
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


if __name__ == "__main__":
    sys.exit(main())
