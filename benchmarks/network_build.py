#!/usr/bin/env python3
"""Model-build time of fracture networks: 10, 30 and 100 fractures on a
200 x 200 mesh (simulation.build_model: geometry with the junction search,
enrichment, sub-cell quadrature, bulk stiffness, contact operators).

    PYTHONPATH=$PWD python benchmarks/network_build.py [--runs 3] [--tip ramp]

The networks are random but reproducible (seed 6): straight fractures of
0.08-0.25 m in the unit square, uniform orientations, so they cross and end
near one another; ends within half a cell of another fracture are snapped (T).
Each size is built once to compile the kernels, then timed --runs times; the
median goes to docs/performance.md with the machine and its load.
"""

from __future__ import annotations

import argparse
import logging
import statistics
import sys
import time
from collections import Counter

import numpy as np

from xfemslip.case import build, loads_case
from xfemslip.errors import GeometryError
from xfemslip.simulation import build_model


def network(count: int, seed: int = 6) -> list[np.ndarray]:
    """count straight fractures, re-drawing any that would overlap another."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        c = rng.uniform(0.1, 0.9, 2)
        a = rng.uniform(0.0, np.pi)
        half = 0.5 * rng.uniform(0.08, 0.25)
        d = half * np.array([np.cos(a), np.sin(a)])
        out.append(np.array([c - d, c + d]))
    return out


def case_text(fracs, n: int, tip: str) -> str:
    """n x n cells, the fractures ``fracs`` (end points rounded to 1e-6 m)."""
    fracture = {"friction": 0.6, "kn": 5.0e12, "kt": 5.0e12, "tip": tip}
    return build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [n, n]},
            "material": {"E": 5.0e9, "nu": 0.25},
            "fractures": [dict(fracture, points=p.round(6)) for p in fracs] or None,
            "loading": {
                "initial_stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0},
                "stress": {"xx": -12.0e6, "yy": -40.0e6, "xy": 0.0},
            },
            "boundary": {
                "bottom": {"uy": 0.0},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
        }
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--tip", default="branch", choices=("branch", "ramp"))
    ap.add_argument("--sizes", default="10,30,100")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    print("| fractures | junctions (X, T, V) | dofs | build median [s] | runs [s] |")
    print("|---|---|---|---|---|")
    for count in map(int, args.sizes.split(",")):
        spec = loads_case(case_text(network(count), args.n, args.tip), "net.toml")
        try:
            model = build_model(spec)  # compile / warm up
        except GeometryError as err:
            print(f"{count}: {err}", file=sys.stderr)
            return 1
        kinds = Counter()
        for f in model.fractures:
            kinds["arms"] += len(f.arms) - 1
            kinds["ends"] += len(f.junction_ends)
        times = []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            model = build_model(spec)
            times.append(time.perf_counter() - t0)
        runs = ", ".join(f"{t:.2f}" for t in times)
        print(
            f"| {count} | {kinds['arms']} X, {kinds['ends']} T/V | "
            f"{model.problem.n_dofs} | {statistics.median(times):.2f} | {runs} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
