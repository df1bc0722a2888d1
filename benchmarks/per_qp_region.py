#!/usr/bin/env python3
"""Cost of the per-quadrature-point reservoir in enriched cells (xfemslip.fem.poro):
bulk assembly of the same model with one material (the default path), with a
reservoir by cell only (qp_material=None) and with the per-QP split, and the
Biot body load; median of several calls after a warm-up, ratios from the
same run.  ``--default-only`` times the first row alone, with the API that
older trees have, to compare a branch with main (PYTHONPATH=... each).

    python benchmarks/per_qp_region.py [--case CASE.toml] [--runs 7]
"""

from __future__ import annotations

import argparse
import statistics
import time

from xfemslip.case import load_case
from xfemslip.fem.assembly import assemble_bulk
from xfemslip.simulation import build_model


def median_time(fn, runs: int) -> float:
    """Median wall time [s] of fn() over runs calls, after one warm-up call."""
    fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def former_vs_current(model, runs: int) -> None:
    """Enriched-cell matrices of the one-material path: the former direct
    kernel call against assembly._enriched_matrices, interleaved, same process."""
    import numpy as np

    from xfemslip import kernels
    from xfemslip.fem.assembly import _enriched_matrices

    mesh, ec, D = model.mesh, model.ec, model.D

    def former():
        return kernels.backend(model.kernels).enriched_cell_matrices(
            np.ascontiguousarray(mesh.bounds[ec.cells]),
            ec.qp_offsets,
            ec.qp_xy,
            ec.qp_w,
            ec.column_offsets,
            ec.column_F,
            ec.column_gradF,
            ec.slot_column,
            ec.slot_node,
            ec.slot_fnode,
            np.ascontiguousarray(D),
        )

    def current():
        return _enriched_matrices(mesh, ec, D, None, backend=model.kernels)

    a, b = former(), current()
    same = all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    t_f, t_c = [], []
    for _ in range(runs):
        for fn, out in ((former, t_f), (current, t_c)):
            start = time.perf_counter()
            fn()
            out.append(time.perf_counter() - start)
    f, c = statistics.median(t_f), statistics.median(t_c)
    print(
        f"| former kernel call | {f * 1e3:.2f} ms |\n| _enriched_matrices | "
        f"{c * 1e3:.2f} ms | ratio {c / f:.3f}, bitwise equal: {same}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="cases/depleting_reservoir.toml")
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument(
        "--default-only",
        action="store_true",
        help="time the one-material assembly only (runs on older trees too)",
    )
    args = parser.parse_args()
    model = build_model(load_case(args.case))
    from xfemslip.fem.enrichment import find_candidates
    from xfemslip.fem.poro import body_load

    mesh, ec, ip, mats = model.mesh, model.ec, model.ip, model.materials
    cand = find_candidates(mesh, model.fractures)
    rows = {
        "one material (default path)": lambda: assemble_bulk(
            mesh, model.D, cand, ec, ip, backend=model.kernels
        ),
        "reservoir, enriched cells by cell": lambda: assemble_bulk(
            mesh, mats.D, cand, ec, ip, mats.cell, backend=model.kernels
        ),
        "reservoir, enriched cells per QP": lambda: assemble_bulk(
            mesh, mats.D, cand, ec, ip, mats.cell, mats.qp, backend=model.kernels
        ),
        "Biot body load (per QP in enriched cells)": lambda: body_load(
            mesh, model.bulk, model.pore, ec, model.kernels
        ),
    }
    if args.default_only:
        rows = dict(list(rows.items())[:1])
    else:
        former_vs_current(model, args.runs)
    print(f"{args.case}: {mesh.n_cells} cells, {ec.cells.size} enriched")
    base = None
    for name, fn in rows.items():
        t = median_time(fn, args.runs)
        base = base or t
        print(f"| {name} | {t * 1e3:.1f} ms | {t / base:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
