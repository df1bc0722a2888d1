"""Initial guesses from earlier solutions (xfemslip.solve.guess): the
least-squares projection is exact on the span of the kept solutions, optimal
off it, and a LinearSolver on a repeated sequence of systems skips the Krylov
iterations it does not need while giving the direct solution."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from xfemslip.case import build, loads_case
from xfemslip.simulation import build_model
from xfemslip.solve import linear as linsolve
from xfemslip.solve.guess import KEEP, PreviousSolutions
from xfemslip.solve.newton import NewtonSolver

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"


def _nonsymmetric(n, seed=0):
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=0.05, random_state=rng) + 4.0 * sp.identity(n)
    return sp.csr_matrix(A), rng


def test_a_right_hand_side_in_the_span_is_solved_exactly():
    A, rng = _nonsymmetric(200)
    xs = [rng.standard_normal(200) for _ in range(3)]
    prev = PreviousSolutions()
    for x in xs:
        prev.add(x)
    x_true = 2.0 * xs[0] - 0.5 * xs[2]
    x0, res = prev.guess(A, A @ x_true)
    assert np.linalg.norm(x0 - x_true) <= 1e-12 * np.linalg.norm(x_true)
    assert res <= 1e-12 * np.linalg.norm(A @ x_true)


def test_off_the_span_the_residual_is_orthogonal_to_a_x():
    """The normal equations of min ||A X c - b||: (A X)^T (A X c - b) = 0,
    and no other combination has a smaller residual."""
    A, rng = _nonsymmetric(150, seed=3)
    prev = PreviousSolutions()
    X = [rng.standard_normal(150) for _ in range(4)]
    for x in X:
        prev.add(x)
    b = rng.standard_normal(150)
    x0, res = prev.guess(A, b)
    W = A @ np.column_stack(X)
    assert np.abs(W.T @ (A @ x0 - b)).max() <= 1e-10 * np.linalg.norm(
        W
    ) * np.linalg.norm(b)
    assert res == pytest.approx(np.linalg.norm(A @ x0 - b), rel=1e-12)
    for _ in range(20):
        other = np.column_stack(X) @ rng.standard_normal(4)
        assert np.linalg.norm(A @ other - b) >= res


def test_only_the_last_solutions_are_kept_and_degenerate_ones_are_not():
    prev = PreviousSolutions()
    assert prev.guess(sp.identity(5), np.ones(5)) == (None, pytest.approx(np.sqrt(5)))
    prev.add(np.zeros(5))
    prev.add(np.full(5, np.nan))
    assert len(prev) == 0
    for k in range(KEEP + 3):
        prev.add(np.eye(12)[k])
    assert len(prev) == KEEP
    # the oldest ones are gone: e_0 is not in the span any more
    x0, res = prev.guess(sp.identity(12), np.eye(12)[0])
    assert res == pytest.approx(1.0)
    # a repeated solution makes A X rank-deficient; the guess stays exact
    prev.add(np.eye(12)[11])
    x0, res = prev.guess(sp.identity(12), 3.0 * np.eye(12)[11])
    assert np.allclose(x0, 3.0 * np.eye(12)[11]) and res <= 1e-12


@pytest.mark.parametrize("method", ["amg", "superlu"])
def test_a_repeated_system_costs_no_krylov_iteration(method, monkeypatch):
    """The slip system of the cracked reservoir solved, then solved again with
    a scaled right-hand side (a later load step of a proportional load with
    the same contact tangent): the second answer is the direct solution and
    takes no Krylov iteration; a new right-hand side still matches.  SuperLU
    solves through its kept factorization of another tangent (Schwarz-GMRES;
    the band limits lifted for this small mesh)."""
    pytest.importorskip("pyamg")
    monkeypatch.setattr(linsolve, "LU_BAND_LAYERS", 2)
    monkeypatch.setattr(linsolve, "LU_BAND_MAX_FRACTION", 1.0)
    text = build.case_text(build.file_case(CASE, **{"mesh.elements": [30, 30]}))
    model = build_model(loads_case(text, CASE))
    newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", method)
    ls = newton.linear
    rng = np.random.default_rng(7)
    n = newton.free.size
    # a non-symmetric contact tangent on the enriched dofs
    dofs = np.nonzero(newton.free >= 2 * model.mesh.nodes.shape[0])[0][:8]
    Kc = sp.csr_matrix(
        (1e9 * (1.0 + rng.random(64)), (np.repeat(dofs, 8), np.tile(dofs, 8))),
        shape=(n, n),
    )
    A = (newton.K_ff + Kc).tocsc()
    r = rng.standard_normal(n)
    if method == "superlu":  # make the second system go through the kept LU
        ls.solve(Kc * 0.5, r)
    x1 = ls.solve(Kc, r)
    its = ls.stats["krylov_iterations"]
    x2 = ls.solve(Kc, 2.5 * r)
    x_ref = spla.spsolve(A, r)
    for x, scale in ((x1, 1.0), (x2, 2.5)):
        assert np.linalg.norm(x - scale * x_ref) <= 1e-8 * np.linalg.norm(scale * x_ref)
    assert ls.stats["krylov_iterations"] == its
    assert ls.stats["guesses_exact"] == 1
    r3 = rng.standard_normal(n)
    x3 = ls.solve(Kc, r3)
    x3_ref = spla.spsolve(A, r3)
    assert np.linalg.norm(x3 - x3_ref) <= 1e-8 * np.linalg.norm(x3_ref)
    assert ls.stats["krylov_iterations"] > its
