#!/usr/bin/env python3
"""A generated network of 100 fractures with branch tips against the
PARDISO floor, whole processes, alternated in the same run.

    python benchmarks/network_floor.py [--runs 3] [--configs floor,pardiso,default]
        [--count 100] [--n 200] [--seed 1] [--trees DIR ...] [--json FILE]
        [--markdown docs/performance/network_floor.md]

``--trees`` compares versions: each run and configuration other than the
floor is run once per source tree (a git worktree of another commit, say,
or ``.``), that tree put first on PYTHONPATH, alternated with the others.
The children start in a temporary directory and report the package they
imported: a ``python -c`` child started in the project root would import
the root's ``xfemslip`` whatever PYTHONPATH says.

The runs get the caller's thread variables (MKL_NUM_THREADS,
OPENBLAS_NUM_THREADS, NUMBA_NUM_THREADS), written under the table; the
table in docs/performance is measured with none set, as a user runs it.

The network: ``[network.generate]`` with ``count`` fractures, uniform
orientations, power-law lengths (exponent 2.5) on [0.06, 0.25] m, friction
0.4, the default (branch) tips, on n x n cells of a 1 m block; in-situ
stress (-20, -40) MPa, sigma_xx relaxed to -12 MPa in 2 load steps; the
result written as h5 (``[output] formats = ["h5"]``).

Configurations, each a process of its own (wall time from start to exit in
the parent, CPU time and peak memory (ru_maxrss) of that child alone, wait4):

- floor: the same mesh without fractures built by xfemslip (mesh, assembly),
  then ONE factorize-and-solve of K_ff u = F by pypardiso in SPD mode
  (mtype 2, upper triangle), imports included, nothing written (the floor of
  benchmarks/scaling.py);
- pardiso: ``xfemslip run`` with the mkl extra installed ("auto" takes
  PARDISO);
- default: the same run without the extra (pypardiso hidden from the child).

Each run takes every configuration once, in the order given; times are
medians over --runs runs (min and max printed too), the load average
(os.getloadavg) is recorded before every child.  A warm-up of each
configuration first compiles and caches the Numba kernels and byte-compiles
the sources (as an installed package has them).
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
import threading
import time
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]


def case_text(count: int, n: int, seed: int, cracked: bool) -> str:
    from xfemslip.case import build

    doc = {
        "name": f"network-{count}",
        "domain": {"size": [1.0, 1.0]},
        "mesh": {"elements": [n, n]},
        "material": {"E": 5.0e9, "nu": 0.25},
        "loading": {
            "initial_stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0},
            "stress": {"xx": -12.0e6, "yy": -40.0e6, "xy": 0.0},
            "steps": 2,
        },
        "boundary": {
            "bottom": {"uy": 0.0},
            "top": "traction",
            "left": "traction",
            "right": "traction",
        },
        "output": {"formats": ["h5"]},
    }
    if cracked:
        doc["network"] = {
            "friction": 0.4,
            "generate": {
                "seed": seed,
                "count": count,
                "orientation": {"distribution": "uniform"},
                "length": {
                    "distribution": "power_law",
                    "exponent": 2.5,
                    "min": 0.06,
                    "max": 0.25,
                },
            },
        }
    return build.case_text(doc)


RUN = """
import sys
{hide}
import xfemslip
print("xfemslip imported from", xfemslip.__file__, flush=True)
from xfemslip.cli import main
sys.argv = ["xfemslip", "run", "-q", "--overwrite", {case!r}, "-o", {out!r}]
main()
"""

FLOOR = """
import json, time
t0 = time.perf_counter()
import numpy as np, scipy.sparse as sp
from xfemslip.case import load_case
from xfemslip.simulation import build_model
model = build_model(load_case({case!r}))
p = model.problem
free = np.ones(p.n_dofs, bool); free[p.fixed] = False
K = p.K[free][:, free].tocsr()
F = np.asarray(p.F_unit)[free]
t1 = time.perf_counter()
import pypardiso
A = sp.triu(K, format="csr"); A.sort_indices()
x = pypardiso.PyPardisoSolver(mtype=2).solve(A, F)
t2 = time.perf_counter()
print(json.dumps(dict(dofs=int(K.shape[0]), build=t1 - t0, solve=t2 - t1)))
"""


def split(config: str) -> tuple[str, str | None]:
    """("pardiso", tree) of a configuration "pardiso@tree" (None: no tree)."""
    name, _, tree = config.partition("@")
    return name, tree or None


def expanded(configs: list[str], trees: list[str] | None) -> list[str]:
    """The configurations of a run: with trees, each one but the floor once
    per tree ("pardiso@tree"), in the order given."""
    if not trees:
        return list(configs)
    return [
        c if c == "floor" else f"{c}@{t}"
        for c in configs
        for t in (trees if c != "floor" else [None])
    ]


def child(config: str, work: Path, args) -> dict:
    name, tree = split(config)
    tag = "".join(ch if ch.isalnum() else "_" for ch in config)
    case = work / f"{tag}.toml"
    case.write_text(case_text(args.count, args.n, args.seed, name != "floor"))
    out = work / f"out_{tag}"
    if name == "floor":
        code = FLOOR.format(case=str(case))
    else:
        hide = 'sys.modules["pypardiso"] = None' if name == "default" else ""
        code = RUN.format(hide=hide, case=str(case), out=str(out))
    env = dict(os.environ)
    if tree:
        env["PYTHONPATH"] = str(Path(tree).resolve())
    log = work / "child.log"
    load = os.getloadavg()[0]
    start = time.perf_counter()
    with open(log, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-c", code],
            stdout=fh,
            stderr=subprocess.STDOUT,
            cwd=work,
            env=env,
        )
        timer = threading.Timer(args.timeout, proc.kill)
        timer.start()
        _, status, usage = os.wait4(proc.pid, 0)  # this child alone
        timer.cancel()
    wall = time.perf_counter() - start
    code = os.waitstatus_to_exitcode(status)
    text = log.read_text()
    if code != 0:
        sys.exit(f"{config} failed ({code}): {text.strip()[-800:]}")
    if tree:
        imported = next(
            (
                ln.split(" from ", 1)[1]
                for ln in text.splitlines()
                if ln.startswith("xfemslip imported")
            ),
            "",
        )
        if not Path(imported).resolve().is_relative_to(Path(tree).resolve()):
            sys.exit(
                f"{config}: the child imported {imported or 'nothing'}, not {tree}"
            )
    row = dict(
        config=config,
        wall=wall,
        cpu=usage.ru_utime + usage.ru_stime,
        rss_mib=usage.ru_maxrss / 1024,
        load=load,
    )
    if config == "floor":
        row.update(json.loads(text.strip().splitlines()[-1]))
    else:
        import h5py

        with h5py.File(out / "result.h5") as f:
            row.update(
                run_wall=float(f.attrs["wall_time_s"]),
                newton=[int(i) for i in f.attrs["newton_iterations_per_step"]],
                dofs=int(f.attrs["n_dofs"]),
            )
    return row


HEADER = [
    "configuration",
    "wall, median (min, max) [s]",
    "/ floor",
    "CPU [s]",
    "peak RSS [MiB]",
    "Newton iterations",
]
THREADS = ("MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")
LABELS = {
    "floor": "floor: one PARDISO SPD solve, no fractures",
    "pardiso": "`xfemslip run`, mkl extra",
    "default": "`xfemslip run`, default install",
}


def label(config: str) -> str:
    """The table's name of a configuration (with its tree, if any)."""
    name, tree = split(config)
    text = LABELS.get(name, name)
    return f"{text}, tree `{tree}`" if tree else text


