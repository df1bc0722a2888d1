"""The Newton systems of a run, recorded as it solves them: what the linear
solver tests replay through other paths (tests/unit/solve)."""

from __future__ import annotations

from xfemslip.case import loads_case
from xfemslip.simulation import build_model
from xfemslip.solve.newton import NewtonSolver


def recorded_systems(text, path, steps):
    """The Newton systems (blocks, r) of a run of the case ``text`` (read as
    if from ``path``), in order, solved by SuperLU without the stick/slip
    predictor, and its solver."""
    model = build_model(loads_case(text, path))
    solver = NewtonSolver(
        model.problem, 1e-10, 30, "consistent", "superlu", predictor=False
    )
    systems = []
    solve = solver._solve

    def record(res, r, k, it, eta):
        systems.append((res.blocks.copy(), r.copy()))
        return solve(res, r, k, it, eta)

    solver._solve = record
    solver.run(steps)
    return solver, systems
