#!/usr/bin/env python3
"""Time to build (not solve) a case with hundreds of generated fractures:
realizing the network and validating the case (``load_case``), then the
geometry check of ``xfemslip check`` (mesh + fractures against the mesh),
then everything ``run`` builds before the first Newton iteration
(``simulation.build_model``: enrichment, quadrature, assembly).  Medians of
several runs in one process (the first, which compiles Numba kernels, is a
warm-up and not counted).

    python benchmarks/dfn_build.py [--count 200] [--runs 5] [--mesh 100]
"""

from __future__ import annotations

import argparse
import logging
import statistics
import tempfile
import time
from pathlib import Path


def case_text(count: int, mesh: int, tip: str = "ramp") -> str:
    from xfemslip.case import build

    h = 1.0 / mesh
    return build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [mesh, mesh]},
            "material": {"E": 5.0e9, "nu": 0.3},
            "network": {
                "friction": 0.3,
                "tip": tip,
                "generate": {
                    "seed": 7,
                    "count": count,
                    "intersections": "avoid",
                    "min_spacing": 1.2 * h,
                    "outside": "reject",
                    "orientation": {
                        "distribution": "von_mises",
                        "mean": 45.0,
                        "kappa": 2.0,
                    },
                    "length": {
                        "distribution": "power_law",
                        "exponent": 2.5,
                        "min": 4 * h,
                        "max": 12 * h,
                    },
                },
            },
            "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6}},
            "boundary": {
                "bottom": {"uy": 0.0},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
        }
    )


def timings(path: Path) -> dict:
    from xfemslip.case import load_case
    from xfemslip.simulation import build_model, check_geometry

    t0 = time.perf_counter()
    spec = load_case(path)
    t1 = time.perf_counter()
    check_geometry(spec)
    t2 = time.perf_counter()
    model = build_model(spec)
    t3 = time.perf_counter()
    assert len(spec.fractures) == len(model.fractures)
    return {"load_case": t1 - t0, "check_geometry": t2 - t1, "build_model": t3 - t2}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--mesh", type=int, default=100)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "dfn.toml"
        path.write_text(case_text(args.count, args.mesh))
        timings(path)  # warm-up: Numba kernels
        runs = [timings(path) for _ in range(args.runs)]
    print(f"{args.count} fractures, {args.mesh} x {args.mesh} cells, {args.runs} runs")
    for key in runs[0]:
        values = [r[key] for r in runs]
        print(
            f"  {key:15s} median {statistics.median(values):.3f} s "
            f"(min {min(values):.3f}, max {max(values):.3f})"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
