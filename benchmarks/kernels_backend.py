#!/usr/bin/env python3
"""Whole-process time of `xfemslip run` with the NumPy and the Numba kernel
backends (`[solver] kernels`), interleaved, on cases of growing enriched-cell
work: the measurement behind `kernels.AUTO_NUMPY_MAX_WORK` (the "auto" rule).

    python benchmarks/kernels_backend.py [--runs 3] [--only NAME ...] [--json out.json]
        [--markdown docs/performance/kernels_backend.md]

Each configuration runs in a fresh process with a warm Numba cache and cached
bytecode (as an installed package has), h5 output only.  Reported: the
enriched-cell work of the model (`simulation.kernel_work`), median wall and
CPU (user + system) per backend, and numpy / numba.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import sys
import tempfile
from pathlib import Path

import mdtable
from xfem_process import timed_run

from xfemslip.case import build

ROOT = Path(__file__).resolve().parents[1]
NETWORK = ROOT / "cases/fracture_network.toml"


def reservoir(n: int) -> dict:
    path = ROOT / "cases/reservoir_depletion.toml"
    return build.file_case(path, **{"mesh.elements": [n, n]})


def network(n: int, count: int, tip: str) -> dict:
    """The shipped DFN sweep's base case on n x n cells, count fractures."""
    sweep = build.file_case(ROOT / "cases/sweeps/dfn_realizations.toml")
    keys = {
        "mesh.elements": [n, n],
        "network.generate.count": count,
        "network.tip": tip,
    }
    return build.with_keys(sweep["base"], **keys)


CONFIGS = {
    "reservoir 50": lambda: reservoir(50),
    "reservoir 100": lambda: reservoir(100),
    "reservoir 200": lambda: reservoir(200),
    "reservoir 400": lambda: reservoir(400),
    "network 80 (shipped)": lambda: build.file_case(NETWORK),
    "dfn 30 ramp, 50": lambda: network(50, 30, "ramp"),
    "dfn 30 ramp, 100": lambda: network(100, 30, "ramp"),
    "network 100 branch, 200": lambda: network_floor_case(),
}


def network_floor_case() -> dict:
    """The 100 branch-tipped fractures of network_floor.py (a relaxation in
    two steps, which Newton converges; the DFN base scaled to 100 fractures
    on 200 x 200 cells, loaded from zero in one step, converges only by the
    normal-traction fixed point after a failed Newton solve, 87 s, a
    measure of that remedy more than of the kernels)."""
    import tomllib

    from network_floor import case_text

    return tomllib.loads(case_text(100, 200, 1, True))


LABELS = {
    "reservoir 50": "reservoir 50 x 50",
    "reservoir 100": "reservoir 100 x 100",
    "reservoir 200": "reservoir 200 x 200",
    "reservoir 400": "reservoir 400 x 400",
    "network 80 (shipped)": "shipped 15-fracture network, 80 x 80",
    "dfn 30 ramp, 50": "30 generated fractures, 50 x 50",
    "dfn 30 ramp, 100": "30 generated fractures, 100 x 100",
    "network 100 branch, 200": "100 generated fractures, branch tips, 200 x 200",
}


def markdown(rows: list[dict], runs: int, loads) -> str:
    """The table of docs/performance/kernels_backend.md: per case, its
    enriched-cell work, median wall (CPU) per backend, numpy / numba CPU."""
    cells = [
        [
            LABELS[r["case"]],
            f"{r['work']:.1e}",
            f"{r['numpy_wall']:.2f} ({r['numpy_cpu']:.2f})",
            f"{r['numba_wall']:.2f} ({r['numba_cpu']:.2f})",
            f"{r['numpy_cpu'] / r['numba_cpu']:.2f}",
        ]
        for r in rows
    ]
    header = [
        "case",
        "enriched-cell work",
        "numpy: wall (CPU) [s]",
        "numba: wall (CPU) [s]",
        "numpy / numba, CPU",
    ]
    return mdtable.table(header, cells) + mdtable.note(
        f"Whole-process `xfemslip run`, h5 output, warm caches, medians of {runs} "
        "runs, the backends interleaved",
        loads,
    )


def with_backend(case: dict, backend: str) -> str:
    """Case text with ``[solver] kernels = backend`` and, where the case
    names output formats, result.h5 only."""
    keys = {"solver.kernels": backend}
    if "formats" in case.get("output", {}):
        keys["output.formats"] = ["h5"]
    return build.case_text(build.with_keys(case, **keys))


def work_of(case: Path) -> float:
    from xfemslip.case import load_case
    from xfemslip.fem.enrichment import build_enriched_cells, find_candidates
    from xfemslip.simulation import _geometry, kernel_work

    spec = load_case(case)
    mesh, fractures = _geometry(spec)
    cand = find_candidates(mesh, fractures)
    return kernel_work(build_enriched_cells(mesh, fractures, cand))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--only", nargs="*", help="configuration names (default: all)")
    ap.add_argument("--json", type=Path)
    mdtable.add_option(ap, "docs/performance/kernels_backend.md")
    args = ap.parse_args()
    loads = [mdtable.load()]
    folder = Path(tempfile.mkdtemp(prefix="xfemslip-kernels-"))
    env = dict(
        os.environ,
        NUMBA_CACHE_DIR=str(folder / "numba"),
        PYTHONPYCACHEPREFIX=str(folder / "pycache"),
    )
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    rows = []
    for name, make in CONFIGS.items():
        if args.only and name not in args.only:
            continue
        cases = {}
        for backend in ("numpy", "numba"):
            case = folder / f"{re.sub(r'[^a-z0-9]+', '_', name)}_{backend}.toml"
            case.write_text(with_backend(make(), backend))
            cases[backend] = case
            timed_run(case, folder / "out", env)  # warm the caches
        times = {b: [] for b in cases}
        for _ in range(args.runs):
            for backend, case in cases.items():
                times[backend].append(timed_run(case, folder / "out", env))
        row = {"case": name, "work": work_of(cases["numpy"])}
        for backend in cases:
            row[f"{backend}_wall"] = statistics.median(t[0] for t in times[backend])
            row[f"{backend}_cpu"] = statistics.median(t[1] for t in times[backend])
        rows.append(row)
        loads.append(mdtable.load())
        print(
            f"| {name} | {row['work']:.3g} | "
            f"{row['numpy_wall']:.2f} ({row['numpy_cpu']:.2f})"
            f" | {row['numba_wall']:.2f} ({row['numba_cpu']:.2f})"
            f" | {row['numpy_cpu'] / row['numba_cpu']:.2f} |",
            flush=True,
        )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    mdtable.write(args.markdown, markdown(rows, args.runs, loads))
    return 0


if __name__ == "__main__":
    sys.exit(main())
