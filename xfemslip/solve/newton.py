"""Load stepping and Newton-Raphson (paper eq. 21).

Residual r(u) = K_bulk u + f_con(u) - f_0 - lambda F_ext on the free dofs, where
f_0 is the contact force of the in-situ traction sigma0 . n at zero jump (the
force that balances the initial stress; zero without one).  Where the contact
law cannot carry that traction (shear above the friction limit, tension), f_0
differs from f_con(0) and the excess is released in the first load step
(ContactSet.in_situ_force).  Convergence: eta = ||r_free|| / ||F_ref|| <=
tolerance, where F_ref stacks the applied forces on the free dofs, the
released in-situ excess and the reactions on the prescribed ones, so
displacement-driven cases (no applied force at all) have a meaningful
reference (eta of the paper with F_ext including reactions).

Tangents: "consistent" uses the exact derivative of the return map (not
symmetric while slipping), which gives quadratic convergence once the
stick/slip set has settled; "secant" is the paper's eq. 28 update.  With the
consistent tangent the first solve of a step uses a predicted stick/slip set
(xfemslip.contact.predictor): when the guess is right the step converges in one
solve, when it is wrong Newton goes on from there under the true law.  The linear
systems go to xfemslip.solve.linear (SuperLU with the factorization kept, or
AMG-preconditioned GMRES), which handles the non-symmetric case.

The remedies for a stick/slip set that does not settle (ping-pong freezes,
slip-reversal holds, the local branch search) are in xfemslip.solve.remedies.
A load step Newton fails on is then solved by a fixed point on the normal
traction (Tresca problems, each a Newton solve), and where that fails too,
cut in halves.  What stays here, about 950 lines, is one piece:
NewtonSolver's load stepping with the fixed point and bisection, the Newton
loop that applies the remedies and restores the true law, the line search
and the failure messages share the solver's state (free dofs, reduced
stiffness, committed history, linear solver) from one iteration to the
next; cut apart they would pass that state back and forth without making
either half readable on its own.

Logging: one INFO line per converged load step (its iterations, cuts and
contact states); every Newton iteration, cut, prediction and remedy at DEBUG
(``-v`` on the command line).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from xfemslip.contact.branches import force_branches
from xfemslip.contact.defaults import AUTO_PENALTY, PENALTY_RATIO_MEASURED
from xfemslip.contact.interface import ContactResult, ContactSet
from xfemslip.contact.predictor import predict_state, predicted_law
from xfemslip.conventions import (
    OPEN,
    SLIP,
    STICK,
    TANGENT_CONSISTENT,
    TANGENT_SECANT,
    TANGENTS,
)
from xfemslip.errors import ConvergenceError
from xfemslip.solve import remedies
from xfemslip.solve.linear import LinearSolver
from xfemslip.solve.lowrank import stick_tangents

logger = logging.getLogger(__name__)

# kn*h/E above this is named in the message of a Newton failure as a likely cause.
PENALTY_RATIO_HIGH = 1.0e5
# Step halvings tried by the line search before keeping the best trial.
LINE_SEARCH_CUTS = 6
# Load-step bisection: a load step that does not converge is cut in halves, at
# most this many times by default ([solver] max_step_cuts), so the smallest
# sub-step is 1/2**5 = 1/32 of the step.  Every converged sub-step commits the
# friction history, exactly as a load step does; a failed attempt leaves the
# committed state untouched (nothing is committed before convergence).
DEFAULT_STEP_CUTS = 5
# The fixed point on the normal traction that solves a load step Newton failed
# on (NewtonSolver._fixed_point): at most FIXED_POINT_MAX Tresca problems,
# Anderson-accelerated over the last FIXED_POINT_DEPTH differences.
FIXED_POINT_MAX = 50
FIXED_POINT_DEPTH = 5
# Its first normal traction: that of the step under this many times the
# friction, where almost every patch sticks.  (With every patch held in
# stick instead, a patch at the edge of opening cycles between open and
# closed on the crowded network of NewtonSolver._fixed_point.)
FIXED_POINT_START = 10.0


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
    floating: list | None = None
    # largest penalty stiffness relative to the bulk, max(kn, kt) * h_min / E [-]
    penalty_ratio: float = 0.0
    # (n_nodes, 2) node coordinates: rigid-body modes of the AMG linear solver
    node_xy: np.ndarray | None = None
    # (n_dofs,) the node of each dof (an enriched dof's: the node it
    # enriches): SuperLU's elimination order is a nested dissection of the
    # grid (xfemslip.solve.ordering); None: SuperLU's minimum degree
    dof_node: np.ndarray | None = None
    # far-field stress (xx, yy, xy) [Pa] added from load factor 0 to 1
    # (predictor.stress_increment), or None: only used to guess the stick/slip
    # set of a step (predictor.py)
    load_stress: tuple[float, float, float] | None = None
    # (weights(lam) -> (m,), [F_1 .. F_m]): loads that are not proportional
    # to lam (pressure changes from a file at several times), added to
    # lam F_unit as sum_j weights_j(lam) F_j; None: none
    load_pieces: tuple[Callable[[float], np.ndarray], list[np.ndarray]] | None = None

    def load(self, lam: float) -> np.ndarray:
        """The external force at load factor lam (n_dofs,) [N/m]."""
        if self.load_pieces is None:
            return lam * self.F_unit
        weights, forces = self.load_pieces
        F = lam * self.F_unit
        for w, Fj in zip(weights(lam), forces, strict=True):
            F = F + w * Fj
        return F


@dataclass
class StepResult:
    step: int
    load_factor: float
    u: np.ndarray
    contact: ContactResult
    iterations: int
    residuals: list  # eta at every iteration (of the last sub-step)
    switches: list  # stick/slip/open switches at every iteration (idem)
    cuts: int = 0  # load-step bisections needed in this step
    substeps: int = 1  # converged sub-steps that make up this step
    freezes: int = 0  # ping-pong freezes (all sub-steps)
    factors: list | None = None  # load factors of the converged sub-steps, in order
    # sub-steps whose first Newton solve used the predicted stick/slip set
    predicted: int = 0
    # Newton steps re-solved with slip-reversing patches held in stick (each
    # one extra linear solve; remedies.slip_reversals), all sub-steps
    reversals: int = 0
    # local branch searches that found a consistent stick/slip set for a
    # patch reversing after its holds and its neighbours (all sub-steps)
    searches: int = 0
    # Tresca problems solved by the normal-traction fixed point (0: Newton
    # converged on the Coulomb law itself; NewtonSolver._fixed_point)
    fixed_point: int = 0


class NewtonSolver:
    """Newton-Raphson over load steps on a Problem; keeps the converged steps."""

    def __init__(
        self,
        problem: Problem,
        tolerance: float,
        max_iterations: int,
        tangent: str,
        linear_solver: str = "auto",
        *,
        max_step_cuts: int = DEFAULT_STEP_CUTS,
        predictor: bool = True,
    ):
        self.p = problem
        # guess the stick/slip set of each step (consistent tangent only: the
        # secant one is not exact within a set, so the guess would not pay)
        self.predictor = (
            bool(predictor) and tangent == "consistent" and problem.contact.n > 0
        )
        self.max_cuts = int(max_step_cuts)
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
        c = problem.contact
        self.c_dofs = np.where(c.dofs >= 0, self.reduced[np.maximum(c.dofs, 0)], -1)
        self.linear = LinearSolver(
            self.K_ff,
            linear_solver,
            self.free,
            problem.node_xy,
            self.c_dofs,
            kernels=c.kernels,
            contact_coef=c.coef,
            contact_stick=stick_tangents(c.weight, c.kn, c.kt, c.normal, c.tangent),
            dof_node=None if problem.dof_node is None else problem.dof_node[self.free],
        )
        # tangent blocks of the contact evaluations whose tangent is never
        # used (_scratch_blocks)
        self._scratch: np.ndarray | None = None
        zero = c.evaluate(
            np.zeros(n),
            self.mode,
            c.pt_committed,
            c.gt_committed,
            scratch=self._scratch_blocks(),
        )
        self.f_c0 = c.in_situ_force(zero)
        # the contact law at zero jump: what it admits of the in-situ traction
        # (kept for the log and deplete; its tangent blocks are not needed)
        self.in_situ = zero
        # the in-situ excess over the contact law (ContactSet.in_situ_force),
        # released from the first load step on: a load like lam F_ext, so it
        # is stacked into the reference of eta (None: nothing to release)
        self._release = (
            None if self.f_c0 is zero.force else (self.f_c0 - zero.force)[self.free]
        )
        self.completed: list[StepResult] = []
        # committed normal traction and load factor (for the predictor)
        self._pn_committed = c.pn0.copy()
        self._lam_committed = 0.0

    def run(self, steps: int) -> list[StepResult]:
        """Proportional loading in ``steps`` equal load steps."""
        return self.run_path([k / steps for k in range(1, steps + 1)])

    def run_path(self, factors) -> list[StepResult]:
        """Load steps ending at the load factors ``factors`` (from 0), in order.

        Proportional loading is ``run``; a path like [1, 0, 1, 0] loads and
        unloads (friction is path dependent: the history carries over).
        """
        u = np.zeros(self.p.n_dofs)
        lam0 = 0.0
        n = len(factors)
        for k, lam in enumerate(factors, start=1):
            u = self._advance(u, lam0, float(lam), k, n)
            lam0 = float(lam)
        return self.completed

    # The pieces that path following (xfemslip.solve.continuation) drives:
    # the equilibrium at a load factor, the residual, the tangent solve, and
    # the acceptance of a converged state as a step.

    def equilibrium(self, u, lam, step, steps):
        """Newton (with its remedies) to load factor ``lam`` from ``u`` and
        the committed history; nothing is committed.  Returns (u, contact
        result, iterations); raises ConvergenceError."""
        u, res, log = self._newton(u, lam, step, steps)
        return u, res, log.iterations

    def residual(self, u, lam, res: ContactResult):
        """(residual on the free dofs, eta) at u, load factor lam, with the
        contact result res of u."""
        return self._residual(u, lam, res)

    def solve_tangent(self, res: ContactResult, r, step, iteration, eta):
        """x with (K_ff + the contact tangent of res) x = r on the free dofs;
        ConvergenceError (step, iteration, eta) when the matrix is singular."""
        return self._solve(res, r, step, iteration, eta)

    def accept(self, step, lam, u, res: ContactResult, iterations) -> StepResult:
        """Commit the converged state (u, res) at load factor lam as step
        ``step`` (history, predictor state) and record its StepResult."""
        self.p.contact.commit(res)
        self._pn_committed = res.pn.copy()
        self._lam_committed = lam
        result = StepResult(
            step,
            lam,
            u.copy(),
            dataclasses.replace(res, blocks=None),
            iterations,
            [],
            [],
            factors=[lam],
        )
        self.completed.append(result)
        return result

    def _residual(self, u, lam, res: ContactResult, Ku=None):
        """(residual on the free dofs, eta) at u; ``Ku``: K @ u when known
        (the contact law changed but u did not, or _line_search's trials)."""
        f_int = (self.p.K @ u if Ku is None else Ku) + res.force - self.f_c0
        load = self.p.load(lam)
        r = f_int - load
        ref2 = float(np.sum(load[self.free] ** 2) + np.sum(r[self.p.fixed] ** 2))
        if self._release is not None:
            ref2 += float(np.sum(self._release**2))
        ref = math.sqrt(ref2)
        norm = float(np.linalg.norm(r[self.free]))
        eta = norm / ref if ref > 0.0 else (0.0 if norm == 0.0 else math.inf)
        return r[self.free], eta

    def _advance(self, u, lam0, lam1, k, steps):
        """Load step k from lam0 to lam1, bisected on failure (max_cuts times).

        The step is split into 2**max_cuts units; ``size`` is the current
        sub-step in units.  A converged sub-step commits the contact history
        and the next one tries twice the size; a failed one is retried from
        the last committed state at half the size.
        """
        start = time.perf_counter()
        solve_start = self.linear.stats["solve_time"]
        units = 1 << self.max_cuts
        done, size = 0, units
        cuts = substeps = iterations = freezes = predicted = reversals = 0
        searches = fixed_point = 0
        tried = False  # the normal-traction fixed point, once per step
        factors = []  # load factors of the converged sub-steps
        while done < units:
            end = min(done + size, units)
            lam = lam1 if end == units else lam0 + (lam1 - lam0) * end / units
            try:
                u_new, res, log = self._newton(u, lam, k, steps)
            except ConvergenceError as err:
                found = None
                if err.retryable and not tried and self._fixed_point_applies():
                    # once per load step, before the step is cut: the same
                    # problem, so the answer is the step's as posed
                    tried = True
                    found = self._fixed_point(u, lam, k, steps, err)
                if found is None:
                    if not err.retryable or size == 1:
                        if cuts or tried:
                            raise self._after_remedies(
                                err, cuts, size / units, tried
                            ) from None
                        raise
                    size //= 2
                    cuts += 1
                    lam_from = lam0 + (lam1 - lam0) * done / units
                    lam_to = lam0 + (lam1 - lam0) * (done + size) / units
                    logger.debug(
                        "step %d/%d: cutting the load step (cut %d of at most %d): "
                        "load factor %.6g -> %.6g (%s)",
                        k,
                        steps,
                        cuts,
                        self.max_cuts,
                        lam_from,
                        lam_to,
                        err.reason,
                    )
                    continue
                u_new, res, log = found
                fixed_point += log.fixed_point
            self.p.contact.commit(res)
            self._pn_committed = res.pn.copy()
            self._lam_committed = lam
            u = u_new
            done = end
            factors.append(lam)
            if cuts:  # after a success, try a sub-step twice as long again
                size = min(2 * size, units)
            substeps += 1
            iterations += log.iterations
            freezes += log.freezes
            predicted += log.predicted
            reversals += log.reversals
            searches += log.found
        if cuts:
            logger.debug(
                "step %d/%d converged in %d sub-steps after %d cut(s)",
                k,
                steps,
                substeps,
                cuts,
            )
        self._log_step_time(k, steps, start, solve_start)
        logger.info(
            "step %d/%d: converged in %d Newton iteration(s)%s; contact points: "
            "%d slip, %d stick, %d open",
            k,
            steps,
            iterations,
            (f" over {substeps} sub-steps after {cuts} cut(s)" if cuts else "")
            + (
                f" ({fixed_point} Tresca problems of a fixed point on the normal "
                "traction)"
                if fixed_point
                else ""
            ),
            np.count_nonzero(res.state == SLIP),
            np.count_nonzero(res.state == STICK),
            np.count_nonzero(res.state == OPEN),
        )
        self.completed.append(
            StepResult(
                k,
                lam1,
                u.copy(),
                # kept until the output is written; its tangent blocks (the
                # largest part on crowded networks) are never read again
                dataclasses.replace(res, blocks=None),
                iterations,
                log.residuals,
                log.switches,
                cuts=cuts,
                substeps=substeps,
                freezes=freezes,
                factors=factors,
                predicted=predicted,
                reversals=reversals,
                searches=searches,
                fixed_point=fixed_point,
            )
        )
        return u

    def _log_step_time(self, k, steps, start, solve_start):
        """Debug line: the step's wall time and its linear solves' time, and
        their ratio to the first step's (whose solve holds the factorization
        the later steps reuse)."""
        wall = time.perf_counter() - start
        solve = self.linear.stats["solve_time"] - solve_start
        if not self.completed:
            self._first_step_time = (wall, solve)
        first_wall, first_solve = self._first_step_time
        logger.debug(
            "step %d/%d: %.3f s (%.2f of step 1), linear solves %.3f s "
            "(%.2f of step 1's)",
            k,
            steps,
            wall,
            wall / first_wall if first_wall > 0 else 1.0,
            solve,
            solve / first_solve if first_solve > 0 else 1.0,
        )

    def _after_remedies(self, err, cuts, fraction, fixed_point=False):
        """The error of the last attempt, saying that the normal-traction
        fixed point (``fixed_point``: it was tried) and bisection did not
        help."""
        tried = []
        if fixed_point:
            tried.append("a fixed point on the normal traction (Tresca problems)")
        if cuts:
            tried.append(
                f"cutting the load step {cuts} time(s) (sub-steps down to "
                f"{fraction:.3g} of it)"
            )
        why = f"even after {' and '.join(tried)}: {err.reason}"
        return ConvergenceError(
            self._message(err.step, why, err.iteration, err.residual, err.flips),
            step=err.step,
            iteration=err.iteration,
            residual=err.residual,
            increment=err.increment,
            flips=err.flips,
            reason=why,
            retryable=err.retryable,
        )

    def _fixed_point_applies(self) -> bool:
        """Whether _fixed_point can help: some friction, none weakening (a
        weakening bound depends on the slip of the step as well)."""
        c = self.p.contact
        return bool(np.any(c.friction > 0.0)) and not np.any(c.weakens)

    def _fixed_point(self, u, lam, k, steps, first):
        """The load step that Newton failed on (``first``) at load factor
        ``lam``, solved from ``u`` by a fixed point on the normal traction:
        Coulomb's bound c - f p_N is frozen at the normal traction of the
        last iterate, which makes the step a Tresca problem (a bound that
        does not depend on the jump: the slip law is associated and its
        tangent symmetric, without the coupling dp_T/dg_N = -s f k_N that
        turns a crowded network's Newton iterations into cycles), solved by
        Newton; the normal tractions it gives bound the next one, the
        iterates Anderson-accelerated (FIXED_POINT_DEPTH).  The first
        normal traction is that of the step under FIXED_POINT_START times
        the friction.  The fixed point ends when the true Coulomb law at the
        iterate meets the Newton tolerance (the acceptance test of _newton),
        so the answer is the load step's.  Returns (u, contact result of the
        true law, _NewtonLog of all the Newton solves) or None when a Newton
        solve fails or FIXED_POINT_MAX Tresca problems do not converge.

        Measured on the DFN sweep's base with 100 fractures (ramp tips)
        loaded from zero in one step, where Newton on the Coulomb law cycles
        (and bisection cannot help: under a proportional load from zero
        every sub-step is the same problem scaled): at 100 x 100 cells the
        start and 14 Tresca problems in 30 Newton iterations (the whole run
        35 s, the 30 iterations of the failed Newton solve included); at 200
        x 200 cells 16 problems in 43 iterations (85 s; Newton and bisection
        had failed after 5 min 50 s).  Without the acceleration the fixed
        point contracts by about 0.8 and 0.94 per problem there (45
        problems, and eta still 3e-7 after 60)."""
        c = self.p.contact
        total = _NewtonLog()
        logger.debug(
            "step %d/%d: %s; solving the step by a fixed point on the normal "
            "traction (Tresca problems)",
            k,
            steps,
            first.reason,
        )

        def solve(law, u, what):
            try:
                u, res, log = self._newton(u, lam, k, steps, law)
            except ConvergenceError as err:
                logger.debug(
                    "step %d/%d: fixed point, %s: %s", k, steps, what, err.reason
                )
                return None
            for name in ("iterations", "freezes", "reversals", "searches", "found"):
                setattr(total, name, getattr(total, name) + getattr(log, name))
            total.residuals += log.residuals
            total.switches += log.switches
            return u, res

        raised = FIXED_POINT_START * c.friction
        out = solve(
            dataclasses.replace(c, friction=raised, friction_dynamic=raised),
            u,
            f"the start under {FIXED_POINT_START:g} x the friction",
        )
        if out is None:
            return None
        u, res = out
        x = res.pn.copy()
        X, G = [], []  # the last iterates and their changes, for Anderson
        zero = np.zeros_like(c.friction)
        for it in range(1, FIXED_POINT_MAX + 1):
            bound = c.shear_bound(np.minimum(x, 0.0))
            tresca = dataclasses.replace(
                c,
                friction=zero,
                friction_dynamic=zero,
                cohesion=bound,
                cohesion_dynamic=bound,
            )
            out = solve(tresca, u, f"Tresca problem {it}")
            if out is None:
                return None
            u, res = out
            true = c.evaluate(u, self.mode, c.pt_committed, c.gt_committed)
            _, eta = self._residual(u, lam, true)
            logger.debug(
                "step %d/%d: fixed point %d: eta = %.3e under the Coulomb law",
                k,
                steps,
                it,
                eta,
            )
            if eta <= self.tol:
                self._check_floating(true, k, total.iterations, eta)
                if not (np.all(np.isfinite(u)) and _finite(true)):
                    return None
                total.fixed_point = it
                return u, true, total
            X.append(x)
            G.append(res.pn - x)
            del X[: -FIXED_POINT_DEPTH - 1], G[: -FIXED_POINT_DEPTH - 1]
            x = _anderson(X, G)
        return None

    def _newton(self, u, lam, k, steps, contact=None):
        """Newton to load factor lam from u and the committed history.

        Returns (u, contact result, _NewtonLog); raises ConvergenceError.
        Nothing is committed here.  ``contact``: the contact law solved for
        (the model's by default; _fixed_point's raised friction and Tresca
        laws).
        """
        c = self.p.contact if contact is None else contact
        u = u.copy()
        u[self.p.fixed] = lam * self.p.fixed_values
        pt_prev, gt_prev = c.pt_committed.copy(), c.gt_committed.copy()
        prev_regime = remedies.regimes(c.state_committed, c.pt_committed)
        log = _NewtonLog()
        history = []  # regimes of the iterates under the current law
        law = c  # the contact law evaluated: c, or c with frozen points
        frozen = None
        held = np.zeros(c.n, np.int64)  # times each patch was held (slip_reversals)
        forced = False  # law forces the branches of a local search
        res = law.evaluate(u, self.mode, pt_prev, gt_prev)
        Ku = self.p.K @ u  # K u of the iterate (new contact laws at one u reuse it)
        r, eta = self._residual(u, lam, res, Ku)
        for it in range(self.max_it + 1):
            regime = remedies.regimes(res.state, res.pt)
            flips = int(np.count_nonzero(regime != prev_regime))
            log.residuals.append(eta)
            log.switches.append(flips)
            history.append(regime)
            logger.debug(
                "step %d/%d iteration %d: eta = %.3e; contact points: %d slip, %d "
                "stick, "
                "%d open; %d switched%s",
                k,
                steps,
                it,
                eta,
                np.count_nonzero(res.state == SLIP),
                np.count_nonzero(res.state == STICK),
                np.count_nonzero(res.state == OPEN),
                flips,
                "" if frozen is None else f"; {int(frozen.sum())} frozen",
            )
            if not np.isfinite(eta):
                raise self._fail(k, it, eta, flips, "the residual is not finite")
            if eta <= self.tol and (frozen is not None or forced):
                # converged with frozen points: restore the true law, go on
                logger.debug(
                    "step %d/%d: converged with %d frozen point(s)%s; "
                    "releasing them and checking the true contact law",
                    k,
                    steps,
                    0 if frozen is None else int(frozen.sum()),
                    " and searched branches" if forced else "",
                )
                law, frozen, forced, history = c, None, False, []
                res = law.evaluate(u, self.mode, pt_prev, gt_prev)
                r, eta = self._residual(u, lam, res, Ku)
                regime = remedies.regimes(res.state, res.pt)
                history.append(regime)
            if eta <= self.tol:
                self._check_floating(res, k, it, eta)
                if not (np.all(np.isfinite(u)) and _finite(res)):
                    raise self._fail(
                        k, it, eta, flips, "the solution is not finite (overflow)"
                    )
                log.iterations = it
                return u, res, log
            if it == self.max_it:
                raise self._fail(
                    k, it, eta, flips, self._no_convergence_reason(log.switches)
                )
            cycling = remedies.ping_pong(history)
            if cycling is not None and log.freezes < remedies.PINGPONG_MAX_FREEZES:
                frozen = cycling if frozen is None else (frozen | cycling)
                law = force_branches(c, stick_at=frozen)
                log.freezes += 1
                logger.debug(
                    "step %d/%d iteration %d: %d contact point(s) ping-pong "
                    "between stick and slip; freezing their state (freeze %d of "
                    "at most %d)",
                    k,
                    steps,
                    it,
                    int(cycling.sum()),
                    log.freezes,
                    remedies.PINGPONG_MAX_FREEZES,
                )
                history = []
                res = law.evaluate(u, self.mode, pt_prev, gt_prev)
                r, eta = self._residual(u, lam, res, Ku)
            guess = (
                self._guess(u, lam, regime, Ku)
                if it == 0 and frozen is None and contact is None
                else None
            )
            if guess is not None:  # first solve with the predicted set
                log.predicted = 1
                du = self._solve(guess[0], guess[1], k, it, eta)
                guess = None  # its tangent blocks are not needed any more
            else:
                du = self._solve(res, r, k, it, eta)
                flipped, stubborn = remedies.slip_reversals(
                    law,
                    u,
                    du,
                    self.free,
                    self.mode,
                    regime,
                    pt_prev,
                    gt_prev,
                    held,
                    self._scratch_blocks,
                )
                if (
                    flipped is None
                    and stubborn is not None
                    and log.searches < remedies.LOCAL_SEARCHES
                ):
                    log.searches += 1
                    searched = remedies.local_search(
                        c,
                        law,
                        u,
                        res,
                        r,
                        stubborn,
                        self.c_dofs,
                        self.K_ff,
                        self.free,
                        self.mode,
                    )
                    if searched is not None:
                        law, forced = searched, True
                        log.found += 1
                        logger.debug(
                            "step %d/%d iteration %d: the Newton step reverses "
                            "the slip of %d contact patch(es) held %d times "
                            "already; a consistent stick/slip set of them and "
                            "their neighbours was found: solving with it",
                            k,
                            steps,
                            it,
                            int(stubborn.sum()),
                            remedies.REVERSAL_HOLDS,
                        )
                        res = law.evaluate(u, self.mode, pt_prev, gt_prev)
                        r, eta = self._residual(u, lam, res, Ku)
                        regime = remedies.regimes(res.state, res.pt)
                        du = self._solve(res, r, k, it, eta)
                if flipped is not None:
                    held += flipped
                    frozen = flipped if frozen is None else (frozen | flipped)
                    law = force_branches(c, stick_at=frozen)
                    log.reversals += 1
                    logger.debug(
                        "step %d/%d iteration %d: the Newton step reverses the "
                        "slip of %d contact patch(es) (forward <-> backward); "
                        "holding them in stick, the state between the two",
                        k,
                        steps,
                        it,
                        int(flipped.sum()),
                    )
                    res = law.evaluate(u, self.mode, pt_prev, gt_prev)
                    r, eta = self._residual(u, lam, res, Ku)
                    regime = remedies.regimes(res.state, res.pt)
                    du = self._solve(res, r, k, it, eta)
            pt_prev, gt_prev, prev_regime = res.pt, res.gt, regime
            eta_before = eta
            u, res, r, eta, Ku = self._line_search(
                u, du, lam, eta, pt_prev, gt_prev, law, Ku
            )
            if self.mode == TANGENT_SECANT and not eta < eta_before:
                # the secant direction is no descent direction (it drops the
                # n-t coupling of the slip law): one consistent iteration
                logger.debug(
                    "step %d/%d iteration %d: the secant tangent gave no descent; "
                    "the next iteration uses the consistent tangent",
                    k,
                    steps,
                    it + 1,
                )
                res = law.evaluate(u, TANGENT_CONSISTENT, pt_prev, gt_prev)
        raise AssertionError("unreachable")

    def _guess(self, u, lam, regime, Ku):
        """(contact result, residual) at u (K u: ``Ku``) under the predicted
        stick/slip set (predictor.py), or None without a prediction or when
        it is the set of the true law at u already."""
        if not self.predictor:
            return None
        c = self.p.contact
        state, sign = predict_state(
            c, self._pn_committed, self.p.load_stress, lam - self._lam_committed
        )
        res = predicted_law(c, state, sign).evaluate(
            u, self.mode, c.pt_committed, c.gt_committed
        )
        guess = remedies.regimes(res.state, res.pt)
        if np.array_equal(guess, regime):
            return None
        logger.debug(
            "predicted stick/slip set: %d slip, %d stick, %d open (%d differ "
            "from the state at the start); first solve with it",
            np.count_nonzero(res.state == SLIP),
            np.count_nonzero(res.state == STICK),
            np.count_nonzero(res.state == OPEN),
            int(np.count_nonzero(guess != regime)),
        )
        return res, self._residual(u, lam, res, Ku)[0]

    def _line_search(self, u, du, lam, eta0, pt_prev, gt_prev, law, Ku):
        """Backtracking on eta along the Newton direction (Armijo on the norm).

        The full step is tried first and kept whenever it lowers eta, so
        Newton's quadratic convergence is untouched near the solution.  With a
        very stiff penalty the full step can overshoot the contact states
        (open <-> slip ping-pong); halving the step up to LINE_SEARCH_CUTS
        times restores a decrease.  If none decreases, the best trial is kept.
        Returns (u, contact result, residual, eta, K u) of the kept trial.

        K u is linear along the line: a shorter step's is (1 - a) K u + a
        K u_full from the start's (``Ku``) and the full
        step's, each a product with K, so a backtracking trial costs no
        product (a product took 10 ms of the 21 ms of a residual on a
        100-fracture network), and the error of the combination is
        round-off of the internal forces, not of the sum K_ij u_j: nothing
        accumulates over the iterations.
        """
        Ku_full = None
        best = None
        alpha = 1.0
        for _ in range(LINE_SEARCH_CUTS + 1):
            trial = u.copy()
            trial[self.free] -= alpha * du
            # Only the kept trial's tangent is used: the full step (the one
            # kept near the solution) gets its own blocks, a shorter one is
            # evaluated into the scratch blocks and, if kept, once more
            # below (same result, bit for bit).  A fresh tangent per trial
            # (up to 6 more per iteration of a stalling Newton solve) is an
            # array of 8 m (2J)^2 bytes, 10.7 MB on a crowded network.
            scratch = None if alpha == 1.0 else self._scratch_blocks()
            res = law.evaluate(trial, self.mode, pt_prev, gt_prev, scratch=scratch)
            if Ku_full is None:
                Ku_full = Ku_trial = self.p.K @ trial
            else:
                Ku_trial = (1.0 - alpha) * Ku + alpha * Ku_full
            r, eta = self._residual(trial, lam, res, Ku_trial)
            if best is None or eta < best[3]:
                best = (trial, res, r, eta, Ku_trial)
            if eta <= (1.0 - 1.0e-4 * alpha) * eta0:
                break
            alpha *= 0.5
        if best[1].blocks is None:  # the same evaluation, with its tangent
            best = (
                best[0],
                law.evaluate(best[0], self.mode, pt_prev, gt_prev),
                *best[2:],
            )
        if alpha < 1.0:
            logger.debug(
                "line search: step length %.3g (eta %.3e -> %.3e)", alpha, eta0, best[3]
            )
        return best

    def _scratch_blocks(self) -> np.ndarray:
        """The (m, 2J, 2J) array that contact evaluations whose tangent is
        not used write their tangent blocks into (ContactSet.evaluate), one
        per solver."""
        if self._scratch is None:
            c = self.p.contact
            self._scratch = np.empty((c.n, c.dofs.shape[1], c.dofs.shape[1]))
        return self._scratch

    def _no_convergence_reason(self, switches):
        """Why Newton stopped, and what to change."""
        why = f"no convergence in {self.max_it} iterations"
        if sum(1 for n in switches[-5:] if n > 0) >= 4:
            why += "; the contact states keep switching between iterations (ping-pong)"
            ratio = self.p.penalty_ratio
            if PENALTY_RATIO_HIGH < ratio <= PENALTY_RATIO_MEASURED:
                why += (
                    f", and the penalty is very stiff (kn*h/E up to {ratio:.1e}; "
                    f"10 to 1e4 is usual): lower kn/kt, or use more load steps"
                )
            else:
                why += "; use more load steps or raise [solver] max_iterations"
        for index, _ in self.p.floating or []:
            why += (
                f"; fractures[{index}] cuts the domain in two and one part is held "
                "by the fracture alone: when the shear driving that part reaches "
                "friction x normal force + cohesion x length there is no static "
                "equilibrium (rigid sliding without bound), and close to it Newton "
                "may not find one; prescribe a displacement on that part, or raise "
                "the friction or cohesion"
            )
        if self.mode == TANGENT_SECANT:
            why += (
                '; or set [solver] tangent = "consistent" (the secant tangent '
                "converges linearly at best)"
            )
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
                    retryable=False,
                )

    def _solve(self, res, r, k, it, eta):
        if not np.isfinite(eta):  # a remedy's law evaluated to inf or NaN
            raise self._fail(k, it, eta, 0, "the residual is not finite")
        try:
            du = self.linear.solve_contact(res.blocks, r)
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

    def _penalty_note(self) -> str:
        """Names a penalty above PENALTY_RATIO_MEASURED and the value to use
        instead, or ''."""
        ratio = self.p.penalty_ratio
        if not ratio > PENALTY_RATIO_MEASURED:
            return ""
        c = self.p.contact
        e_over_h = float(np.max(np.maximum(c.kn, c.kt))) / ratio  # [Pa/m]
        if not e_over_h > 0.0:  # the ratio overflowed (e.g. E = 1e-300 Pa)
            return "; the penalty kn*h/E is beyond the float range"
        kn, kt = (float(np.max(v)) / e_over_h for v in (c.kn, c.kt))
        top = PENALTY_RATIO_MEASURED
        return (
            f"; the penalty is stiffer than the range where Newton was measured to "
            f"converge (kn*h/E up to {kn:.1e}, kt*h/E up to {kt:.1e}; measured "
            f"0.1 to {top:.0e}), where the residual stalls at round-off: lower "
            f"kn/kt to at most {top * e_over_h:.3g} Pa/m ({top:.0e} E/h; the "
            f"default {AUTO_PENALTY:.0f} E/h = {AUTO_PENALTY * e_over_h:.3g} Pa/m "
            "moves the slip of the shipped cases by at most 0.04 % of its maximum)"
        )

    def _fail(self, k, it, eta, flips, why, *, retryable=True):
        """The ConvergenceError of load step k; ``retryable`` False when a
        smaller load step cannot cure it (no bisection)."""
        why += self._penalty_note()
        return ConvergenceError(
            self._message(k, why, it, eta, flips),
            step=k,
            iteration=it,
            residual=eta,
            flips=flips,
            reason=why,
            retryable=retryable,
        )

    def _message(self, k, why, it, eta, flips) -> str:
        """The one-line message of a ConvergenceError."""
        return (
            f"load step {k} did not converge: {why}; iteration {it}, residual eta = "
            f"{eta:.3e} (tolerance {self.tol:.1e}), {flips} stick/slip switches in "
            f"the last iteration; {len(self.completed)} converged step(s) kept"
        )


