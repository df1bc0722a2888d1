#!/usr/bin/env python3
"""The field section (cases/field_section.toml) against the floor of its own
mesh, whole processes, alternated, medians of --runs.

    MKL_NUM_THREADS=2 OPENBLAS_NUM_THREADS=1 NUMBA_NUM_THREADS=2 \\
    python benchmarks/field_section.py --sizes 10 5 --runs 3 \\
        --markdown docs/performance/field_section.md

Per mesh size (``[mesh] size``), each configuration in its own process, wall
time from start to exit as the parent sees it:

- run (mkl): ``xfemslip run -q`` of the case, result.h5 only (the floor
  writes nothing), pypardiso installed ("auto" takes PARDISO);
- run (default): the same with pypardiso hidden (AMG);
- floor: the same graded mesh (its node coordinates from the case), the
  plane-strain stiffness of uniform rock assembled here with NumPy (COO,
  2 x 2 Gauss, nothing of xfemslip's assembly), the sides and the bottom on
  rollers, a unit load on the top, and ONE symmetric positive-definite
  factorize-and-solve by MKL PARDISO (pypardiso, mtype 2), imports included.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "cases" / "field_section.toml"

RUN = """
import sys
{hide}
from xfemslip.cli import main
sys.argv = ["xfemslip", "run", "-q", "--overwrite", {case!r}]
main()
"""

FLOOR = """
import json, sys, time
import numpy as np, scipy.sparse as sp
import pypardiso
x = np.load({nodes!r}); y = np.load({nodes!r}.replace("x.npy", "y.npy"))
nx, ny = x.size - 1, y.size - 1
E, nu = 20e9, 0.25
lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
D = np.array([[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]])
I, J = np.meshgrid(np.arange(nx), np.arange(ny))
I, J = I.ravel(), J.ravel()
n0 = J * (nx + 1) + I
nodes = np.stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1], axis=1)
hx, hy = np.diff(x)[I], np.diff(y)[J]
xa, ya = np.array([-1., 1., 1., -1.]), np.array([-1., -1., 1., 1.])
Ke = np.zeros((I.size, 8, 8))
g = 1 / np.sqrt(3)
for xi in (-g, g):
    for eta in (-g, g):
        dx = xa * (1 + ya * eta) / 2 / hx[:, None]
        dy = ya * (1 + xa * xi) / 2 / hy[:, None]
        B = np.zeros((I.size, 3, 8))
        B[:, 0, 0::2] = dx; B[:, 1, 1::2] = dy
        B[:, 2, 0::2] = dy; B[:, 2, 1::2] = dx
        Ke += np.einsum("eik,ij,ejl->ekl", B, D, B) * (hx * hy / 4)[:, None, None]
dofs = np.empty((I.size, 8), np.int64)
dofs[:, 0::2], dofs[:, 1::2] = 2 * nodes, 2 * nodes + 1
rows = np.repeat(dofs, 8, axis=1).ravel(); cols = np.tile(dofs, 8).ravel()
n = 2 * (nx + 1) * (ny + 1)
K = sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(n, n)).tocsr()
node = np.arange((nx + 1) * (ny + 1)); ix, iy = node % (nx + 1), node // (nx + 1)
fixed = np.concatenate([2 * node[(ix == 0) | (ix == nx)], 2 * node[iy == 0] + 1])
free = np.setdiff1d(np.arange(n), fixed)
F = np.zeros(n); F[2 * node[iy == ny] + 1] = -1.0
A = sp.triu(K[free][:, free], format="csr"); A.sort_indices()
u = pypardiso.PyPardisoSolver(mtype=2).solve(A, F[free])
print(json.dumps(dict(dofs=int(free.size))))
"""


def child(code: str, cwd: Path) -> float:
    """Wall time [s] of ``python -c code``, start to exit."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(done.stderr.strip().splitlines()[-1])
    return wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[10.0, 5.0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument(
        "--markdown", type=Path, help="also write the table to this file"
    )
    args = parser.parse_args()
    import numpy as np

    from xfemslip.case import build, load_case

    lines = [
        "| size [m] | cells | run mkl [s] | run default [s] | floor [s] "
        "| mkl / floor | default / floor |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    loads = [os.getloadavg()[0]]
    print("\n".join(lines), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for size in args.sizes:
            keys = {
                "mesh.size": size,
                "output.formats": ["h5"],
                "output.directory": str(work / "out"),
            }
            case = work / f"case_{size:g}.toml"
            case.write_text(build.case_text(build.file_case(CASE, **keys)))
            mesh = load_case(case).mesh
            np.save(work / "x.npy", mesh.x)
            np.save(work / "y.npy", mesh.y)
            codes = {
                "mkl": RUN.format(hide="", case=str(case)),
                "default": RUN.format(
                    hide='sys.modules["pypardiso"] = None', case=str(case)
                ),
                "floor": FLOOR.format(nodes=str(work / "x.npy")),
            }
            for code in codes.values():  # warm-up: Numba's cache, file cache
                child(code, work)
            times = {k: [] for k in codes}
            for _ in range(args.runs):
                for k, code in codes.items():
                    times[k].append(child(code, work))
            med = {k: statistics.median(v) for k, v in times.items()}
            cells = f"{mesh.x.size - 1} x {mesh.y.size - 1}"
            lines.append(
                f"| {size:g} | {cells} | {med['mkl']:.2f} | {med['default']:.2f} | "
                f"{med['floor']:.2f} | {med['mkl'] / med['floor']:.2f} | "
                f"{med['default'] / med['floor']:.2f} |"
            )
            loads.append(os.getloadavg()[0])
            print(lines[-1], flush=True)
    note = (
        f"\nMedians of {args.runs} whole processes per configuration, "
        f"alternated; {platform.machine()}, {os.cpu_count()} cores, "
        f"{time.strftime('%Y-%m-%d')}, load average "
        f"{min(loads):.1f}-{max(loads):.1f}.\n"
    )
    mdtable.write(args.markdown, "\n".join(lines) + "\n" + note)


if __name__ == "__main__":
    main()
