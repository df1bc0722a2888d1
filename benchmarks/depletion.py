#!/usr/bin/env python3
"""Cost of the critical-depletion search: `xfemslip deplete` against `xfemslip
run` on the same case (whole-process wall and CPU time, warm Numba cache),
alternating the two, median of several runs; the ratio is taken from the same
run so that machine load cancels as far as it can.

    python benchmarks/depletion.py [--case cases/depleting_reservoir.toml] [--runs 5]
        [--markdown docs/performance/depletion.md]
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

import mdtable


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


def markdown(case: str, rows: dict[str, list[tuple[float, float]]], loads) -> str:
    """The table of docs/performance/depletion.md: median wall and CPU time
    of each command, then the deplete / run CPU ratio of the pairs."""
    runs = len(rows["run"])
    ratios = [d[1] / r[1] for r, d in zip(rows["run"], rows["deplete"], strict=True)]
    text = mdtable.table(
        ["command", "wall [s]", "CPU [s]"],
        [
            [
                f"`xfemslip {name}`",
                f"{statistics.median(v[0] for v in values):.2f}",
                f"{statistics.median(v[1] for v in values):.2f}",
            ]
            for name, values in rows.items()
        ],
    )
    return text + mdtable.note(
        f"`{case}`, whole processes alternated, warm caches, medians of {runs}; "
        f"deplete / run CPU ratio {statistics.median(ratios):.2f} "
        f"({min(ratios):.2f} to {max(ratios):.2f} over the {runs} pairs)",
        loads,
    )


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="cases/depleting_reservoir.toml")
    parser.add_argument("--runs", type=int, default=5)
    mdtable.add_option(parser, "docs/performance/depletion.md")
    opt = parser.parse_args()
    loads = [mdtable.load()]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        timed(["run", opt.case, "-o", str(out / "warm"), "-q"])  # fill the cache
        rows = {"run": [], "deplete": []}
        for i in range(opt.runs):
            rows["run"].append(timed(["run", opt.case, "-o", str(out / f"r{i}"), "-q"]))
            rows["deplete"].append(
                timed(["deplete", opt.case, "-o", str(out / f"d{i}"), "-q"])
            )
            loads.append(mdtable.load())
    mdtable.write(opt.markdown, markdown(opt.case, rows, loads))
    return 0


if __name__ == "__main__":
    sys.exit(main())