@dataclass
class _NewtonLog:
    """What one Newton solve did."""

    iterations: int = 0
    freezes: int = 0
    reversals: int = 0  # Newton steps that held reversing patches in stick
    searches: int = 0  # local branch searches (xfemslip.contact.branches)
    found: int = 0  # of them, those that found a consistent set
    predicted: int = 0  # 1 if the first solve used the predicted set
    residuals: list = field(default_factory=list)
    switches: list = field(default_factory=list)
    fixed_point: int = 0  # Tresca problems of NewtonSolver._fixed_point


def _anderson(X, G) -> np.ndarray:
    """The next iterate of the fixed point x = x + g(x) by Anderson
    acceleration (type II) from the iterates X and their changes G (lists,
    oldest first): x + g - (dX + dG) gamma, gamma the least-squares fit of
    g by the differences dG (Walker & Ni 2011, SIAM J. Numer. Anal. 49)."""
    x, g = X[-1], G[-1]
    if len(X) == 1:
        return x + g
    dX = np.diff(np.array(X), axis=0).T
    dG = np.diff(np.array(G), axis=0).T
    gamma = np.linalg.lstsq(dG, g, rcond=None)[0]
    return x + g - (dX + dG) @ gamma


def _finite(res: ContactResult) -> bool:
    return all(
        np.all(np.isfinite(a)) for a in (res.force, res.gn, res.gt, res.pn, res.pt)
    )