def markdown(rows, configs, args) -> str:
    """The table of the measured rows (each a child's dict): per
    configuration the median wall time, its ratio to the floor's median, the
    median CPU time, the largest peak RSS and the Newton iterations per
    load step."""
    floor = statistics.median(r["wall"] for r in rows if r["config"] == "floor")
    out = []
    for config in configs:
        mine = [r for r in rows if r["config"] == config]
        walls = [r["wall"] for r in mine]
        med = statistics.median(walls)
        newton = mine[0].get("newton")
        out.append(
            [
                label(config),
                f"{med:.2f} ({min(walls):.2f}, {max(walls):.2f})",
                f"{med / floor:.1f}",
                f"{statistics.median(r['cpu'] for r in mine):.1f}",
                f"{max(r['rss_mib'] for r in mine):,.0f}",
                "-" if not newton else " + ".join(str(k) for k in newton),
            ]
        )
    dofs = {split(r["config"])[0]: r.get("dofs") for r in rows}
    env = rows[0].get("env") or {k: os.environ.get(k, "-") for k in THREADS}
    how = (
        f"{args.count} generated fractures (seed {args.seed}, branch tips) on "
        f"{args.n} x {args.n} cells, {dofs.get('pardiso') or dofs.get('default')} "
        f"dofs (the floor's mesh {dofs.get('floor')}); medians of {args.runs} "
        "whole processes per configuration, alternated; "
        + ", ".join(f"{k}={env.get(k, '-')}" for k in THREADS)
    )
    loads = [r["load"] for r in rows]
    return mdtable.table(HEADER, out) + mdtable.note(how, loads)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--configs", default="floor,pardiso,default")
    ap.add_argument("--count", type=int, default=100)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=3600.0)
    ap.add_argument("--no-warmup", action="store_true")
    ap.add_argument(
        "--trees",
        nargs="+",
        metavar="DIR",
        help="source trees to compare (each put first on PYTHONPATH in turn)",
    )
    ap.add_argument("--json")
    ap.add_argument(
        "--from-json",
        metavar="FILE",
        help="write the table of a run saved with --json (nothing is measured)",
    )
    mdtable.add_option(ap, "docs/performance/network_floor.md")
    args = ap.parse_args()
    configs = expanded(args.configs.split(","), args.trees)
    if args.from_json:
        rows = json.loads(Path(args.from_json).read_text())
        args.runs = max(r["run"] for r in rows) + 1
        mdtable.write(args.markdown, markdown(rows, configs, args))
        return 0
    for tree in [ROOT, *(Path(t) for t in args.trees or [])]:
        compileall.compile_dir(str(tree / "xfemslip"), quiet=1)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if not args.no_warmup:
            for config in configs:
                if split(config)[0] != "default":  # compiles what the others load
                    child(config, work, args)
        for run in range(args.runs):
            for config in configs:
                row = child(config, work, args)
                row["run"] = run
                row["env"] = {k: os.environ.get(k, "-") for k in THREADS}
                rows.append(row)
                print(json.dumps(row), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    mdtable.write(args.markdown, markdown(rows, configs, args))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
