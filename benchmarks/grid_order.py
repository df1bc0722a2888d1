#!/usr/bin/env python3
"""SuperLU in the grid's nested-dissection order against SuperLU in its
minimum-degree order and against AMG: whole `xfemslip run` processes of the
default install (no mkl extra), alternated in the same run.

    python benchmarks/grid_order.py [--runs 3] [--cases r200,r283,r400,n10,n20,n30]
        [--configs grid,mmd,amg] [--json FILE]
        [--markdown docs/performance/grid_order.md]

Cases: ``rN`` the shipped reservoir case (cases/reservoir_depletion.toml)
on N x N cells; ``nK`` a generated network of K fractures with branch tips
on 200 x 200 cells (benchmarks/network_floor.py's case, 2 load steps).
Configurations, each a process of its own with pypardiso hidden:

- grid: ``linear_solver = "superlu"``, as shipped (the grid's order where
  the enriched dofs are at most GRID_ORDER_MAX_ENRICHED of the free dofs,
  minimum degree otherwise);
- mmd: the same with the grid's order switched off (the limit set to -1);
- amg: ``linear_solver = "amg"``.

Wall time from start to exit in the parent, peak memory (ru_maxrss) of the
child alone (wait4), the load average before each child; medians over
--runs runs (min and max printed).  A warm-up run of each case first
byte-compiles the sources and caches the Numba kernels.  What it measures:
where the order applies (the rule of xfemslip/solve/linear.py) and where
"auto" should take SuperLU in it rather than AMG.
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
import time
from pathlib import Path

import mdtable
from network_floor import case_text as network_text

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "reservoir_depletion.toml"

RUN = """
import sys
sys.modules["pypardiso"] = None
from xfemslip.solve import linear
if {mmd!r}:
    linear.GRID_ORDER_MAX_ENRICHED = -1.0
from xfemslip.cli import main
sys.argv = ["xfemslip", "run", "-q", "--overwrite", {case!r}, "-o", {out!r}]
main()
"""


def case_text(case: str, method: str) -> str:
    from xfemslip.case import build

    if case.startswith("r"):
        n = int(case[1:])
        keys = {
            "mesh.elements": [n, n],
            "solver.linear_solver": method,
            "output.formats": ["h5"],
        }
        return build.case_text(build.file_case(CASE, **keys))
    # the generated network's case has no [solver] table
    text = network_text(int(case[1:]), 200, 1, True)
    return text + f'\n[solver]\nlinear_solver = "{method}"\n'


def child(case: str, config: str, work: Path) -> dict:
    method = "amg" if config == "amg" else "superlu"
    path = work / f"{case}_{config}.toml"
    path.write_text(case_text(case, method))
    out = work / f"out_{case}_{config}"
    code = RUN.format(mmd=config == "mmd", case=str(path), out=str(out))
    load = os.getloadavg()[0]
    start = time.perf_counter()
    with open(work / "child.log", "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-c", code], stdout=fh, stderr=subprocess.STDOUT, cwd=work
        )
        _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        text = (work / "child.log").read_text()
        sys.exit(f"{case} {config} failed: {text.strip()[-800:]}")
    import h5py

    with h5py.File(out / "result.h5") as f:
        dofs = int(f.attrs["n_dofs"])
        newton = [int(i) for i in f.attrs["newton_iterations_per_step"]]
    return dict(
        case=case,
        config=config,
        wall=wall,
        rss_mib=usage.ru_maxrss / 1024,
        load=load,
        dofs=dofs,
        newton=newton,
    )


HEADER = [
    "case",
    "dofs",
    "SuperLU, grid's order [s]",
    "SuperLU, minimum degree [s]",
    "AMG [s]",
    "peak RSS grid / mmd / AMG [MiB]",
    "Newton iterations",
]
NAMES = {"r": "reservoir case, {} x {} cells", "n": "{} fractures, 200 x 200 cells"}


def markdown(rows, cases, configs, runs) -> str:
    out = []
    for case in cases:
        mine = [r for r in rows if r["case"] == case]
        label = NAMES[case[0]].format(*(case[1:],) * 2)
        cells = [label, f"{mine[0]['dofs']:,}"]
        rss = []
        for config in ("grid", "mmd", "amg"):
            walls = [r["wall"] for r in mine if r["config"] == config]
            if not walls:
                cells.append("-")
                rss.append("-")
                continue
            med = statistics.median(walls)
            cells.append(f"{med:.2f} ({min(walls):.2f}, {max(walls):.2f})")
            peak = max(r["rss_mib"] for r in mine if r["config"] == config)
            rss.append(f"{peak:,.0f}")
        cells.append(" / ".join(rss))
        cells.append(" + ".join(str(k) for k in mine[0]["newton"]))
        out.append(cells)
    how = (
        f"whole `xfemslip run` processes without the mkl extra, medians of {runs} "
        f"(min, max), configurations alternated; OPENBLAS_NUM_THREADS="
        f"{os.environ.get('OPENBLAS_NUM_THREADS', '-')}"
    )
    return mdtable.table(HEADER, out) + mdtable.note(how, [r["load"] for r in rows])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--cases", default="r200,r283,r400,n10,n20,n30")
    ap.add_argument("--configs", default="grid,mmd,amg")
    ap.add_argument("--json")
    mdtable.add_option(ap, "docs/performance/grid_order.md")
    args = ap.parse_args()
    cases, configs = args.cases.split(","), args.configs.split(",")
    compileall.compile_dir(str(ROOT / "xfemslip"), quiet=1)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for case in cases:
            child(case, configs[0], work)  # warm-up
        for run in range(args.runs):
            for case in cases:
                for config in configs:
                    row = child(case, config, work)
                    row["run"] = run
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    mdtable.write(args.markdown, markdown(rows, cases, configs, args.runs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
