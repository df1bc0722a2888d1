"""Wall time of one ``xfemslip sweep`` with 1 and 2 local processes and through
a Dask LocalCluster of 2 worker processes.

Each measurement is the whole ``python -m xfemslip sweep ... --force`` process
(start-up, validation, the runs, the summary), median of ``--runs`` repeats.
The Numba cache is warmed first.  The Dask cluster is started once, before
timing (a cluster is long-lived); its workers import xfemslip on their first
task, so the first Dask run carries that cost (also reported).

Usage, from the project root::

    python benchmarks/sweep_parallel.py --runs 3
    python benchmarks/sweep_parallel.py --runs 3 --step 3   # 31 angles, 0..90
    python benchmarks/sweep_parallel.py --runs 3 --sweeps paper 3 \
        --markdown docs/performance/sweep_parallel.md      # both, one table
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]


def _sweep_file(folder: Path, step: float | None) -> Path:
    """The paper's angle sweep, or the same base with angles 0..90 by step."""
    if step is None:
        return ROOT / "cases" / "sweeps" / "fracture_angle.toml"
    path = folder / "angles.toml"
    base = (ROOT / "cases" / "reservoir_depletion.toml").as_posix()
    path.write_text(
        f'base = "{base}"\n[vary]\n'
        f'"fractures[0].angle" = {{ start = 0.0, stop = 90.0, step = {step} }}\n'
    )
    return path


def _time(args: list[str], out: Path) -> float:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "xfemslip", "sweep", *args, "-o", str(out)]
    start = time.perf_counter()
    done = subprocess.run([*cmd, "--force"], capture_output=True, text=True, env=env)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr}")
    return elapsed


MODES = ("--jobs 1", "--jobs 2", "Dask, 2 workers")


def markdown(rows: list[dict], runs: int, dask_version: str, loads) -> str:
    """The table of docs/performance/sweep_parallel.md: per sweep, the median
    time of each mode and (its speed-up against --jobs 1)."""
    cells = []
    for row in rows:
        base = statistics.median(row["times"]["--jobs 1"])
        cells.append(
            [f"{row['label']}, {row['cases']} cases"]
            + [
                f"{statistics.median(row['times'][m]):.2f} s "
                f"({base / statistics.median(row['times'][m]):.2f})"
                for m in MODES
            ]
        )
    first = ", ".join(f"{row['times']['Dask, 2 workers'][0]:.2f} s" for row in rows)
    return mdtable.table(["sweep", *MODES], cells) + mdtable.note(
        f"Medians of {runs} whole `xfemslip sweep` processes, the modes "
        f"interleaved; a Dask LocalCluster of 2 worker processes, "
        f"dask/distributed {dask_version}; the workers' first run, importing "
        f"xfemslip: {first}",
        loads,
    )


def measure(sweep: Path, runs: int, tmp: Path, cluster) -> dict[str, list[float]]:
    _time([str(sweep), "-j", "1"], tmp / "warm")  # numba cache, page cache
    modes = {
        "--jobs 1": ["-j", "1"],
        "--jobs 2": ["-j", "2"],
        "Dask, 2 workers": ["--scheduler", cluster.scheduler_address],
    }
    times: dict[str, list[float]] = {name: [] for name in modes}
    for _ in range(runs):  # interleaved: load changes hit all modes
        for name, extra in modes.items():
            times[name].append(_time([str(sweep), *extra], tmp / "out"))
    return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--step", type=float, default=None, help="angle step [deg]")
    ap.add_argument(
        "--sweeps",
        nargs="+",
        help='several sweeps in one table: "paper" (the paper\'s angle study) or '
        "an angle step [deg]",
    )
    mdtable.add_option(ap, "docs/performance/sweep_parallel.md")
    opts = ap.parse_args()
    import distributed
    from distributed import LocalCluster

    from xfemslip.studies.sweep import load_sweep

    steps = (
        [None if s == "paper" else float(s) for s in opts.sweeps]
        if opts.sweeps
        else [opts.step]
    )
    rows, loads = [], [mdtable.load()]
    os.environ["PYTHONPATH"] = str(ROOT)  # for the cluster's workers
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for step in steps:
            # a cluster of its own per sweep: its first run is the workers' first
            with LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True,
                dashboard_address=None,
            ) as cluster:  # fmt: skip
                sweep = _sweep_file(tmp, step)
                times = measure(sweep, opts.runs, tmp, cluster)
            label = (
                "paper's angle study" if step is None else f"angles every {step:g} deg"
            )
            rows.append(
                {"label": label, "cases": len(load_sweep(sweep).cases), "times": times}
            )
            loads.append(mdtable.load())
    mdtable.write(
        opts.markdown, markdown(rows, opts.runs, distributed.__version__, loads)
    )


if __name__ == "__main__":
    main()
