"""Local branch search (xfemslip.contact.branches): the stick/slip set it returns
for a cluster of patches is checked against a full sparse solve of the same
affine problem and the true return map at its solution."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from xfemslip.case import build, loads_case
from xfemslip.contact import branches as local_branches
from xfemslip.contact.branches import force_branches
from xfemslip.conventions import SLIP
from xfemslip.fem.assembly import coo_block
from xfemslip.simulation import build_model
from xfemslip.solve.newton import NewtonSolver

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"


def _setup(friction):
    keys = {"mesh.elements": [20, 20], "fractures.0.friction": friction}
    text = build.case_text(build.file_case(CASE, **keys))
    model = build_model(loads_case(text, CASE))
    solver = NewtonSolver(model.problem, 1e-10, 60, "consistent", predictor=False)
    c = model.problem.contact
    u = np.zeros(model.problem.n_dofs)
    u[model.problem.fixed] = model.problem.fixed_values
    return solver, c, u


def _exact(solver, law, u):
    """One Newton solve under a law fixed on every branch (affine: exact)."""
    c = solver.p.contact
    res = law.evaluate(u, solver.mode, c.pt_committed, c.gt_committed)
    r, _ = solver._residual(u, 1.0, res)
    u1 = u.copy()
    u1[solver.free] -= solver._solve(res, r, 1, 0, 1.0)
    res1 = law.evaluate(u1, solver.mode, c.pt_committed, c.gt_committed)
    return u1, solver._residual(u1, 1.0, res1)[1]


def _on_branches(c, idx, branches):
    """c with the patches idx held on branches (0 stick, +-1 slip)."""
    moving = branches != 0
    return force_branches(
        c, stick_at=idx[~moving], slip_at=idx[moving], sign=branches[moving]
    )


@pytest.mark.parametrize("friction", [0.1, 0.3])
def test_searched_branches_solve_the_cluster_consistently(friction):
    solver, c, u = _setup(friction)
    res = c.evaluate(u, solver.mode, c.pt_committed, c.gt_committed)
    r, _ = solver._residual(u, 1.0, res)
    mid = c.n // 2
    idx = np.arange(mid - 2, mid + 2)  # 4 patches: 81 combinations
    mask = np.zeros(c.n, bool)
    mask[idx] = True
    rest = np.nonzero(~mask)[0]
    now = local_branches.current_branches(res, rest)
    stick = force_branches(c, stick_at=mask).evaluate(
        u, solver.mode, c.pt_committed, c.gt_committed
    )
    blocks = res.blocks.copy()
    blocks[mask] = stick.blocks[mask]
    K = solver.K_ff + coo_block(solver.c_dofs, blocks, solver.free.size, c.kernels)
    branches = local_branches.search(c, solver.c_dofs, K, u[solver.free], res, r, idx)
    assert branches is not None
    # the far-field load makes the middle of the fault slip (paper, Sec. 4)
    assert np.all(branches != 0)
    # independent check: the whole model with the rest held on its branches
    # and the cluster on the searched ones, solved by one sparse solve ...
    law = _on_branches(_on_branches(c, rest, now), idx, branches)
    u1, eta = _exact(solver, law, u)
    assert eta < 1e-10
    # ... where the true return map gives the searched branches back
    true = c.evaluate(u1, solver.mode, c.pt_committed, c.gt_committed)
    got = np.where(true.state[idx] == SLIP, np.sign(true.pt[idx]), 0)
    np.testing.assert_array_equal(got, branches)
    # and the opposite slip direction is not consistent there
    law = _on_branches(_on_branches(c, rest, now), idx, -branches)
    u2, _ = _exact(solver, law, u)
    true = c.evaluate(u2, solver.mode, c.pt_committed, c.gt_committed)
    got = np.where(true.state[idx] == SLIP, np.sign(true.pt[idx]), 0)
    assert not np.array_equal(got, -branches)


def test_neighbours_are_the_patches_sharing_a_cell():
    solver, c, _ = _setup(0.1)
    one = np.zeros(c.n, bool)
    one[c.n // 2] = True
    near = local_branches.neighbours(solver.c_dofs, solver.K_ff, one)
    assert near[c.n // 2]
    # a single straight fault: the neighbours are the patches next to it
    # along the fault, a few, not the whole fault
    assert 2 <= int(near.sum()) - 1 <= 6
    assert np.all(np.abs(np.nonzero(near)[0] - c.n // 2) <= 3)


def test_a_second_search_may_hold_a_patch_the_first_forced_to_slip():
    """A patch that one search forced to slip (committed slip -sign x inf)
    and a later search holds in stick: on cluster_base its committed slip is
    its own again, so the held patch carries the finite stick traction of
    the true law (on the first search's law held in stick its traction was
    infinite, and a crowded network's Newton solve stopped on NaN)."""
    from xfemslip.conventions import STICK
    from xfemslip.solve.remedies import cluster_base

    solver, c, u = _setup(0.3)
    mid = c.n // 2
    u1, _ = _exact(solver, c, u)  # the slipping solution of the step
    first = _on_branches(c, np.array([mid]), np.array([1]))
    # a hold on top (ping-pong or slip reversal): infinite cohesion at mid
    held = force_branches(first, stick_at=np.array([mid, mid + 1]))
    mask = np.zeros(c.n, bool)
    mask[[mid, mid + 1]] = True
    stale = force_branches(held, stick_at=mask).evaluate(
        u1, solver.mode, c.pt_committed, c.gt_committed
    )
    assert not np.isfinite(stale.pt[mid])  # premise: the failure it fixes
    base = cluster_base(c, held, mask)
    np.testing.assert_array_equal(base.slip_committed, c.slip_committed)
    np.testing.assert_array_equal(base.cohesion, c.cohesion)
    got = force_branches(base, stick_at=mask).evaluate(
        u1, solver.mode, c.pt_committed, c.gt_committed
    )
    stick = force_branches(c, stick_at=mask).evaluate(
        u1, solver.mode, c.pt_committed, c.gt_committed
    )
    assert np.all(np.isfinite(got.pt)) and np.all(np.isfinite(got.force))
    assert np.all(got.state[mask] == STICK)
    np.testing.assert_array_equal(got.pt, stick.pt)
    np.testing.assert_array_equal(got.force, stick.force)
