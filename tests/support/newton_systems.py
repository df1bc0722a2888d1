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


def solve_like_spsolve(newton, systems, ls, kernels="numpy"):
    """Solve every (blocks, r) of ``systems`` with ``ls.solve_contact`` in
    turn, asserting each answer's backward error against the assembled
    matrix K_ff + the blocks (at most LU_BACKWARD_ERROR) and its agreement
    with spsolve to 1e-8.  Returns (the number of times the blocks changed,
    including the first system; each matrix's relative asymmetry)."""
    import numpy as np
    import scipy.sparse.linalg as spla

    from xfemslip.fem.assembly import coo_block
    from xfemslip.solve.linear import LU_BACKWARD_ERROR, backward_error

    changes, last, asym = 0, None, []
    for blocks, r in systems:
        A = (
            newton.K_ff + coo_block(newton.c_dofs, blocks, newton.free.size, kernels)
        ).tocsc()
        asym.append(abs(A - A.T).max() / abs(A).max())
        changes += last is None or not np.array_equal(blocks, last)
        last = blocks
        x = ls.solve_contact(blocks, r)
        assert backward_error(A, x, r) <= LU_BACKWARD_ERROR
        x_ref = spla.spsolve(A, r)
        assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    return changes, asym
