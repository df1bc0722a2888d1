#!/usr/bin/env python3
"""XFEM samples of a probability study: each solved on its own against the
study's shared path, whole processes alternated in the same run.

    python benchmarks/study_reuse.py [--samples 100] [--runs 3]
        [--markdown docs/performance/study_reuse.md]

The study: the seed paper's 50 x 50 reservoir case with a pore pressure
(benchmarks/uncertainty.py, RESERVOIR: a 0.6 m fracture at 45 degrees,
depleted by 30 MPa in 5 steps) with friction, sigma_xx and the initial pore
pressure uncertain (RESERVOIR_STUDY), ``evaluate = "xfem"``.

Configurations, each a process of its own, one after the other in every run:

- plain: every sample as a process of ``xfemslip sweep`` solved it when each
  sample was a case of its own: ``loads_case`` and ``deplete`` of its case
  with the default outputs (h5 and VTU), outside ``shared.sharing``: its
  own mesh, enrichment, assembly and SuperLU factorizations;
- shared: ``evaluate_xfem`` (what ``xfemslip sweep`` runs), one process
  (``jobs = 1``): the samples share the geometry, the bulk stiffness and
  its Schur factors (xfemslip.solve.shared), and write result.h5 and the
  tables only.

Both are timed inside their process after a warm-up sample (Numba kernels
compiled and cached), so the ratio is that of the samples themselves; both
processes write each sample's dp_critical, and the run checks that they are
equal (the same bisection brackets) and that the probabilities are.  The
load average (os.getloadavg) is taken before every child.
"""

from __future__ import annotations

import argparse
import json
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
sys.path.insert(0, str(ROOT / "benchmarks"))


def _spec(folder: Path, samples: int):
    import uncertainty as bench  # benchmarks/uncertainty.py

    from xfemslip.studies.uncertainty import load_uncertainty

    return load_uncertainty(bench._study(folder, bench.RESERVOIR, samples, "xfem"))


def _plain(spec, folder: Path):
    """Each sample solved as a case of its own (default outputs)."""
    import tomllib

    import numpy as np
    import tomli_w

    from xfemslip.case import loads_case
    from xfemslip.studies.depletion import deplete
    from xfemslip.studies.reactivation import read_sample, sample_cases

    dp = np.full((spec.samples, len(spec.base_spec.fractures)), np.nan)
    for i, (cid, text, _case, _reason) in enumerate(sample_cases(spec)):
        document = tomllib.loads(text)
        document["output"].pop("formats", None)  # the case's own: h5 and VTU
        case = loads_case(tomli_w.dumps(document), spec.case_path)
        deplete(case, folder / cid, overwrite=True)
        dp[i] = read_sample(folder / cid)["dp_critical"]
    return dp


def child(config: str, samples: int, out: Path) -> None:
    import numpy as np

    from xfemslip.solve import shared
    from xfemslip.studies.reactivation import (
        UncertaintyResult,
        aggregate,
        evaluate_xfem,
    )

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "warm").mkdir()
        warm = _spec(folder / "warm", 1)
        evaluate_xfem(warm, folder / "warm" / "out", jobs=1, force=True)
        shared.forget()  # the study below builds and factors its own
        (folder / "study").mkdir()
        spec = _spec(folder / "study", samples)
        start = time.perf_counter()
        if config == "plain":
            dp = _plain(spec, folder / "plain")
            probability = aggregate(
                UncertaintyResult(
                    spec,
                    "",
                    [str(i) for i in range(spec.samples)],
                    np.full(spec.samples, "ok"),
                    [""] * spec.samples,
                    dp,
                )
            ).probability
        else:
            result = evaluate_xfem(spec, folder / "shared", jobs=1, force=True)
            dp, probability = result.dp_critical, result.probability
        wall = time.perf_counter() - start
    out.write_text(
        json.dumps(
            {
                "wall": wall,
                "dp": np.where(np.isnan(dp), None, dp).tolist(),
                "probability": probability.tolist(),
            }
        )
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--samples", type=int, default=100)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--markdown", type=Path, default=None)
    ap.add_argument("--child", choices=("plain", "shared"), help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    opts = ap.parse_args()
    if opts.child:
        child(opts.child, opts.samples, opts.out)
        return
    walls: dict[str, list[float]] = {"plain": [], "shared": []}
    loads, answers = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for run in range(opts.runs):
            for config in ("plain", "shared"):
                out = Path(tmp) / f"{config}{run}.json"
                loads.append(os.getloadavg()[0])
                subprocess.run(
                    [
                        sys.executable,
                        __file__,
                        "--child",
                        config,
                        "--samples",
                        str(opts.samples),
                        "--out",
                        str(out),
                    ],
                    check=True,
                )
                got = json.loads(out.read_text())
                walls[config].append(got["wall"])
                answers.setdefault(config, got)
                print(f"run {run + 1}: {config} {got['wall']:.1f} s", flush=True)
    same_dp = answers["plain"]["dp"] == answers["shared"]["dp"]
    same_p = answers["plain"]["probability"] == answers["shared"]["probability"]
    med = {k: statistics.median(v) for k, v in walls.items()}
    ratios = [p / s for p, s in zip(walls["plain"], walls["shared"], strict=True)]
    n = opts.samples
    lines = [
        f"| {n} XFEM samples, 50 x 50 reservoir case, one process | wall time "
        "(median) | per sample | range |",
        "|---|---|---|---|",
    ]
    for k, label in (
        ("plain", "each sample on its own (own build, factorizations, VTU)"),
        ("shared", "the study's shared path (`xfemslip sweep`)"),
    ):
        lines.append(
            f"| {label} | {med[k]:.1f} s | {1e3 * med[k] / n:.0f} ms | "
            f"{min(walls[k]):.1f}-{max(walls[k]):.1f} s |"
        )
    lines += [
        "",
        f"Speed-up {med['plain'] / med['shared']:.1f}x (median of the per-run "
        f"ratios {statistics.median(ratios):.1f}x, {opts.runs} runs alternated); "
        f"same critical changes of every sample: {'yes' if same_dp else 'NO'}, "
        f"same probabilities: {'yes' if same_p else 'NO'}.  "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"load average {min(loads):.1f}-{max(loads):.1f} during the runs.",
    ]
    mdtable.write(opts.markdown, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
