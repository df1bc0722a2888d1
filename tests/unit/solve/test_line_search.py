"""The line search's K u: a backtracking trial takes (1 - a) K u + a K u_full
instead of a product with K (NewtonSolver._line_search).  Each kept trial's
K u must be the product K @ u of that trial to round-off, and the answer of
a run that backtracks must be the one of the same run with every K u
computed as a product."""

from __future__ import annotations

import numpy as np

import xfemslip.solve.newton as newton
from tests.support.matrix import RESERVOIR, point_fields, reservoir_text, solve

E, N = 5.0e9, 18


def stiff_case() -> str:
    """kn h / E = 1e8 and a cohesion: the full Newton step overshoots the
    contact states and the line search backtracks (to 1/8 of the step)."""
    return reservoir_text(n=N, cohesion=2.5e6, kn=1.0e8 * E * N)


def test_kept_trials_carry_their_own_K_u(monkeypatch):
    real = newton.NewtonSolver._line_search
    seen = []

    def spy(self, u, du, *args):
        out = real(self, u, du, *args)
        trial, Ku = out[0], out[4]
        step = (u - trial)[self.free]
        alpha = float(np.dot(step, du) / np.dot(du, du))
        # the round-off floor of the product itself: eps sum_j |K_ij u_j|
        floor = float((abs(self.p.K) @ abs(trial)).max())
        seen.append((alpha, float(np.abs(Ku - self.p.K @ trial).max()) / floor))
        return out

    monkeypatch.setattr(newton.NewtonSolver, "_line_search", spy)
    out = solve(stiff_case(), RESERVOIR, "consistent")
    assert out.converged
    alphas = [a for a, _ in seen]
    assert min(alphas) < 0.5, alphas  # the combination was used and kept
    assert max(err for _, err in seen) < 1.0e-14, seen


def test_backtracking_run_ends_where_products_everywhere_end(monkeypatch):
    """The same run with K u recomputed as a product for every trial
    (the plain line search) reaches the same slip to the Newton tolerance,
    in the same number of iterations."""
    fast = solve(stiff_case(), RESERVOIR, "consistent")
    real_residual = newton.NewtonSolver._residual

    def product(self, u, lam, res, Ku=None):
        return real_residual(self, u, lam, res)

    monkeypatch.setattr(newton.NewtonSolver, "_residual", product)
    plain = solve(stiff_case(), RESERVOIR, "consistent")
    assert fast.converged and plain.converged
    assert fast.iterations == plain.iterations
    slip_fast = point_fields(fast.steps[-1].contact)[0]
    slip_plain = point_fields(plain.steps[-1].contact)[0]
    scale = float(np.abs(slip_plain).max())
    assert scale > 0.0
    assert np.abs(slip_fast - slip_plain).max() <= 1.0e-8 * scale
