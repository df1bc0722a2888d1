#!/usr/bin/env python3
"""Cost of the critical-depletion search: `xfemslip deplete` against `xfemslip
run` on the same case (whole-process wall and CPU time, warm Numba cache),
alternating the two, median of several runs; the ratio is taken from the same
run so that machine load cancels as far as it can.

    python benchmarks/depletion.py [--case cases/depleting_reservoir.toml] [--runs 5]
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


def timed(args: list[str]) -> tuple[float, float]:
    """(wall, CPU) seconds of one xfemslip process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "xfemslip", *args],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=dict(os.environ),
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="cases/depleting_reservoir.toml")
    parser.add_argument("--runs", type=int, default=5)
    opt = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        timed(["run", opt.case, "-o", str(out / "warm"), "-q"])  # fill the cache
        rows = {"run": [], "deplete": []}
        for i in range(opt.runs):
            rows["run"].append(timed(["run", opt.case, "-o", str(out / f"r{i}"), "-q"]))
            rows["deplete"].append(
                timed(["deplete", opt.case, "-o", str(out / f"d{i}"), "-q"])
            )
    for name, values in rows.items():
        wall = statistics.median(v[0] for v in values)
        cpu = statistics.median(v[1] for v in values)
        print(f"{name:8s} wall {wall:6.2f} s  CPU {cpu:6.2f} s  (median of {opt.runs})")
    ratios = [d[1] / r[1] for r, d in zip(rows["run"], rows["deplete"], strict=True)]
    print(
        f"deplete / run CPU ratio: median {statistics.median(ratios):.2f} "
        f"(min {min(ratios):.2f}, max {max(ratios):.2f})"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
