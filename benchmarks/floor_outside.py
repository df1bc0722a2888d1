#!/usr/bin/env python3
"""The single-fracture reservoir case against a floor measured from outside:
fresh installs, a floor that does not share the project's code, whole
processes alternated.

    python benchmarks/floor_outside.py [--sizes 200 400] [--runs 3]
        [--venvs DIR] [--markdown docs/performance/floor_outside.md]

- Two virtual environments made by the README's commands in ``--venvs``
  (kept there for the next run): ``default`` (``pip install -e .``) and
  ``mkl`` (``pip install -e '.[mkl]'``).
- floor: a script of its own (below, FLOOR; it imports numpy, scipy and
  pypardiso, not xfemslip), run by the mkl environment: the Q4 plane-strain
  stiffness of the same n x n mesh of the 1 m block (E = 5 GPa, nu = 0.3,
  2 x 2 Gauss points) assembled as COO triplets by NumPy, u_y = 0 on the
  bottom and u_x = 0 at one corner, the edge tractions of the case, and one
  SPD factorize-and-solve by pypardiso (mtype 2, upper triangle).
- default / mkl: ``xfemslip run`` of cases/reservoir_depletion.toml at
  n x n cells (h5 only) from each environment, as a user runs it: no thread
  variable set (OPENBLAS_NUM_THREADS, MKL_NUM_THREADS, OMP_NUM_THREADS,
  NUMBA_NUM_THREADS removed from the environment).
- default, 1 BLAS thread: the default run with OPENBLAS_NUM_THREADS=1 (what
  the project's own benchmarks set).

The sources are byte-compiled first, as an installed package has them (the
editable installs read xfemslip from this tree; under
PYTHONDONTWRITEBYTECODE=1 every process would compile its modules again,
0.25-0.3 s).  Every run takes each configuration once, in that order; wall
times from start to exit in the parent, medians over --runs, and each
configuration's peak resident memory (the kernel's ru_maxrss of the
process, the largest over the runs); the load average is read before every
process.  The table goes to --markdown (and is printed).
"""

from __future__ import annotations

import argparse
import compileall
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
THREAD_VARS = (
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "OMP_NUM_THREADS",
    "NUMBA_NUM_THREADS",
)

FLOOR = r"""
import sys
import numpy as np
import scipy.sparse as sp
import pypardiso

n = int(sys.argv[1])
E, nu, L = 5.0e9, 0.3, 1.0
h = L / n
c = E / ((1 + nu) * (1 - 2 * nu))
D = c * np.array([[1 - nu, nu, 0], [nu, 1 - nu, 0], [0, 0, (1 - 2 * nu) / 2]])
g = 1 / np.sqrt(3)
xi = np.array([-1, 1, 1, -1.0])
eta = np.array([-1, -1, 1, 1.0])
Ke = np.zeros((8, 8))
for a in (-g, g):
    for b in (-g, g):
        dN = np.array([xi * (1 + eta * b), eta * (1 + xi * a)]) / 4 * (2 / h)
        B = np.zeros((3, 8))
        B[0, 0::2] = dN[0]
        B[1, 1::2] = dN[1]
        B[2, 0::2] = dN[1]
        B[2, 1::2] = dN[0]
        Ke += B.T @ D @ B * (h * h / 4)
i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
n0 = (j * (n + 1) + i).ravel()
nodes = np.stack([n0, n0 + 1, n0 + n + 2, n0 + n + 1], axis=1)
dofs = np.empty((n * n, 8), np.int64)
dofs[:, 0::2] = 2 * nodes
dofs[:, 1::2] = 2 * nodes + 1
rows = np.repeat(dofs, 8, axis=1).ravel()
cols = np.tile(dofs, (1, 8)).ravel()
vals = np.tile(Ke.ravel(), n * n)
N = 2 * (n + 1) ** 2
K = sp.coo_matrix((vals, (rows, cols)), shape=(N, N)).tocsr()
F = np.zeros(N)
sxx, syy = -20e6, -40e6
y = np.arange(n + 1)
w = np.full(n + 1, h)
w[[0, -1]] = h / 2
F[2 * (y * (n + 1) + n)] += sxx * w       # right edge, normal +x
F[2 * (y * (n + 1))] -= sxx * w           # left edge, normal -x
F[2 * (n * (n + 1) + y) + 1] += syy * w   # top edge, normal +y
fixed = np.concatenate([2 * np.arange(n + 1) + 1, [0]])
free = np.setdiff1d(np.arange(N), fixed)
Kff = K[free][:, free]
solver = pypardiso.PyPardisoSolver(mtype=2)
u = solver.solve(sp.triu(Kff, format="csr"), F[free])
print(len(free), float(np.abs(u).max()))
"""

CASE_EDIT = ("elements = [50, 50]", 'formats = ["h5", "vtu"]')


def _environment(venvs: Path, name: str) -> Path:
    """The virtual environment ``name`` in ``venvs``, made by the README's
    command when missing (and the command run again in a kept one, so it has
    what the project requires now); its python."""
    python = venvs / name / "bin" / "python"
    if not python.exists():
        venvs.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "venv", str(venvs / name)], check=True)
    target = str(ROOT) if name == "default" else f"{ROOT}[mkl]"
    subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "-e", target], check=True
    )
    return python


