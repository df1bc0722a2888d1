"""Load stepping and Newton-Raphson (paper eq. 21).

Residual r(u) = K_bulk u + f_con(u) - f_con(0) - lambda F_ext on the free dofs
(f_con(0) is the in-situ contact force that balances the initial stress, zero
without one).  Convergence: eta = ||r_free|| / ||F_ref|| <= tolerance, where
F_ref stacks the applied forces on the free dofs and the reactions on the
prescribed ones, so displacement-driven cases (no applied force at all) have a
meaningful reference (eta of the paper with F_ext including reactions).

Tangents: "consistent" uses the exact derivative of the return map (not
symmetric while slipping), which gives quadratic convergence once the
stick/slip set has settled; "secant" is the paper's eq. 28 update.  The linear
systems go to xfemslip.linsolve (SuperLU with the factorization kept, or
AMG-preconditioned GMRES), which handles the non-symmetric case.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from xfemslip import kernels
from xfemslip.assembly import coo_block
from xfemslip.contact import OPEN, SLIP, STICK, ContactResult, ContactSet
from xfemslip.errors import ConvergenceError
from xfemslip.linsolve import LinearSolver

logger = logging.getLogger(__name__)

# kn*h/E above this is named in the message of a Newton failure as a likely cause.
PENALTY_RATIO_HIGH = 1.0e5
# Step halvings tried by the line search before keeping the best trial.
LINE_SEARCH_CUTS = 6

TANGENTS = {"consistent": kernels.TANGENT_CONSISTENT, "secant": kernels.TANGENT_SECANT}


@dataclass
class Problem:
    K: sp.csr_matrix  # bulk stiffness (n_dofs, n_dofs)
    F_unit: np.ndarray  # external force at load factor 1 (n_dofs,)
    fixed: np.ndarray  # prescribed dofs
    fixed_values: np.ndarray  # their final values
    contact: ContactSet
    n_dofs: int
    # (fracture index in the case file, mask of its contact points) for each
    # fracture that cuts the domain in two with one part left without any
    # prescribed displacement: that part is held by the fracture alone.
    floating: list = None
    # largest penalty stiffness relative to the bulk, max(kn, kt) * h_min / E [-]
    penalty_ratio: float = 0.0
    # (n_nodes, 2) node coordinates: rigid-body modes of the AMG linear solver
    node_xy: np.ndarray = None


@dataclass
class StepResult:
    step: int
    load_factor: float
    u: np.ndarray
    contact: ContactResult
    iterations: int
    residuals: list  # eta at every iteration
    switches: list  # stick/slip/open switches at every iteration


def _regime(state, pt):
    """Branch of the contact law at each point: open, stick, slip forward (+t),
    slip backward.  A switch between any two changes the tangent, so it is what
    the log and the ConvergenceError count as a stick/slip switch."""
    return np.where(state == SLIP, np.where(pt >= 0.0, SLIP, SLIP + 1), state)


class NewtonSolver:
    """Newton-Raphson over load steps on a Problem; keeps the converged steps."""

    def __init__(
        self,
        problem: Problem,
        tolerance: float,
        max_iterations: int,
        tangent: str,
        linear_solver: str = "auto",
    ):
        self.p = problem
        self.tol = tolerance
        self.max_it = max_iterations
        self.mode = TANGENTS[tangent]
        n = problem.n_dofs
        free = np.ones(n, bool)
        free[problem.fixed] = False
        self.free = np.nonzero(free)[0]
        self.reduced = -np.ones(n, np.int64)
        self.reduced[self.free] = np.arange(self.free.size)
        self.K_ff = problem.K[self.free][:, self.free].tocsr()
        self.linear = LinearSolver(self.K_ff, linear_solver, self.free, problem.node_xy)
        c = problem.contact
        self.c_dofs = np.where(c.dofs >= 0, self.reduced[np.maximum(c.dofs, 0)], -1)
        zero = c.evaluate(np.zeros(n), self.mode, c.pt_committed, c.gt_committed)
        self.f_c0 = zero.force
        self.completed: list[StepResult] = []

    def run(self, steps: int) -> list[StepResult]:
        u = np.zeros(self.p.n_dofs)
        for k in range(1, steps + 1):
            u = self._step(u, k, steps)
        return self.completed

    def _residual(self, u, lam, res: ContactResult):
        f_int = self.p.K @ u + res.force - self.f_c0
        r = f_int - lam * self.p.F_unit
        ref = math.sqrt(
            float(
                np.sum((lam * self.p.F_unit[self.free]) ** 2)
                + np.sum(r[self.p.fixed] ** 2)
            )
        )
        norm = float(np.linalg.norm(r[self.free]))
        eta = norm / ref if ref > 0.0 else (0.0 if norm == 0.0 else math.inf)
        return r[self.free], eta

    def _step(self, u, k, steps):
        lam = k / steps
        c = self.p.contact
        u = u.copy()
        u[self.p.fixed] = lam * self.p.fixed_values
        pt_prev, gt_prev = c.pt_committed.copy(), c.gt_committed.copy()
        prev_regime = _regime(c.state_committed, c.pt_committed)
        residuals = []
        switches = []
        res = c.evaluate(u, self.mode, pt_prev, gt_prev)
        r, eta = self._residual(u, lam, res)
        for it in range(self.max_it + 1):
            regime = _regime(res.state, res.pt)
            flips = int(np.count_nonzero(regime != prev_regime))
            residuals.append(eta)
            switches.append(flips)
            logger.info(
                "step %d/%d iteration %d: eta = %.3e; contact points: %d slip, %d "
                "stick, "
                "%d open; %d switched",
                k,
                steps,
                it,
                eta,
                np.count_nonzero(res.state == SLIP),
                np.count_nonzero(res.state == STICK),
                np.count_nonzero(res.state == OPEN),
                flips,
            )
            if not np.isfinite(eta):
                raise self._fail(k, it, eta, flips, "the residual is not finite")
            if eta <= self.tol:
                self._check_floating(res, k, it, eta)
                c.commit(res)
                self.completed.append(
                    StepResult(k, lam, u.copy(), res, it, residuals, switches)
                )
                return u
            if it == self.max_it:
                raise self._fail(
                    k, it, eta, flips, self._no_convergence_reason(switches)
                )
            du = self._solve(res, r, k, it, eta)
            pt_prev, gt_prev, prev_regime = res.pt, res.gt, regime
            u, res, r, eta = self._line_search(u, du, lam, eta, pt_prev, gt_prev)
        raise AssertionError("unreachable")

    def _line_search(self, u, du, lam, eta0, pt_prev, gt_prev):
        """Backtracking on eta along the Newton direction (Armijo on the norm).

        The full step is tried first and kept whenever it lowers eta, so
        Newton's quadratic convergence is untouched near the solution.  With a
        very stiff penalty the full step can overshoot the contact states
        (open <-> slip ping-pong); halving the step up to LINE_SEARCH_CUTS
        times restores a decrease.  If none decreases, the best trial is kept.
        """
        c = self.p.contact
        best = None
        alpha = 1.0
        for _ in range(LINE_SEARCH_CUTS + 1):
            trial = u.copy()
            trial[self.free] -= alpha * du
            res = c.evaluate(trial, self.mode, pt_prev, gt_prev)
            r, eta = self._residual(trial, lam, res)
            if best is None or eta < best[3]:
                best = (trial, res, r, eta)
            if eta <= (1.0 - 1.0e-4 * alpha) * eta0:
                break
            alpha *= 0.5
        if alpha < 1.0:
            logger.info(
                "line search: step length %.3g (eta %.3e -> %.3e)", alpha, eta0, best[3]
            )
        return best

    def _no_convergence_reason(self, switches):
        """Why Newton stopped, and what to change."""
        why = f"no convergence in {self.max_it} iterations"
        if sum(1 for n in switches[-5:] if n > 0) >= 4:
            why += "; the contact states keep switching between iterations (ping-pong)"
            ratio = self.p.penalty_ratio
            if ratio > PENALTY_RATIO_HIGH:
                why += (
                    f", and the penalty is very stiff (kn*h/E up to {ratio:.1e}; "
                    f"10 to 1e4 is usual): lower kn/kt, or use more load steps"
                )
            else:
                why += "; use more load steps or raise [solver] max_iterations"
        return why

    def _check_floating(self, res, k, it, eta):
        """A block held only by a fracture with no sticking point slides unbounded."""
        for index, mask in self.p.floating or []:
            if mask.any() and not np.any(res.state[mask] == STICK):
                raise self._fail(
                    k,
                    it,
                    eta,
                    0,
                    f"fractures[{index}] cuts the domain in two and one part has no "
                    "prescribed "
                    "displacement, so only the fracture holds it; no point of the "
                    "fracture "
                    "sticks, so that part slides without bound (no static "
                    "equilibrium). "
                    "Prescribe a displacement on that part (e.g. on its edge) or raise "
                    "the "
                    "friction or cohesion",
                )

    def _solve(self, res, r, k, it, eta):
        Kc = coo_block(self.c_dofs, res.blocks, self.free.size)
        try:
            du = self.linear.solve(Kc, r)
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise self._fail(
                k,
                it,
                eta,
                0,
                f"the tangent matrix is singular ({exc}); a part "
                "of the body may be free to move (e.g. a block cut off by a "
                "fracture with nothing holding it)",
            ) from None
        if not np.all(np.isfinite(du)):
            raise self._fail(k, it, eta, 0, "the linear solve gave non-finite values")
        return du

    def _fail(self, k, it, eta, flips, why):
        return ConvergenceError(
            f"load step {k} did not converge: {why}; iteration {it}, residual eta = "
            f"{eta:.3e} "
            f"(tolerance {self.tol:.1e}), {flips} stick/slip switches in the last "
            "iteration; "
            f"{len(self.completed)} converged step(s) kept",
            step=k,
            iteration=it,
            residual=eta,
            flips=flips,
        )
