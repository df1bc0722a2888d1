#!/usr/bin/env python3
"""Nucleation length of the Uenishi & Rice fault (tests.support.nucleation)
under mesh refinement, for the two load shapes and the two controls of
xfemslip.solve.continuation: 2a against 2 a_c = 2 x 0.579 mu* / W, the
onset load factor, the largest slip over D_c, the path's steps, the
bisection solves, the linear solves and the wall time of the path following
(model build apart).

    python benchmarks/nucleation.py [--h 2 1 0.5 0.25] [--shapes gaussian parabola]
                                    [--controls potency max_slip]

Prints a markdown table; the results are in docs/method.md, "Nucleation".
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.support
from tests.support import nucleation as ur  # noqa: E402
from xfemslip.solve.continuation import (  # noqa: E402
    ContinuationOptions,
    follow_to_nucleation,
)


def one(h: float, shape: str, control: str) -> str:
    model, solver, geometry = ur.model_and_solver(h, shape)
    start = time.perf_counter()
    result = follow_to_nucleation(
        solver, geometry, ContinuationOptions(control=control)
    )
    wall = time.perf_counter() - start
    n = result.nucleation
    two_ac = 2.0 * ur.critical_half_length()
    return (
        f"| {h:g} | {two_ac / h:.1f} | {shape} | {control} | "
        f"{model.problem.n_dofs} | {n.load_factor:.6f} | {n.length:.3f} | "
        f"{100 * (n.length / two_ac - 1):+.2f} % | {n.slipping_length:.2f} | "
        f"{n.max_slip / ur.DC:.3f} | {len(result.path)} | {result.bisections} | "
        f"{solver.linear.stats['solves']} | {wall:.1f} |"
    )


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--h", type=float, nargs="+", default=[2.0, 1.0, 0.5, 0.25])
    parser.add_argument("--shapes", nargs="+", default=["gaussian", "parabola"])
    parser.add_argument("--controls", nargs="+", default=["potency"])
    args = parser.parse_args()
    print(f"2 a_c = {2 * ur.critical_half_length():.3f} m")
    print(
        "| h [m] | cells over 2 a_c | load | control | dofs | onset lambda | "
        "2a [m] | error | stable set [m] | max slip / D_c | steps | bisections "
        "| linear solves | wall [s] |"
    )
    print("|" + " --- |" * 14)
    for h in args.h:
        for shape in args.shapes:
            for control in args.controls:
                print(one(h, shape, control), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
