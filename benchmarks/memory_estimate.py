#!/usr/bin/env python3
"""Predicted against measured peak memory of whole runs (xfemslip.memory).

For each case: the three estimates (from the case alone, after the node
enrichments, from the built model) and the peak resident memory of
`xfemslip run` in its own process (ru_maxrss of that process alone), with
the ratios estimate / measured.  Cases: the shipped ones, many load steps,
large meshes and crowded generated networks (60 fractures on 30 x 30 cells:
seed 1 fails after 186 Newton iterations over 6 load-step cuts, seed 14
converges in 10 load steps after 59; 200 fractures, the shipped DFN
realizations' table).  All sizes in MB (1e6 B).

    python benchmarks/memory_estimate.py [--only NAME,...] [--timeout 900]
        [--markdown docs/performance/memory_estimate.md]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.support
from tests.support.casegen import sweep_member  # noqa: E402
from tests.support.hardcases import estimates, measure  # noqa: E402
from xfemslip import memory  # noqa: E402
from xfemslip.case import build  # noqa: E402

CASES = ROOT / "cases"


def _shipped(name, **keys):
    return build.case_text(build.file_case(CASES / f"{name}.toml", **keys))


def _network(count, n, seed=1, steps=1):
    keys = {
        "network.generate.count": count,
        "mesh.elements": [n, n],
        "loading.steps": steps,
    }
    return sweep_member(index=seed - 1, **keys)


INPUTS = {
    "reservoir": lambda: _shipped("reservoir_depletion"),
    "liu-borja": lambda: _shipped("liu_borja_plate"),
    "network": lambda: _shipped("fracture_network"),
    "depleting": lambda: _shipped("depleting_reservoir"),
    "reservoir-400-steps": lambda: _shipped(
        "reservoir_depletion", **{"loading.steps": 400}
    ),
    "network-100-steps": lambda: _shipped("fracture_network", **{"loading.steps": 100}),
    "reservoir-200x200": lambda: _shipped(
        "reservoir_depletion", **{"mesh.elements": [200, 200]}
    ),
    "reservoir-300x300": lambda: _shipped(
        "reservoir_depletion", **{"mesh.elements": [300, 300]}
    ),
    "dfn-60-30x30": lambda: _network(60, 30),
    "dfn-60-30x30-s14-10": lambda: _network(60, 30, seed=14, steps=10),
    "dfn-200-50x50": lambda: _network(200, 50),
    "dfn-200-100x100": lambda: _network(200, 100),
}


LABELS = {
    "reservoir": "`reservoir_depletion`",
    "liu-borja": "`liu_borja_plate`",
    "network": "`fracture_network`",
    "depleting": "`depleting_reservoir`",
    "reservoir-400-steps": "reservoir, 400 load steps",
    "network-100-steps": "network, 100 load steps",
    "reservoir-200x200": "reservoir, 200 x 200",
    "reservoir-300x300": "reservoir, 300 x 300",
    "dfn-60-30x30": "60 fractures, 30 x 30",
    "dfn-60-30x30-s14-10": "60 fractures, 30 x 30, seed 14, 10 steps",
    "dfn-200-50x50": "200 fractures, 50 x 50",
    "dfn-200-100x100": "200 fractures, 100 x 100",
}


def markdown(rows: list[tuple[str, object, list[float], float]], loads) -> str:
    """The table of docs/performance/memory_estimate.md: the three estimates
    and the measured peak of each case, in MB; a run that failed (exit code
    not 0) is marked, its peak is that of the failed run."""
    cells = [
        [LABELS[name] + ("" if code == 0 else f" (exit {code})")]
        + [f"{e:.0f}" for e in est]
        + [f"{peak:.0f}"]
        for name, code, est, peak in rows
    ]
    text = mdtable.table(
        [
            "case",
            "from the case",
            "before the enriched cells",
            "from the model",
            "measured peak",
        ],
        cells,
    )
    return text + mdtable.note(
        "MB (1e6 B); each case one `xfemslip run` process, its peak resident "
        "memory (ru_maxrss of that process alone)",
        loads,
    )


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--only", default=",".join(INPUTS))
    parser.add_argument("--timeout", type=float, default=900.0)
    mdtable.add_option(parser, "docs/performance/memory_estimate.md")
    opt = parser.parse_args()
    rows, loads = [], [mdtable.load()]
    os.environ.pop(memory.ENV_LIMIT, None)
    print(
        f"{'case':20s} {'exit':>5s} {'wall':>6s} {'case':>7s} {'enrich':>7s} "
        f"{'model':>7s} {'peak':>7s} {'ratios':>11s}   [s, MB; estimate / peak]"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for name in opt.only.split(","):
            path = Path(tmp) / f"{name}.toml"
            path.write_text(INPUTS[name]())
            est = [e / 1e6 for e in estimates(path)]
            argv = [sys.executable, "-m", "xfemslip", "run", "-q", str(path)]
            argv += ["-o", str(Path(tmp) / f"out-{name}")]
            code, wall, peak, _ = measure(argv, opt.timeout, Path(tmp) / f"{name}.log")
            peak *= 2**20 / 1e6  # MiB -> MB
            cols = " ".join(f"{e:7.0f}" for e in est)
            print(
                f"{name:20s} {code!s:>5s} {wall:6.1f} {cols} {peak:7.0f} "
                f"{est[1] / peak:5.2f} {est[2] / peak:5.2f}",
                flush=True,
            )
            rows.append((name, code, est, peak))
            loads.append(mdtable.load())
    mdtable.write(opt.markdown, markdown(rows, loads))
    return 0


if __name__ == "__main__":
    sys.exit(main())
