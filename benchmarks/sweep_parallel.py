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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--step", type=float, default=None, help="angle step [deg]")
    opts = ap.parse_args()
    from distributed import LocalCluster

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sweep = _sweep_file(tmp, opts.step)
        _time([str(sweep), "-j", "1"], tmp / "warm")  # numba cache, page cache
        os.environ["PYTHONPATH"] = str(ROOT)  # for the cluster's workers
        with LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster:
            modes = {
                "--jobs 1": ["-j", "1"],
                "--jobs 2": ["-j", "2"],
                "Dask, 2 workers": ["--scheduler", cluster.scheduler_address],
            }
            times: dict[str, list[float]] = {name: [] for name in modes}
            for _ in range(opts.runs):  # interleaved: load changes hit all modes
                for name, extra in modes.items():
                    times[name].append(_time([str(sweep), *extra], tmp / "out"))
        from xfemslip.studies.sweep import load_sweep

        n_cases = len(load_sweep(sweep).cases)
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    print(
        f"sweep: {sweep.name} ({n_cases} cases); runs: {opts.runs}; "
        f"load average after: {load}"
    )
    base = statistics.median(times["--jobs 1"])
    print("| mode | median [s] | min [s] | max [s] | speed-up vs --jobs 1 |")
    print("| --- | --- | --- | --- | --- |")
    for name, values in times.items():
        med = statistics.median(values)
        print(
            f"| {name} | {med:.2f} | {min(values):.2f} | {max(values):.2f} "
            f"| {base / med:.2f} |"
        )
    print(
        f"first Dask run (workers import xfemslip): {times['Dask, 2 workers'][0]:.2f} s"
    )


if __name__ == "__main__":
    main()
