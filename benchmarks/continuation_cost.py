#!/usr/bin/env python3
"""What following the path to the loss of equilibrium costs: ``xfemslip
deplete`` of the weakening displaced fault (cases/displaced_fault_weakening.toml)
against one ``xfemslip run`` of the same mesh, whole processes, alternated,
medians of --runs.

    OPENBLAS_NUM_THREADS=1 python benchmarks/continuation_cost.py \\
        --sizes 12.5 3.125 --runs 3 \\
        --markdown docs/performance/continuation_cost.md

Per mesh size (``[mesh] size`` near the fault), each in its own process, the
wall time from start to exit as the parent sees it, result.h5 only:

- deplete: the load steps up to the first slip of the weakening fault, then
  the bordered Newton steps of the slip-controlled path to the limit point
  and its bisection (xfemslip.solve.continuation), the first slip and the
  patch length read off the path;
- run: the case's load steps (12 of 2.5 MPa), nothing more.

The table gives both, their ratio (the target: at most 10) and the number of
states of the path (steps written by deplete) against the run's 12.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "displaced_fault_weakening.toml"
TABLE = "docs/performance/continuation_cost.md"


def child(args: list[str]) -> float:
    """Wall time [s] of ``xfemslip ARGS``, start to exit."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "xfemslip", *args], capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(done.stderr.strip().splitlines()[-1])
    return wall


def case_at(size: float, folder: Path) -> Path:
    """The shipped case with ``[mesh] size`` = size, h5 output only."""
    from xfemslip.case import build

    text = build.case_text(
        build.file_case(CASE, **{"mesh.size": size, "output.formats": ["h5"]})
    )
    path = folder / f"case_{size:g}.toml"
    path.write_text(text, encoding="utf-8")
    return path


def path_states(out: Path) -> int:
    """Steps written by deplete (the path's states after the start)."""
    lines = (out / "slip_vs_depletion.csv").read_text().splitlines()
    return len(lines) - 2  # the header and step 0


def markdown(rows: list[dict], loads: list[float], runs: int) -> str:
    """The table of the measurements: one row per mesh size."""
    body = [
        [
            f"{r['size']:g}",
            r["states"],
            f"{r['deplete']:.1f}",
            f"{r['run']:.1f}",
            f"{r['deplete'] / r['run']:.1f}",
        ]
        for r in rows
    ]
    header = ["cells [m]", "path states", "deplete [s]", "run [s]", "deplete / run"]
    how = f"Medians of {runs} whole processes per command, alternated"
    return mdtable.table(header, body) + mdtable.note(how, loads)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[12.5, 3.125])
    parser.add_argument("--runs", type=int, default=3)
    mdtable.add_option(parser, TABLE)
    args = parser.parse_args()
    rows, loads = [], []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for size in args.sizes:
            case = case_at(size, folder)
            times: dict[str, list[float]] = {"deplete": [], "run": []}
            for _ in range(args.runs):
                loads.append(mdtable.load())
                times["deplete"].append(
                    child(["deplete", "-q", "--overwrite", str(case), "-o", f"{tmp}/d"])
                )
                times["run"].append(
                    child(["run", "-q", "--overwrite", str(case), "-o", f"{tmp}/r"])
                )
            row = {k: statistics.median(v) for k, v in times.items()}
            row.update(size=size, states=path_states(folder / "d"))
            print(
                f"{size:g} m: deplete {row['deplete']:.1f} s, run {row['run']:.1f} s,"
                f" {row['states']} states",
                flush=True,
            )
            rows.append(row)
    mdtable.write(args.markdown, markdown(rows, loads, args.runs))


if __name__ == "__main__":
    main()
