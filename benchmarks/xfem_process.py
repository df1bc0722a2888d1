"""One timed `xfemslip run` process, shared by the benchmark scripts that
measure whole-process time (startup, kernels_backend, ogs_compare,
accuracy_vs_time).  Imported by basename: the scripts run as
`python benchmarks/NAME.py`, which puts this folder first on sys.path."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path

# `python -m xfemslip` (the scripts' own interpreter); startup.py times the
# console script a user types instead.
PYTHON_M = (sys.executable, "-m", "xfemslip")


def timed_run(case, out, env=None, command=PYTHON_M) -> tuple[float, float]:
    """(wall, CPU) seconds of `<command> run -q --overwrite CASE -o OUT`; CPU
    is the user + system time of the child.  Exits with the child's stderr
    if it fails."""
    argv = [*command, "run", "-q", "--overwrite", str(case), "-o", str(out)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(
        argv, env=dict(os.environ) if env is None else env, capture_output=True,
        text=True,
    )  # fmt: skip
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        sys.exit(
            f"xfemslip run {Path(case).name} failed ({proc.returncode}): "
            f"{proc.stderr.strip()[-500:]}"
        )
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
