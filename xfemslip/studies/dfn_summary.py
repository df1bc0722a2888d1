"""Aggregate of a sweep over random-network realizations: ``dfn_summary.csv``.

A sweep whose ``[vary]`` holds a ``network.*`` key (typically
``network.generate.seed``) gets, besides ``summary.csv``, one row per metric
over the cases that have a result (status ok or skipped): the number of
realizations, mean, standard deviation (ddof = 1; 0 for one realization),
min, median and max.  Failed and refused cases are left out and counted.
"""

from __future__ import annotations

import numpy as np

from xfemslip import display
from xfemslip.io.csv import write_csv

DFN_SUMMARY = "dfn_summary.csv"
AGGREGATED = (
    "fractures",
    "slipping_fractures",
    "slipping_fraction",
    "max_abs_slip_m",
    "mean_slip_m",
    "slip_length_m",
    "slip_share",
)
COLUMNS = ("metric", "realizations", "mean", "std", "min", "median", "max", "failed")


def is_dfn_sweep(keys) -> bool:
    """Whether a sweep varies the fracture network (a ``network.*`` key)."""
    return any(k == "network" or k.startswith("network.") for k in keys)


def aggregate(rows) -> list[dict]:
    """One dict per metric of AGGREGATED over the rows with a result."""
    done = [r for r in rows if r.status in ("ok", "skipped") and r.metrics]
    failed = len(rows) - len(done)
    out = []
    for metric in AGGREGATED:
        values = np.array([float(r.metrics[metric]) for r in done], dtype=float)
        n = values.size
        out.append(
            {
                "metric": metric,
                "realizations": n,
                "mean": float(values.mean()) if n else float("nan"),
                "std": float(values.std(ddof=1)) if n > 1 else 0.0,
                "min": float(values.min()) if n else float("nan"),
                "median": float(np.median(values)) if n else float("nan"),
                "max": float(values.max()) if n else float("nan"),
                "failed": failed,
            }
        )
    return out


def _text(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def write_dfn_summary(path, rows) -> list[dict]:
    """Write ``dfn_summary.csv`` atomically; return the aggregate."""
    table = aggregate(rows)
    write_csv(path, COLUMNS, ([_text(row[c]) for c in COLUMNS] for row in table))
    return table


def format_aggregate(table: list[dict]) -> str:
    """The aggregate as an aligned text table."""
    rows = [[_text(row[c]) for c in COLUMNS] for row in table]
    return display.table(COLUMNS, rows, left=range(len(COLUMNS)))
