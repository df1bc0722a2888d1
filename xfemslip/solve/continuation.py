"""Quasi-static path following up to the loss of equilibrium of a fault with
slip-weakening friction: the nucleation of dynamic rupture.

With friction that weakens with slip, a slowly raised load makes the slipping
patch of a fault grow until no neighbouring equilibrium exists: the load
factor lambda reaches a maximum along the equilibrium path and the slip per
unit of load grows without bound (Uenishi & Rice 2003, JGR 108(B1) 2042).
Load control cannot pass that point, and near it Newton fails for any step
size, which says nothing about where the point is.  Here the path is
followed with the slip as the control (indirect displacement control, de
Borst 1987, Computers & Structures 25), and the maximum of lambda is located
by bisection on the control.

The path in two stages:

1. **Approach** (load control).  From the start state, load steps
   (NewtonSolver.equilibrium, with its remedies) until a patch of a
   slip-weakening fracture slips: each to just past the load factor where
   the tangent predicts the first of them reaches its bound, at most
   ``load_step``.  A step whose slip on those patches exceeds
   ``approach_slip`` D_c is halved: the control stage starts close to first
   slip, before any limit point.
2. **Slip control** (bordered Newton).  The load factor is an unknown and
   one equation is added: the control c(u) = a . u rises by dc per step.
   With ``control = "potency"`` (default), a . u = sum_p w_p s_p g_T,p over
   the closed patches of the slip-weakening fractures (w_p the patch length,
   s_p the sign of its shear traction at the start of the step): the slip
   potency of those fractures [m^2].  With ``"max_slip"``, a . u = s_j g_T,j
   of the patch j with the largest accumulated slip [m].  Both are linear in
   u within a step, so the bordered system

       [K_t   dR/dlambda] [du     ]     [R     ]
       [a^T   0         ] [dlambda] = - [a . (u - u_n) - dc]

   is solved by two solves with the tangent K_t (Crisfield 1991, ch. 9):
   K_t x_r = R and K_t x_f = dR/dlambda, then dlambda = -(g + a . x_r) /
   (a . x_f) with g the constraint's residual, du = -x_r - dlambda x_f.
   The bordered matrix stays regular at the limit point, where K_t is
   singular.  At a converged state the slope of the path is
   dlambda/dc = -1 / (a . x_f) (one more solve with the converged tangent).

The control measures the slip of the fault itself, so its step size is
measured in slip: dc = ``slip_step`` D_c times the slipping length (potency)
or D_c (max_slip), D_c the smallest slip distance of the weakening patches.
Two caps keep a step on the path.  Between changes of the set of slipping
patches the problem is linear (for linear weakening at constant p_N), so a
step ends just past the next sticking weakening patch that the tangent
predicts to reach its bound (APPROACH_OVERSHOOT past it, and at least
APPROACH_MIN_STEP of ``load_step`` past the start: a patch predicted on its
bound must be pushed over it, or round-off decides); and no step
moves the load factor by more than ``load_step`` (near first slip the
control answers mostly through the elastic penalty, where a slip-sized step
is a large load step).  The size grows by GROW after a step converged in at
most EASY_ITERATIONS iterations and halves after one that needed
HARD_ITERATIONS or more, within [``min_slip_step``, ``max_slip_step``]; a
failed step is retried at CUT of it, and a step that fails at
``min_slip_step`` is a ConvergenceError (one line: step, iteration,
residual), with the converged steps kept in ``solver.completed``.  A
converged state that has left the path (its load factor moved by more than
``load_step``, or a patch slipped by EXCURSION times the step's slip: an
equilibrium of a fault ruptured far beyond the nucleation patch, which
reaches the same control value) counts as a failed step, and so does a
Newton iteration that returns to a stick/slip set it had left.

**Limit point.**  A step whose end has dlambda/dc <= 0 or a lambda below the
previous one brackets the maximum of lambda between its two ends.  The
bracket is bisected on the control (every trial a bordered solve from the
committed start of the step, nothing committed) until it is narrower than
``limit_tolerance`` of the control reached; the state at its lower end (the
last equilibrium with dlambda/dc > 0) is committed as the final step and
reported: the load factor (the seismic onset), the length of the slipping
patch (the nucleation length 2a, placed within its last whole patch by the
zero of the slope: ``_zero_slope_length``) and the point of largest slip (the
nucleation point).  A path that reaches ``max_load`` first ends with a load
step to it and reports no nucleation.

Measured on the Uenishi & Rice problem (benchmarks/nucleation.py,
docs/method.md "Nucleation"): the two controls give the same onset (to
1e-5), the same length and about the same number of linear solves, on
10 to 82 cells over the nucleation length.  The potency is the default: it
weighs the slip of every weakening patch, where the other follows one patch
chosen at the start of each step.  A spherical arc length on all the dofs
(Crisfield 1981) was not used: the displacement of the whole body is
dominated by its elastic response to the load, in which the slip of a
nucleation patch is a small part, so such a constraint is close to load
control at a localized limit point (de Borst 1987).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field

import numpy as np

from xfemslip.contact.interface import ContactResult, PatchGeometry
from xfemslip.conventions import OPEN, SLIP, STICK
from xfemslip.errors import ConvergenceError
from xfemslip.fem.assembly import scatter_vector
from xfemslip.solve import remedies

logger = logging.getLogger(__name__)

__all__ = [
    "CONTROLS",
    "ContinuationOptions",
    "ContinuationResult",
    "Nucleation",
    "PathPoint",
    "follow_to_nucleation",
]

CONTROLS = ("potency", "max_slip")
# Step-size adaptation: a step converged in at most EASY_ITERATIONS Newton
# iterations lets the next one grow by GROW; one that needed HARD_ITERATIONS
# or more halves it; a failed step is retried at CUT of its size.
EASY_ITERATIONS = 3
HARD_ITERATIONS = 8
GROW = 1.5
CUT = 0.25
# Bisections of the approach's load step before the stage gives up.
APPROACH_CUTS = 30
# The approach's step goes this fraction of itself past the predicted first
# slip of a weakening patch, so that the patch slips (by a slip of the order
# of this fraction of the step's elastic shear over k_T).
APPROACH_OVERSHOOT = 1.0e-3
# ... and at least this fraction of load_step, so that a patch predicted on
# its bound (a prediction of zero) still moves the path.
APPROACH_MIN_STEP = 1.0e-6
# A converged control step whose slip on some weakening patch exceeds this
# many times the step's slip (the control step over its length) has left the
# path (_check_excursion).
EXCURSION = 50.0
# Lag of the plastic slip (a fraction of the elastic slip p_T / k_T) that
# puts a committed slipping patch on its slip branch for the first tangent of
# a path started from a committed slipping state (_slipping_tangent).
SLIP_TANGENT_LAG = 1.0e-9


@dataclass(frozen=True, kw_only=True)
class ContinuationOptions:
    """Options of :func:`follow_to_nucleation` (slip steps in units of D_c)."""

    max_load: float = 1.0  # the path ends at this load factor [-]
    load_step: float = 0.05  # largest load-factor change of one step [-]
    approach_slip: float = 0.02  # largest slip at the end of the approach [D_c]
    control: str = "potency"  # "potency" | "max_slip"
    slip_step: float = 0.02  # first control step [D_c]
    min_slip_step: float = 1.0e-5  # [D_c]
    max_slip_step: float = 0.2  # [D_c]
    limit_tolerance: float = 1.0e-3  # bracket of the limit point / control [-]
    max_steps: int = 2000  # control steps

    def __post_init__(self):
        if self.control not in CONTROLS:
            raise ValueError(f"control must be one of {CONTROLS}, got {self.control!r}")
        if not 0.0 < self.min_slip_step <= self.slip_step <= self.max_slip_step:
            raise ValueError("need 0 < min_slip_step <= slip_step <= max_slip_step")


@dataclass(frozen=True)
class PathPoint:
    """One converged state along the path."""

    load_factor: float  # lambda [-]
    control: float  # c - c_start: potency [m^2] or slip [m] since the start
    slope: float  # d lambda / d control there (nan during the approach)
    max_slip: float  # largest accumulated slip of a weakening patch [m]
    slipping_length: float  # slipping length of the weakening fractures [m]
    iterations: int  # Newton iterations of the step that reached it
    step: int  # the StepResult.step it is recorded as


@dataclass(frozen=True)
class Nucleation:
    """The loss of quasi-static equilibrium (the limit point)."""

    # lambda at the limit point, the seismic onset [-]: the larger of the
    # load factors at the two ends of the final bracket (the maximum lies
    # between them, within the bracket times the path's slope)
    load_factor: float
    load_factor_stable: float  # lambda of the last stable state (lower end) [-]
    fracture: int  # case-file index of the fracture that goes unstable
    # the nucleation length 2a [m]: the slipping length where the path's
    # slope with the slipping set frozen vanishes (_zero_slope_length)
    length: float
    # length of the slipping patch of the last stable state [m] (whole
    # patches: the set that is still stable)
    slipping_length: float
    x: float  # the point of largest slip on it [m]
    y: float
    max_slip: float  # the largest accumulated slip there [m]
    control: float  # the control at the limit point (PathPoint.control)
    bracket: float  # width of the final bracket on the control


@dataclass
class ContinuationResult:
    path: list[PathPoint] = field(default_factory=list)
    nucleation: Nucleation | None = None  # None: not within max_load
    bisections: int = 0  # bordered solves spent locating the limit point


@dataclass
class _State:
    """A converged state of the path: displacement, load factor, contact
    result (with its tangent), Newton iterations, slope d lambda / d control
    and x_f = K_t^-1 dR/dlambda there (None: not solved)."""

    u: np.ndarray
    lam: float
    res: ContactResult
    iterations: int
    slope: float
    x_f: np.ndarray | None


def follow_to_nucleation(
    solver,
    geometry: PatchGeometry,
    options: ContinuationOptions | None = None,
    start=None,
) -> ContinuationResult:
    """Follow the equilibrium path of ``solver``'s problem from ``start``
    until quasi-static equilibrium is lost or the load factor reaches
    ``options.max_load`` (module docstring).

    Parameters
    ----------
    solver : NewtonSolver
        Its problem's load (F_unit, prescribed values) is scaled by the load
        factor; its committed contact history is the start state's.  Every
        converged state of the path is committed and appended to
        ``solver.completed`` (StepResult, numbered on from the last one).
    geometry : PatchGeometry
        Where the contact patches lie (contact.interface.patch_geometry).
    options : ContinuationOptions
    start : (u (n_dofs,) [m], load factor) or None
        The committed state to start from; None: the last step of
        ``solver.completed``, or zero load.

    Returns
    -------
    ContinuationResult: the path and the nucleation (None when the load
    factor reaches ``max_load`` first).

    Raises
    ------
    ConvergenceError
        Newton does not converge at the smallest step (one line: step,
        iteration, residual), or the case has no slip-weakening fracture
        (``retryable`` False).  The converged steps stay in
        ``solver.completed``.
    """
    return _Follower(solver, geometry, options or ContinuationOptions()).run(start)


class _Follower:
    """The state of one path following (see follow_to_nucleation)."""

    def __init__(self, solver, geometry, options):
        self.solver = solver
        self.geometry = geometry
        self.opt = options
        self.c = solver.p.contact
        self.weak = self.c.weakens
        self.result = ContinuationResult()
        if self.weak.any():
            self.dc = float(self.c.slip_distance[self.weak].min())

    # ------------------------------------------------------------ driver
    def run(self, start) -> ContinuationResult:
        s = self.solver
        if not self.weak.any():
            raise self._error(
                len(s.completed) + 1,
                0,
                math.nan,
                "no fracture has a slip-weakening friction, so no loss of "
                "equilibrium to follow",
                retryable=False,
            )
        if start is None:
            last = s.completed[-1] if s.completed else None
            start = (last.u, last.load_factor) if last else (np.zeros(s.p.n_dofs), 0.0)
        u, lam = np.array(start[0], float), float(start[1])
        # the control's origin, set when the control stage starts
        self.c0: float | None = None
        u, lam, res = self._approach(u, lam)
        if res is None or lam >= self.opt.max_load:
            return self.result
        self._control(u, lam, res)
        return self.result

    # ------------------------------------------------------------ approach
    def _approach(self, u, lam):
        """Load steps until a weakening patch slips; returns (u, lam, the
        contact result there) or (u, lam, None) at max_load without slip.

        While the weakening patches stick, the tangent at the current state
        predicts linearly where the first of them reaches its bound
        (``_first_slip``); the step goes just past it (APPROACH_OVERSHOOT of
        the step), at most ``load_step``.  The response is linear while
        everything sticks, so the prediction is exact there; elsewhere (other
        fractures slipping, faces opening) the loop checks and goes on.
        """
        s, opt = self.solver, self.opt
        c = self.c
        step = opt.load_step
        cuts = 0
        res = c.evaluate(u, s.mode, c.pt_committed, c.gt_committed)
        # a start state that slips already (the law evaluated from its own
        # history sticks there: its trial tractions sit on the bounds)
        if np.any((c.state_committed == SLIP) & self.weak):
            return u, lam, self._slipping_tangent(u)
        for _ in range(opt.max_steps):
            if lam >= opt.max_load:
                break
            k = len(s.completed) + 1
            ahead = max(self._first_slip(res, k), APPROACH_MIN_STEP * opt.load_step)
            target = min(lam + (1.0 + APPROACH_OVERSHOOT) * ahead, lam + step)
            target = min(target, opt.max_load)
            acc0 = c.accumulated_committed.copy()
            try:
                u1, res1, its = s.equilibrium(u, target, k, k)
            except ConvergenceError as err:
                if cuts >= APPROACH_CUTS:
                    raise
                logger.info(
                    "approach: load step to %.6g did not converge (%s); halving",
                    target,
                    err.reason,
                )
                step = 0.5 * (target - lam)
                cuts += 1
                continue
            grew = float(np.max(res1.accumulated[self.weak] - acc0[self.weak]))
            if grew > opt.approach_slip * self.dc and cuts < APPROACH_CUTS:
                step = 0.5 * (target - lam)  # the step went well past first slip
                cuts += 1
                continue
            u, lam, res = u1, target, res1
            self._record(k, lam, u, res, its, math.nan)
            if np.any((res.state == SLIP) & self.weak):
                logger.info(
                    "approach: a slip-weakening patch slips at load factor %.6g; "
                    "following the path with the %s as control",
                    lam,
                    opt.control,
                )
                return u, lam, res
        if lam < opt.max_load:
            raise self._error(
                len(s.completed) + 1,
                0,
                math.nan,
                f"no slip of a weakening patch within {opt.max_steps} load steps",
                retryable=False,
            )
        return u, lam, None

    def _slipping_tangent(self, u) -> ContactResult:
        """The law at the committed state u with the tangent of its slipping
        patches: evaluated from a history whose plastic slip lags by
        SLIP_TANGENT_LAG of the elastic slip |p_T| / k_T, so that those
        patches return on their slip branch (the true history puts their
        trial traction on the bound, which counts as stick).  Never
        committed; its tractions differ from the committed ones by that
        fraction."""
        c, s = self.c, self.solver
        lag = np.where(
            c.state_committed == SLIP,
            SLIP_TANGENT_LAG * c.pt_committed / c.kt,
            0.0,
        )
        law = dataclasses.replace(c, slip_committed=c.slip_committed - lag)
        return law.evaluate(u, s.mode, c.pt_committed, c.gt_committed)

    def _first_slip(self, res, k, x_f=None) -> float:
        """Load-factor increment [-] at which the first sticking weakening
        patch reaches its bound, extrapolated linearly with the tangent of
        res (inf when none is predicted to); x_f: K_t^-1 dR/dlambda there
        (None: solved here).

        Per patch p_N(d) = p_N + d p_N', p_T(d) = p_T + d p_T' with the
        rates of the jump rate -K_t^-1 dR/dlambda; the bound B = c - f p_N
        (at the committed accumulated slip) is met on the + branch at
        d = (B - p_T) / (p_T' + f p_N') and on the - branch at
        d = (B + p_T) / (f p_N' - p_T')."""
        s, c = self.solver, self.c
        rate = np.zeros(s.p.n_dofs)
        if x_f is None:
            x_f = s.solve_tangent(res, self._load_derivative(res), k, 0, 0.0)
        rate[s.free] = -x_f
        rate[s.p.fixed] = s.p.fixed_values
        jump = np.where(c.dofs >= 0, rate[np.maximum(c.dofs, 0)], 0.0)
        jx = (c.coef * jump[:, 0::2]).sum(axis=1)
        jy = (c.coef * jump[:, 1::2]).sum(axis=1)
        dpn = c.kn * (jx * c.normal[:, 0] + jy * c.normal[:, 1])
        dpt = c.kt * (jx * c.tangent[:, 0] + jy * c.tangent[:, 1])
        f = c.friction_at(c.accumulated_committed)
        bound = c.shear_bound(res.pn, c.accumulated_committed)
        with np.errstate(divide="ignore", invalid="ignore"):
            plus = (bound - res.pt) / (dpt + f * dpn)
            minus = (bound + res.pt) / (f * dpn - dpt)
        ahead = np.concatenate([plus, minus])
        closed = np.tile(self.weak & (res.state == STICK), 2)
        ahead = ahead[closed & np.isfinite(ahead) & (ahead > 0.0)]
        return float(ahead.min()) if ahead.size else math.inf

    # ------------------------------------------------------------ control stage
    def _control(self, u, lam, res):
        s, opt = self.solver, self.opt
        size = opt.slip_step
        here = _State(u, lam, res, 0, math.inf, None)
        for _ in range(opt.max_steps):
            k = len(s.completed) + 1
            a = self._control_vector(here.res)
            if self.c0 is None:
                self.c0 = float(a @ u[s.free])
                self._origin = a
            dc = size * self.dc * self._control_scale(here.res)
            # no step should move the load factor by more than load_step:
            # near first slip the control answers mostly through the
            # elastic penalty, and a slip-sized step there is a huge load step
            if here.x_f is None:
                here.x_f = self._load_response(here)
                here.slope = self._slope(a, here.x_f)
            if here.slope > 0.0:
                # the path is linear until the slipping set changes: the
                # step ends just past the next patch predicted to slip
                # at least APPROACH_MIN_STEP of load_step, as in the
                # approach: a patch predicted on its bound (a prediction of
                # round-off size) must be pushed past it, or the steps stall
                # there and round-off decides which patches slip
                ahead = max(
                    self._first_slip(here.res, k, here.x_f),
                    APPROACH_MIN_STEP * opt.load_step,
                )
                ahead = min((1.0 + APPROACH_OVERSHOOT) * ahead, opt.load_step)
                dc = min(dc, ahead / here.slope)
            try:
                end = self._bordered(here, a, dc, k)
            except ConvergenceError as err:
                # the step may have been capped below the size (the next
                # patch to slip): cut what was tried
                tried = min(size, dc / (self.dc * self._control_scale(here.res)))
                if tried * CUT < opt.min_slip_step:
                    raise self._error(
                        k,
                        err.iteration,
                        err.residual,
                        f"{err.reason} at the smallest control step "
                        f"({opt.min_slip_step:g} D_c)",
                    ) from None
                size = max(tried * CUT, opt.min_slip_step)
                logger.info(
                    "continuation step %d: no convergence (%s); control step "
                    "cut to %.3g D_c",
                    k,
                    err.reason,
                    size,
                )
                continue
            if end.lam > opt.max_load:  # reached on the rising path
                self._finish_at_max_load(here.u, k)
                return
            if not self._stable_after(here, end):
                self._locate(here, end, a, dc, k)
                return
            here = end
            self._record(k, end.lam, end.u, end.res, end.iterations, end.slope)
            if end.iterations <= EASY_ITERATIONS:
                size = min(size * GROW, opt.max_slip_step)
            elif end.iterations >= HARD_ITERATIONS:
                size = max(size * 0.5, opt.min_slip_step)
        raise self._error(
            len(s.completed) + 1,
            0,
            math.nan,
            f"no limit point within {opt.max_steps} control steps",
            retryable=False,
        )

    def _control_vector(self, res: ContactResult, control=None) -> np.ndarray:
        """a (n_free,): the gradient of the control (default the option's),
        a . u_free = the control."""
        c, s = self.c, self.solver
        closed = self.weak & (res.state != OPEN)
        sign = np.where(res.pt >= 0.0, 1.0, -1.0)
        if (control or self.opt.control) == "potency":
            weight = np.where(closed, c.weight * sign, 0.0)
        else:
            acc = np.where(closed, res.accumulated, -np.inf)
            j = int(np.argmax(acc))
            weight = np.zeros(c.n)
            weight[j] = sign[j]
        # g_T,p = sum_k coef_pk (u_x t_x + u_y t_y) over the patch's jump dofs
        values = np.empty(c.dofs.shape)
        values[:, 0::2] = (weight[:, None] * c.coef) * c.tangent[:, 0:1]
        values[:, 1::2] = (weight[:, None] * c.coef) * c.tangent[:, 1:2]
        return scatter_vector(c.dofs, values, c.n_dofs)[s.free]

    def _control_scale(self, res) -> float:
        """Length [m] that turns a slip step into a control step: the
        slipping length of the weakening patches for the potency (at least
        their longest patch), 1 for the max slip."""
        if self.opt.control != "potency":
            return 1.0
        c = self.c
        slipping = float(c.weight[self.weak & (res.state == SLIP)].sum())
        return max(slipping, float(c.weight[self.weak].max()))

    # ------------------------------------------------------------ bordered Newton
    def _bordered(self, start: _State, a, dc, k) -> _State:
        """Equilibrium with a . (u - u0) = dc from the committed state
        ``start`` = (u0, lam0, the contact result it converged with, ...).

        The tangent of start.res makes the first iteration: from
        the committed history the law at u0 sticks everywhere (the trial
        traction of a slipping patch is on its bound), and a stick tangent
        would ask the whole control step of the elastic penalty alone, a
        load step that overshoots by orders of magnitude."""
        s, c = self.solver, self.c
        free, fixed = s.free, s.p.fixed
        u0, converged = start.u, start.res
        u, lam = u0.copy(), start.lam
        res = c.evaluate(u, s.mode, c.pt_committed, c.gt_committed)
        r, eta = s.residual(u, lam, res)
        u0f = u0[free]
        seen: list[bytes] = []  # the successive stick/slip sets of the iterates
        for it in range(s.max_it + 1):
            uf = u[free]
            g = dc - float(a @ (uf - u0f))
            if (
                it > 0
                and eta <= s.tol
                and abs(g) <= _constraint_tolerance(a, uf, u0f, dc)
            ):
                self._check_excursion(start, u, lam, res, dc, k, it, eta)
                x_f = s.solve_tangent(res, self._load_derivative(res), k, it, eta)
                return _State(u, lam, res, it, self._slope(a, x_f), x_f)
            if it == s.max_it:
                break
            regime = remedies.regimes(res.state, res.pt).tobytes()
            if not seen or regime != seen[-1]:
                if regime in seen:
                    # the set came back after another one: the full steps
                    # cycle between sets around the step's end; a shorter
                    # step ends closer to the start's set
                    raise self._error(k, it, eta, "the stick/slip states cycle")
                seen.append(regime)
            tangent = converged if it == 0 and converged.blocks is not None else res
            x_r = s.solve_tangent(tangent, r, k, it, eta)
            x_f = s.solve_tangent(tangent, self._load_derivative(tangent), k, it, eta)
            denominator = float(a @ x_f)
            if not (np.isfinite(denominator) and denominator != 0.0):
                raise self._error(
                    k, it, eta, "the load does not move the control (a . x_f = 0)"
                )
            dlam = -(g + float(a @ x_r)) / denominator
            u[free] += -x_r - dlam * x_f
            lam += dlam
            u[fixed] = lam * s.p.fixed_values
            res = c.evaluate(u, s.mode, c.pt_committed, c.gt_committed)
            r, eta = s.residual(u, lam, res)
            if not np.isfinite(eta):
                raise self._error(k, it + 1, eta, "the residual is not finite")
        raise self._error(k, s.max_it, eta, f"no convergence in {s.max_it} iterations")

    @staticmethod
    def _stable_after(before: _State, state: _State) -> bool:
        """Whether ``state``, reached from ``before`` along the path, is
        still below the limit point: the load still rises (a positive slope
        and no lower load factor)."""
        return state.slope > 0.0 and state.lam >= before.lam

    def _check_excursion(self, start, u, lam, res, dc, k, it, eta) -> None:
        """ConvergenceError when a converged state lies off the path: its
        load factor moved by more than load_step, or a weakening patch
        slipped by more than EXCURSION times the step's slip (dc over the
        control's length).  Such an equilibrium exists (a fault ruptured
        far beyond the nucleation patch, at another load: the same control
        value is reached there too), but Newton only got there by leaving
        the neighbourhood of the start; a smaller step stays on the path."""
        moved = abs(lam - start.lam)
        slip = float(np.max(np.abs(res.accumulated - start.res.accumulated)[self.weak]))
        step_slip = dc / self._control_scale(start.res)
        if moved > self.opt.load_step:
            why = f"the step left the path (load factor moved by {moved:.3g})"
        elif slip > EXCURSION * step_slip:
            why = f"the step left the path (a patch slipped by {slip:.3g} m)"
        else:
            return
        raise self._error(k, it, eta, why)

    def _load_derivative(self, res) -> np.ndarray:
        """dR/dlambda on the free dofs: -F_ext plus the tangent times the
        prescribed values (u_fixed = lambda u_bar)."""
        s = self.solver
        p = s.p
        q = -p.F_unit[s.free]
        if p.fixed.size and np.any(p.fixed_values != 0.0):
            e = np.zeros(p.n_dofs)
            e[p.fixed] = p.fixed_values
            q = q + (p.K @ e)[s.free]
            c = self.c
            if res.blocks is not None and c.dofs.size:
                ve = np.where(c.dofs >= 0, e[np.maximum(c.dofs, 0)], 0.0)
                f = np.einsum("mij,mj->mi", res.blocks, ve)
                q = q + scatter_vector(c.dofs, f, p.n_dofs)[s.free]
        return q

    @staticmethod
    def _slope(a, x_f) -> float:
        """d lambda / d control = -1 / (a . x_f) (K_t u' + q lambda' = 0,
        a . u' = 1)."""
        d = float(a @ x_f)
        return -1.0 / d if d != 0.0 else math.inf

    # ------------------------------------------------------------ limit point
    def _locate(self, start: _State, end: _State, a, dc, k):
        """Bisect the control step (0, dc] from the committed state ``start``
        (``end``: the state at dc, past the maximum of lambda) for the
        maximum; commit and report the state at the bracket's lower end."""
        opt = self.opt
        lo, hi = 0.0, dc
        lo_state, hi_state = start, end
        assert self.c0 is not None  # a limit point is met in the control stage
        control_here = abs(float(a @ start.u[self.solver.free]) - self.c0) + dc
        while hi - lo > opt.limit_tolerance * control_here:
            mid = 0.5 * (lo + hi)
            self.result.bisections += 1
            state = self._bordered(start, a, mid, k)
            if self._stable_after(lo_state, state):
                lo, lo_state = mid, state
            else:
                hi, hi_state = mid, state
        if max(lo_state.lam, hi_state.lam) > opt.max_load:
            # the maximum lies beyond the load: the rising path reaches it
            self._finish_at_max_load(start.u, k)
            return
        if lo_state is not start:
            self._record(
                k,
                lo_state.lam,
                lo_state.u,
                lo_state.res,
                lo_state.iterations,
                lo_state.slope,
            )
        point = self.result.path[-1]
        self.result.nucleation = self._nucleation(lo_state, hi_state, point, hi - lo)
        n = self.result.nucleation
        logger.info(
            "loss of equilibrium at load factor %.6g: fracture %d, slipping "
            "patch %.4g m long, largest slip %.4g m at (%.4g, %.4g) (%d "
            "bisection solves)",
            n.load_factor,
            n.fracture,
            n.length,
            n.max_slip,
            n.x,
            n.y,
            self.result.bisections,
        )

    def _nucleation(self, stable: _State, beyond: _State, point, bracket):
        """The fracture whose slip grows fastest at the limit, the length of
        its slipping patch around the point of largest slip, and that point;
        ``stable``, ``beyond``: the states at the two ends of the bracket."""
        c, geo = self.c, self.geometry
        res = stable.res
        before = self._previous_accumulated()
        growth = np.where(self.weak, res.accumulated - before, -np.inf)
        fracture = int(geo.fracture[int(np.argmax(growth))])
        mine = np.nonzero((geo.fracture == fracture) & self.weak)[0]
        mine = mine[np.argsort(geo.s[mine], kind="stable")]
        slipping = res.state[mine] == SLIP
        j = int(np.argmax(np.where(slipping, res.accumulated[mine], -np.inf)))
        stable_length = float(c.weight[mine[_run(slipping, j)]].sum())
        run = _run(beyond.res.state[mine] == SLIP, j)
        unstable_length = float(c.weight[mine[run]].sum())
        # the slopes per unit of potency, whichever the control (the length
        # does not depend on it)
        a = self._control_vector(res, "potency")
        x, y = (float(v) for v in geo.centre[mine[j]])
        return Nucleation(
            load_factor=max(stable.lam, beyond.lam),
            load_factor_stable=stable.lam,
            fracture=fracture,
            length=_zero_slope_length(
                stable_length,
                self._slope(a, self._load_response(stable)),
                unstable_length,
                self._slope(a, self._load_response(beyond)),
            ),
            slipping_length=stable_length,
            x=x,
            y=y,
            max_slip=float(res.accumulated[mine[j]]),
            control=point.control,
            bracket=bracket,
        )

    def _load_response(self, state: _State) -> np.ndarray:
        """x_f = K_t^-1 dR/dlambda at a converged state (kept, or solved)."""
        if state.x_f is None:
            s = self.solver
            q = self._load_derivative(state.res)
            return s.solve_tangent(state.res, q, len(s.completed), 0, 0.0)
        return state.x_f

    def _previous_accumulated(self) -> np.ndarray:
        """Accumulated slip of the step before the last recorded one."""
        done = self.solver.completed
        if len(done) >= 2:
            return done[-2].contact.accumulated
        return np.zeros(self.c.n)

    # ------------------------------------------------------------ bookkeeping
    def _finish_at_max_load(self, u, k):
        """The control step passed max_load before any limit point: a load
        step to max_load from the committed state ends the path."""
        s = self.solver
        u1, res1, its = s.equilibrium(u, self.opt.max_load, k, k)
        self._record(k, self.opt.max_load, u1, res1, its, math.nan)
        logger.info(
            "the path reaches load factor %.6g without a loss of equilibrium",
            self.opt.max_load,
        )

    def _record(self, k, lam, u, res, its, slope):
        """Commit and record a converged state as step k and as a PathPoint."""
        s = self.solver
        s.accept(k, lam, u, res, its)
        weak_slip = self.weak & (res.state == SLIP)
        control = (
            float(self._origin @ u[s.free]) - self.c0 if self.c0 is not None else 0.0
        )
        self.result.path.append(
            PathPoint(
                load_factor=lam,
                control=control,
                slope=slope,
                max_slip=float(np.max(res.accumulated[self.weak], initial=0.0)),
                slipping_length=float(self.c.weight[weak_slip].sum()),
                iterations=its,
                step=k,
            )
        )

    def _error(self, k, it, eta, why, *, retryable=True) -> ConvergenceError:
        kept = len(self.solver.completed)
        return ConvergenceError(
            f"continuation step {k} did not converge: {why}; iteration {it}, "
            f"residual eta = {eta:.3e} (tolerance {self.solver.tol:.1e}); "
            f"{kept} converged step(s) kept",
            step=k,
            iteration=it,
            residual=eta,
            reason=why,
            retryable=retryable,
        )


def _constraint_tolerance(a, u, u0, dc) -> float:
    """Tolerance on the control's residual g = dc - a . (u - u0) (u, u0
    and a on the free dofs): each bordered update satisfies the linear
    constraint exactly, so g is round-off, of the order of the machine
    epsilon times sum |a_i| (|u_i| + |u0_i|) (the whole displacement,
    which can be far larger than a small control step), or a small
    fraction of dc where that is larger."""
    roundoff = 64.0 * np.finfo(float).eps * float(np.abs(a) @ (np.abs(u) + np.abs(u0)))
    return max(1.0e-12 * abs(dc), roundoff)


def _run(mask, j) -> np.ndarray:
    """Indices of the run of consecutive True entries of ``mask`` around
    index j (empty when mask[j] is False)."""
    if not mask[j]:
        return np.zeros(0, np.int64)
    lo = j
    while lo > 0 and mask[lo - 1]:
        lo -= 1
    hi = j
    while hi + 1 < mask.size and mask[hi + 1]:
        hi += 1
    return np.arange(lo, hi + 1)


def _zero_slope_length(stable, slope, unstable, slope_beyond) -> float:
    """The slipping length [m] at which the path's slope vanishes,
    interpolated linearly between the last stable slipping set (length
    ``stable``, slope > 0) and the first unstable one (``unstable``, slope
    ``slope_beyond`` <= 0).

    A discrete slipping patch grows by whole contact patches, and while its
    set of slipping patches stays the same the problem is linear: the path
    is piecewise linear in the control, its slope that of the frozen set.
    With the set frozen at length L, the slope is positive while the
    weakening zone is stable and changes sign where the lowest eigenvalue of
    its stiffness (elasticity less the weakening, the eigenproblem of
    Uenishi & Rice 2003) passes zero, at L = 2 a_c; near there it is
    proportional to that eigenvalue, linear in L.  The whole-patch lengths
    bracket 2 a_c by one or two patches; the zero of the slope places it
    inside the bracket.  ``stable`` when the upper state does not bracket a
    sign change (slope_beyond > 0, or no longer set).
    """
    if not (slope_beyond < 0.0 < slope and unstable > stable):
        return stable
    return stable + (unstable - stable) * slope / (slope - slope_beyond)