def _versions(python: Path) -> str:
    code = (
        "import importlib.metadata as m\n"
        "out=[]\n"
        "for p in ('numpy','scipy','pyamg','numba','pypardiso','mkl'):\n"
        "    try: out.append(p+' '+m.version(p))\n"
        "    except m.PackageNotFoundError: pass\n"
        "print(', '.join(out))"
    )
    return subprocess.run(
        [str(python), "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()


def _failed(cmd: list[str], code: int, stderr: str) -> None:
    """Stop the benchmark with the command, its exit code and its last lines."""
    tail = "\n".join(stderr.strip().splitlines()[-10:])
    sys.exit(f"{' '.join(cmd)} failed ({code}):\n{tail}")


def _timed(cmd: list[str], env: dict) -> tuple[float, float]:
    """Wall time [s] and peak resident memory [MiB] of one whole process (its
    log goes to a file, read back only if it fails)."""
    with tempfile.TemporaryFile("w+") as log:
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=log)
        _, status, usage = os.wait4(proc.pid, 0)
        elapsed = time.perf_counter() - start
        code = os.waitstatus_to_exitcode(status)
        if code:
            log.seek(0)
            _failed(cmd, code, log.read())
    return elapsed, usage.ru_maxrss / 1024.0  # KiB on Linux


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[200, 400])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument(
        "--venvs",
        type=Path,
        default=Path(tempfile.gettempdir()) / "xfemslip-floor-venvs",
    )
    ap.add_argument("--markdown", type=Path, default=None)
    opts = ap.parse_args()
    pythons = {name: _environment(opts.venvs, name) for name in ("default", "mkl")}
    compileall.compile_dir(str(ROOT / "xfemslip"), quiet=1)
    user = {k: v for k, v in os.environ.items() if k not in THREAD_VARS}
    one = dict(user, OPENBLAS_NUM_THREADS="1")
    base = (ROOT / "cases" / "reservoir_depletion.toml").read_text()
    rows, loads = [], []
    with tempfile.TemporaryDirectory() as tmp:
        floor = Path(tmp) / "floor.py"
        floor.write_text(FLOOR)
        for n in opts.sizes:
            case = Path(tmp) / f"reservoir_{n}.toml"
            case.write_text(
                base.replace("elements = [50, 50]", f"elements = [{n}, {n}]").replace(
                    'formats = ["h5", "vtu"]', 'formats = ["h5"]'
                )
            )
            out = str(Path(tmp) / f"out{n}")

            def run(name, env, case=case, out=out):
                xfemslip = str(pythons[name].parent / "xfemslip")
                return [xfemslip, "run", str(case), "-o", out, "--overwrite"], env

            configs = {
                "floor": ([str(pythons["mkl"]), str(floor), str(n)], user),
                "default": run("default", user),
                "mkl": run("mkl", user),
                "default, OPENBLAS_NUM_THREADS=1": run("default", one),
            }
            for cmd, env in configs.values():  # warm-up: caches, bytecode
                warm = subprocess.run(cmd, env=env, capture_output=True, text=True)
                if warm.returncode:
                    _failed(cmd, warm.returncode, warm.stderr)
            times: dict[str, list[float]] = {k: [] for k in configs}
            peak: dict[str, float] = dict.fromkeys(configs, 0.0)
            for _ in range(opts.runs):
                for name, (cmd, env) in configs.items():
                    loads.append(os.getloadavg()[0])
                    seconds, mib = _timed(cmd, env)
                    times[name].append(seconds)
                    peak[name] = max(peak[name], mib)
            med = {k: statistics.median(v) for k, v in times.items()}
            dofs = 2 * (n + 1) ** 2
            rows.append(
                f"| {n} x {n} | {dofs:,} | {med['floor']:.2f} | "
                + " | ".join(
                    f"{med[k]:.2f} ({med[k] / med['floor']:.2f}x)"
                    for k in configs
                    if k != "floor"
                )
                + " | "
                + " / ".join(f"{peak[k]:,.0f}" for k in ("floor", "default", "mkl"))
                + " |"
            )
            print(rows[-1], flush=True)
    lines = [
        "| mesh | dofs | floor [s] | default [s] (/ floor) | mkl extra [s] (/ floor) "
        "| default, OPENBLAS_NUM_THREADS=1 [s] (/ floor) "
        "| peak RSS: floor / default / mkl [MiB] |",
        "| --- | --- | --- | --- | --- | --- | --- |",
        *rows,
        "",
        f"Medians of {opts.runs} whole processes per configuration, alternated "
        "(peak RSS: the largest of them); "
        f"{platform.machine()}, {os.cpu_count()} cores, load average "
        f"{min(loads):.1f}-{max(loads):.1f}. default: {_versions(pythons['default'])}; "
        f"mkl: {_versions(pythons['mkl'])}.",
    ]
    mdtable.write(opts.markdown, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
