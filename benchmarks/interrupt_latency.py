"""How fast a signal stops a sweep and its workers.

Each trial starts one ``python -m xfemslip sweep`` process (8 members of the
reservoir case at 20 x 20 cells, 4 load steps, on 2 local workers; or an
uncertainty study of 8 XFEM samples; or a Dask-backed sweep on a
``LocalCluster`` of 2 workers with ``--dask``), waits until two members have
finished, sends the signal, and measures from the signal:

- ``end``: until the sweep process has ended;
- ``gone``: until every process it started (found in /proc below its pid;
  with Dask, the members' child processes below the cluster's workers) has
  ended;
- ``finished``: members that finished after the signal (at most the two that
  were running; before workers were stopped with the sweep, all of them).

Linux only (/proc).  Usage, from the project root::

    python benchmarks/interrupt_latency.py --trials 3
    python benchmarks/interrupt_latency.py --trials 3 --dask
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.faults import harness  # noqa: E402
from tests.faults.test_sweep_signals import (  # noqa: E402
    Sweep,
    alive,
    descendants,
    harness_cmdline,
    members,
    sweep_files,
)

SIGNALS = {
    "SIGINT": signal.SIGINT,
    "SIGTERM": signal.SIGTERM,
    "SIGKILL": signal.SIGKILL,
}


def trial(folder: Path, kind: str, sig: int, scheduler=None, tasks=None) -> dict:
    sweep_files(folder, uncertainty="xfem" if kind == "xfem" else None)
    args = ["-j", "2", "sweep.toml", "-o", "out"]
    if scheduler:
        args = ["sweep.toml", "-o", "out", "--scheduler", scheduler]
    sweep = Sweep(args, folder)
    try:
        sweep.wait_for(2)
        started: set[int] = set()
        while not started:
            started = descendants(sweep.proc.pid) | (tasks() if tasks else set())
        before = len(sweep.finished())
        start = time.perf_counter()
        sweep.signal(sig)
        sweep.proc.wait(timeout=harness.TIMEOUT)
        end = time.perf_counter() - start
        while alive(started) and time.perf_counter() - start < harness.TIMEOUT:
            time.sleep(0.005)
        gone = time.perf_counter() - start
    finally:
        sweep.kill()
    return {"end": end, "gone": gone, "finished": len(members(folder / "out")) - before}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=3)
    ap.add_argument("--dask", action="store_true", help="also a Dask-backed sweep")
    opts = ap.parse_args()
    os.environ["PYTHONPATH"] = str(ROOT)
    cases = [("sweep -j 2", "sweep", None), ("xfem study -j 2", "xfem", None)]
    cluster = None
    if opts.dask:
        from distributed import Client, LocalCluster

        cluster = LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        )
        workers = list(Client(cluster).run(os.getpid).values())

        def tasks() -> set[int]:
            return {
                pid
                for w in workers
                for pid in descendants(w)
                if "xfemslip.studies.workers" in harness_cmdline(pid)
            }

        cases.append(("dask sweep", "sweep", (cluster.scheduler_address, tasks)))
    print(
        f"{'sweep':<16} {'signal':<8} {'end [s]':>12} {'gone [s]':>12} {'finished':>9}"
    )
    for label, kind, dask in cases:
        for name, sig in SIGNALS.items():
            rows = []
            for _ in range(opts.trials):
                with tempfile.TemporaryDirectory() as tmp:
                    scheduler, tasks = dask or (None, None)
                    rows.append(trial(Path(tmp), kind, sig, scheduler, tasks))
            end = statistics.median(r["end"] for r in rows)
            gone = max(r["gone"] for r in rows)
            finished = max(r["finished"] for r in rows)
            print(f"{label:<16} {name:<8} {end:>12.2f} {gone:>12.2f} {finished:>9d}")
    if cluster is not None:
        cluster.close()


if __name__ == "__main__":
    main()
