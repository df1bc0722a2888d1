"""Critical depletion: the pore-pressure drop at which each fracture first slips.

``deplete(spec, out_dir)`` runs the case's load steps (the pore-pressure
change of ``[pore_pressure]`` applied in ``loading.steps`` equal steps,
proportionally with any boundary load).  After each converged step, every
fracture that has a contact patch in state SLIP for the first time has its
first slip bracketed by bisection on the load factor between the previous
step (stuck) and this one (slipping), to ``tolerance`` Pa of pore pressure.
Friction is path dependent: every bisection trial restarts from the committed
history of the last converged step below the bracket (the state the solver
keeps for step cutting) and is never committed.

Cross-check (independent of the bisection): while every patch sticks the
response is linear in the load factor, so the tractions of each patch at the
stuck lower bracket and at the initial state give, by linear extrapolation,
the load factor where |p_T| = c - f p_N' is first reached.  It is reported
as ``dp_linear`` beside the bisection result (NaN when another fracture
already slipped below the bracket, which breaks the linearity).

Outputs (in ``out_dir``): ``result.h5`` (and VTU) of the steps as ``run``
writes them, ``critical_depletion.csv``, ``slip_vs_depletion.csv``, and with
``plot=True`` ``slip_vs_depletion.png`` and ``depletion_field.png``
(matplotlib imported only then); all of them one output set, swapped into
``out_dir`` whole (:mod:`xfemslip.io.folder`).
"""

from __future__ import annotations

import csv
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from xfemslip import display
from xfemslip.contact.interface import COMMITTED
from xfemslip.conventions import SLIP
from xfemslip.errors import ConvergenceError, UsageError
from xfemslip.fem.poro import FACE_OFFSET
from xfemslip.io.atomic import atomic_path
from xfemslip.post.metrics import fracture_ends, point_stretches
from xfemslip.post.result import DepletionTable
from xfemslip.simulation import solve_and_write

logger = logging.getLogger(__name__)

# Default bisection tolerance, relative to |pore_pressure.change|.
DEFAULT_REL_TOLERANCE = 1.0e-3
# The smallest meaningful tolerance, relative to |pore_pressure.change|: a
# converged state at load factor lambda satisfies its equilibrium only to
# solver.tolerance times the applied load, so whether a patch slips is decided
# to about that fraction of the change; RESOLUTION_FLOOR stands for round-off
# when the solver tolerance is set very small (the load factor itself resolves
# 2.2e-16).  A smaller --tolerance is raised to this with a warning.
RESOLUTION_FLOOR = 1.0e-12
# Hard cap on the bisection solves of one fracture: a bracket of one load step
# reaches the smallest tolerance above in at most log2(1 / 1e-12) = 40 halvings.
MAX_BISECTIONS = 60


@dataclass
class FractureOnset:
    """First slip of one fracture (NaN fields when it never slips)."""

    fracture: int  # case-file index
    dp_lower: float = np.nan  # pore-pressure change, last stuck state [Pa]
    dp_upper: float = np.nan  # first slipping state [Pa]
    x: float = np.nan  # first slipping patch (centre) [m]
    y: float = np.nan
    dp_linear: float = np.nan  # linear-response extrapolation [Pa]
    trials: int = 0  # bisection solves
    # the first slipping patch holds or touches a singular point of the model
    # (singular_points): its onset depends on the mesh
    at_singularity: bool = False
    singularity: str = ""  # which ("" when not)
    # the pore-pressure change at which the slipping length first reaches
    # the patch length asked for (bisected like the first slip) [Pa]
    dp_patch: float = np.nan
    # with a slip-weakening friction: where quasi-static equilibrium is lost
    # on this fracture (the nucleation of a seismic event), NaN when not
    dp_seismic: float = np.nan  # [Pa]
    nucleation_length: float = np.nan  # the slipping patch 2a then [m]
    x_nucleation: float = np.nan  # the point of largest slip [m]
    y_nucleation: float = np.nan

    @property
    def dp_critical(self) -> float:
        """Midpoint of the bracket [Pa]."""
        return 0.5 * (self.dp_lower + self.dp_upper)


@dataclass
class DepletionReport:
    onsets: list
    rows: list = field(default_factory=list)  # slip vs depletion table rows
    tolerance: float = 0.0  # [Pa]
    patch_length: float | None = None  # [m] (--patch-length)
    out_dir: Path | None = None
    wall_time_s: float = 0.0
    written: list = field(default_factory=list)


def _history(contact):
    """Copy of the committed friction history of a contact set."""
    return contact.history()


def _restore(contact, history) -> None:
    contact.restore(history)


def _slipping(contact, res, fi) -> np.ndarray:
    """Patches of fracture fi in state SLIP."""
    return (contact.fracture == fi) & (res.state == SLIP)


def slipping_length(contact, res, fi) -> float:
    """Length [m] of fracture fi whose patches slip."""
    return float(contact.weight[_slipping(contact, res, fi)].sum())


def singular_points(model, fi, others_slip=False) -> list[tuple[float, str]]:
    """(arc length [m], what) of the points of fracture fi where the stress
    that brings it to slip is singular: where the rock or the pressure change
    on one of its faces changes along it (a reservoir corner on a fault,
    model.breaks: the stuck state's tractions are log-singular there), and,
    once another fracture slips (``others_slip``), its junctions.  Its own
    tips are not: while it sticks, a fracture carries the stress as the
    intact rock did, and a tip is singular only once slip ends there."""
    fr = model.fractures[fi]
    out = []
    if others_slip:
        out += [(float(s), "a junction") for s in fr.junction_s]
    breaks = model.breaks[fi] if model.breaks is not None else ()
    out += [(float(s), "a reservoir corner") for s in breaks if _corner(model, fr, s)]
    return out


def _corner(model, fr, s) -> bool:
    """Whether the rock boundary meeting fracture ``fr`` at arc length s ends
    there (a corner of a unit on the fracture: the faces' rocks change
    differently), rather than running on through it (a horizon crossing the
    fracture, with the same rock on both faces before and after: its
    tractions stay bounded)."""
    zones = model.materials.zones
    eps = FACE_OFFSET * model.mesh.h_min
    ds = max(eps, 1e-6 * float(model.contact.weight.max(initial=1.0)))
    xy, normal = fr.point_at(np.array([s - ds, s + ds]))
    plus = zones.at(xy + eps * normal)
    minus = zones.at(xy - eps * normal)
    through = plus[0] == minus[0] and plus[1] == minus[1]
    return not through


def at_singularity(model, fi, patch, others_slip=False) -> str:
    """What singular point of fracture fi (:func:`singular_points`) the
    contact patch ``patch`` holds or lies next to (within its own length
    along the fracture), or ""."""
    ip, c = model.ip, model.contact
    s = ip.s[c.patch == patch]
    lo, hi = float(s.min()), float(s.max())
    reach = float(c.weight[patch])
    near = [
        (min(abs(p - lo), abs(p - hi)) if not lo <= p <= hi else 0.0, what)
        for p, what in singular_points(model, fi, others_slip)
    ]
    near = [(d, what) for d, what in near if d <= reach]
    return min(near)[1] if near else ""


def _patch_centres(model) -> np.ndarray:
    """(m, 2) weighted centre of every contact patch [m]."""
    c, ip = model.contact, model.ip
    W = np.bincount(c.patch, weights=ip.weight, minlength=c.n)
    return np.column_stack(
        [
            np.bincount(c.patch, weights=ip.weight * ip.xy[:, k], minlength=c.n) / W
            for k in range(2)
        ]
    )


def _linear_onset(contact, fi, pn0, pt0, lam_lo, pn_lo, pt_lo) -> float:
    """Load factor where the linear (all-stuck) response first meets Coulomb.

    Per patch p_N(l) = pn0 + l/l_lo (pn_lo - pn0), likewise p_T; the bound
    |p_T| = c - f p_N is met on the + branch at
    l = (c - f pn0 - pt0) / (dpt + f dpn) and on the - branch at
    l = (c - f pn0 + pt0) / (f dpn - dpt) (per unit l); smallest positive.
    """
    if lam_lo <= 0.0:
        return np.nan
    m = contact.fracture == fi
    f, c = contact.friction[m], contact.cohesion[m]
    dpn = (pn_lo[m] - pn0[m]) / lam_lo
    dpt = (pt_lo[m] - pt0[m]) / lam_lo
    with np.errstate(divide="ignore", invalid="ignore"):
        plus = (c - f * pn0[m] - pt0[m]) / (dpt + f * dpn)
        minus = (c - f * pn0[m] + pt0[m]) / (f * dpn - dpt)
    cand = np.concatenate([plus, minus])
    cand = cand[np.isfinite(cand) & (cand > 0.0)]
    return float(cand.min()) if cand.size else np.nan


def _table_rows(result, change, n) -> list:
    """Slip vs depletion rows: step, load factor, dp, per fracture the max
    slip and the slipping length of its event sizes (``result.events``,
    :mod:`xfemslip.post.events`: the slip that slid, the elastic give of stuck
    points left out), and per fracture the mean slip over its slipping
    length, from the in-situ state (step 0) on; n fractures."""
    rows = [(0, 0.0, 0.0, [(0.0, 0.0)] * n, [0.0] * n)]
    events = result.events
    ends = fracture_ends(result, None)
    for k, step in enumerate(result.steps):
        per = [
            (float(events.max_slip[k, i]), float(events.slipping_length[k, i]))
            for i in range(n)
        ]
        means = [_mean_slip(ff, ends[i]) for i, ff in enumerate(step.fractures)]
        rows.append(
            (step.step, step.load_factor, step.load_factor * change, per, means)
        )
    return rows


def _mean_slip(ff, ends) -> float:
    """Mean |slip that slid| [m] over the points in slip (0 without)."""
    w = point_stretches(ff.s, *ends)
    slipping = np.asarray(ff.state) == SLIP
    length = float(w[slipping].sum())
    if length == 0.0:
        return 0.0
    return float(np.sum(w[slipping] * np.abs(ff.slid[slipping])) / length)


def critical_depletion(solver, model, steps, tolerance, onsets=None, patch_length=None):
    """Run the steps with bisection of every fracture's first slip (and,
    with ``patch_length`` [m], of the change at which its slipping length
    first reaches it).

    Returns (onsets, results).  ``tolerance`` [Pa] is the final bracket width
    in pore pressure.  ``onsets``: a list to fill with one FractureOnset per
    fracture (a new one when None); after a ConvergenceError it holds the
    onsets found before.
    """
    if onsets is None:
        onsets = []
    onsets[:] = [FractureOnset(fracture=fr.index) for fr in model.fractures]
    try:
        _step_and_bisect(solver, model, steps, tolerance, onsets, patch_length)
    finally:
        _drop_nonlinear(onsets)
    return onsets, solver.completed


def _step_and_bisect(solver, model, steps, tolerance, onsets, patch_length) -> None:
    """The loop of critical_depletion: fills ``onsets`` in place."""
    change = model.pore.change
    contact = model.contact
    n_frac = len(model.fractures)
    found = [False] * n_frac
    grown = [patch_length is None] * n_frac
    centres = _patch_centres(model)
    pn0, pt0 = contact.pn0.copy(), contact.pt_committed.copy()
    for fi in range(n_frac):
        found[fi] = _slips_in_situ(solver.in_situ, model, onsets[fi], fi, centres)
    u = np.zeros(model.problem.n_dofs)
    lam0 = 0.0
    prev_res = None
    for k in range(1, steps + 1):
        lam1 = k / steps
        before = _history(contact)
        u_before = u.copy()
        u = solver._advance(u, lam0, lam1, k, steps)
        res = solver.completed[-1].contact
        after = _history(contact)
        bracket = _Bracket(before, u_before, lam0, lam1, k, steps, prev_res)
        for fi in range(n_frac):
            if not found[fi] and _slipping(contact, res, fi).any():
                found[fi] = True
                others = any(found[j] for j in range(n_frac) if j != fi)
                lo_res = _first_slip(
                    solver, model, onsets[fi], fi, bracket, tolerance, centres, others
                )
                lam_lo = onsets[fi].dp_lower / change if change else 0.0
                pn_lo, pt_lo = (
                    (
                        contact.pn0.copy(),
                        bracket.history[COMMITTED.index("pt_committed")].copy(),
                    )
                    if lo_res is None
                    else (lo_res.pn, lo_res.pt)
                )
                onsets[fi].dp_linear = change * _linear_onset(
                    contact, fi, pn0, pt0, lam_lo, pn_lo, pt_lo
                )
            if not grown[fi] and slipping_length(contact, res, fi) >= patch_length:
                grown[fi] = True
                lo, hi, *_ = _bisect(
                    solver,
                    contact,
                    bracket,
                    tolerance / abs(change),
                    lambda r, fi=fi: slipping_length(contact, r, fi) >= patch_length,
                    change,
                    (
                        f"fracture {onsets[fi].fracture} slips over {patch_length:g} m",
                        "not yet",
                    ),
                )
                onsets[fi].dp_patch = 0.5 * (lo + hi) * change
                logger.info(
                    "fracture %d: slipping over %.4g m from dp = %.6g Pa",
                    onsets[fi].fracture,
                    patch_length,
                    onsets[fi].dp_patch,
                )
        _restore(contact, after)
        prev_res = res
        lam0 = lam1


def weakening_path(solver, model, onsets, patch_length=None):
    """Deplete a case with a slip-weakening friction: follow the equilibrium
    path (xfemslip.solve.continuation, its states the steps written) to the
    loss of equilibrium or the end of the change, and read the first slip,
    the patch length and the seismic onset of every fracture off it.

    A load-stepped bisection cannot pass the limit point where the slip
    turns seismic (there is no equilibrium beyond it); the path follows the
    slip instead.  The first slip is bracketed by the path's states (the
    approach to it steps just past the predicted first slip), the patch
    length by the first state that reaches it.  A path that fails is a
    ConvergenceError, the converged states kept: never a wrong onset."""
    from xfemslip.contact.interface import patch_geometry
    from xfemslip.solve.continuation import ContinuationOptions, follow_to_nucleation

    change = model.pore.change
    onsets[:] = [FractureOnset(fracture=fr.index) for fr in model.fractures]
    ids = [fr.index for fr in model.fractures]
    steps = model.spec.loading.steps
    options = ContinuationOptions(max_load=1.0, load_step=1.0 / steps)
    path = follow_to_nucleation(
        solver, patch_geometry(model.contact, model.ip, ids), options
    )
    contact, centres = model.contact, _patch_centres(model)
    previous = 0.0
    for r in solver.completed:
        lam, res = r.load_factor, r.contact
        for fi, onset in enumerate(onsets):
            slipping = _slipping(contact, res, fi)
            if np.isnan(onset.dp_upper) and slipping.any():
                onset.dp_lower, onset.dp_upper = previous * change, lam * change
                first = np.nonzero(slipping)[0]
                bound = (
                    contact.cohesion[first] - contact.friction[first] * res.pn[first]
                )
                util = np.abs(res.pt[first]) / np.where(bound > 0.0, bound, np.inf)
                j = first[np.argmax(util)]
                onset.x, onset.y = (float(v) for v in centres[j])
                others = any(np.isfinite(o.dp_upper) and o is not onset for o in onsets)
                _note_singularity(model, onset, fi, j, others)
            if (
                patch_length is not None
                and np.isnan(onset.dp_patch)
                and slipping_length(contact, res, fi) >= patch_length
            ):
                onset.dp_patch = lam * change
        previous = lam
    n = path.nucleation
    if n is not None:
        fi = ids.index(n.fracture)
        onsets[fi].dp_seismic = n.load_factor * change
        onsets[fi].nucleation_length = n.length
        onsets[fi].x_nucleation, onsets[fi].y_nucleation = n.x, n.y
        logger.info(
            "fracture %d: quasi-static equilibrium is lost at dp = %.6g Pa (the "
            "slip turns seismic): slipping patch %.4g m, largest slip at "
            "(%.4g, %.4g)",
            n.fracture,
            onsets[fi].dp_seismic,
            n.length,
            n.x,
            n.y,
        )
    return onsets, solver.completed


def _note_singularity(model, onset, fi, patch, others_slip=False) -> None:
    """Record and say whether the first slip sits at a singular point."""
    what = at_singularity(model, fi, patch, others_slip)
    onset.at_singularity, onset.singularity = bool(what), what
    if what:
        logger.info(
            "fracture %d: the first slip sits at %s, where the stress of the "
            "model is singular: its depletion depends on the mesh (it falls as "
            "the mesh is refined); the growth of the slipping patch converges "
            "(--patch-length)",
            onset.fracture,
            what,
        )


def _slips_in_situ(zero, model, onset, fi, centres) -> bool:
    """A fracture whose in-situ shear is already above the friction limit
    slips at dp = 0 (the first load step releases the excess: see
    ContactSet.in_situ_force); its onset is the initial state, found without
    bisection, at the patch with the largest excess.  Returns whether it does."""
    contact = model.contact
    over = np.nonzero(_slipping(contact, zero, fi))[0]
    if over.size == 0:
        return False
    excess = np.abs(contact.kt[over] * contact.slip_committed[over]) - np.abs(
        zero.pt[over]
    )
    onset.dp_lower = onset.dp_upper = onset.dp_linear = 0.0
    j = over[np.argmax(excess)]
    onset.x, onset.y = (float(v) for v in centres[j])
    logger.info(
        "fracture %d: slips in situ, before any depletion (its initial shear "
        "traction is above the friction limit on %d patch(es))",
        onset.fracture,
        over.size,
    )
    _note_singularity(model, onset, fi, j)
    return True


def _drop_nonlinear(onsets) -> None:
    """The linear extrapolation holds only while everything sticks: NaN for a
    fracture whose stuck lower bracket lies beyond another fracture's onset."""
    for b in onsets:
        if any(
            a is not b and abs(a.dp_upper) <= abs(b.dp_lower)
            for a in onsets
            if np.isfinite(a.dp_upper)
        ):
            b.dp_linear = np.nan


@dataclass
class _Bracket:
    """A load step whose end state slips: where to restart the bisection."""

    history: tuple  # committed friction history at lam0
    u: np.ndarray  # displacement at lam0
    lam0: float
    lam1: float
    step: int
    steps: int
    res0: object  # contact result at lam0 (None at the initial state)


def _trial(solver, contact, bracket, lam):
    """Contact result at load factor lam from the bracket's committed state.

    One Newton solve from lam0 (nothing committed); if it fails, the
    solver's step cutting from lam0 to lam (its sub-steps commit, so the
    history is restored afterwards and the step it records is dropped).
    """
    _restore(contact, bracket.history)
    try:
        return solver._newton(bracket.u, lam, bracket.step, bracket.steps)[1]
    except ConvergenceError:
        logger.debug("bisection trial at load factor %.6g: cutting the step", lam)
        _restore(contact, bracket.history)
        solver._advance(bracket.u, bracket.lam0, lam, bracket.step, bracket.steps)
        return solver.completed.pop().contact


def _bisect(solver, contact, bracket, width, happened, change=None, said=("yes", "no")):
    """(lo, hi, lo_res, hi_res, trials): the load factors between which
    ``happened(contact result)`` first holds in the bracket's step, to
    ``width`` in load factor (lo_res None at the initial state); each trial
    is one log line, at the pore-pressure change lam * ``change`` [Pa] when
    given, saying ``said[0]`` when it happened and ``said[1]`` when not."""
    lo, hi = bracket.lam0, bracket.lam1
    hi_res = solver.completed[-1].contact
    lo_res = bracket.res0
    trials = 0
    while hi - lo > width:
        mid = 0.5 * (lo + hi)
        if trials >= MAX_BISECTIONS or not lo < mid < hi:
            logger.warning(
                "bisection stopped after %d solves with the bracket %.3g of the "
                "load wide (the load factor cannot be split further)",
                trials,
                hi - lo,
            )
            break
        res = _trial(solver, contact, bracket, mid)
        trials += 1
        where = (
            f"dp = {display.pressure_change(mid * change)}"
            if change is not None
            else f"load factor {mid:.6g}"
        )
        logger.info(
            "step %d/%d: bisection trial %d at %s: %s",
            bracket.step,
            bracket.steps,
            trials,
            where,
            said[0] if happened(res) else said[1],
        )
        if happened(res):
            hi, hi_res = mid, res
        else:
            lo, lo_res = mid, res
    return lo, hi, lo_res, hi_res, trials


def _first_slip(solver, model, onset, fi, bracket, tolerance, centres, others):
    """Bracket the first slip of fracture fi in (lam0, lam1] (module doc);
    returns the contact result at the stuck lower bracket (None: in situ)."""
    contact = model.contact
    change = model.pore.change
    lo, hi, lo_res, hi_res, trials = _bisect(
        solver,
        contact,
        bracket,
        tolerance / abs(change),
        lambda r: _slipping(contact, r, fi).any(),
        change,
        (f"fracture {onset.fracture} slips", "stuck"),
    )
    onset.trials += trials
    onset.dp_lower, onset.dp_upper = lo * change, hi * change
    first = np.nonzero(_slipping(contact, hi_res, fi))[0]
    # the patch with the largest utilisation |p_T| / (c - f p_N) at hi
    bound = contact.cohesion[first] - contact.friction[first] * hi_res.pn[first]
    util = np.abs(hi_res.pt[first]) / np.where(bound > 0.0, bound, np.inf)
    j = first[np.argmax(util)] if first.size else 0
    onset.x, onset.y = (float(v) for v in centres[j])
    logger.info(
        "fracture %d: first slip between dp = %s and %s at (%.4g, %.4g) "
        "(%d bisection solves)",
        onset.fracture,
        display.pressure_change(onset.dp_lower),
        display.pressure_change(onset.dp_upper),
        onset.x,
        onset.y,
        onset.trials,
    )
    _note_singularity(model, onset, fi, j, others)
    return lo_res


def resolved_tolerance(spec, tolerance=None) -> float:
    """Bisection tolerance [Pa] for a case: the default, or the one asked for,
    raised with a warning to the smallest the load steps resolve
    (RESOLUTION_FLOOR)."""
    change = abs(spec.pore_pressure.change)
    if tolerance is None:
        return DEFAULT_REL_TOLERANCE * change
    if not tolerance > 0.0:
        raise UsageError(f"--tolerance must be > 0 Pa, got {tolerance!r}")
    smallest = change * max(spec.solver.tolerance, RESOLUTION_FLOOR)
    if tolerance < smallest:
        logger.warning(
            "--tolerance %.3g Pa is below what the load steps resolve "
            "(|pore_pressure.change| x solver.tolerance = %.3g Pa); using %.3g Pa",
            tolerance,
            smallest,
            smallest,
        )
        return smallest
    return tolerance


def deplete(
    spec,
    out_dir=None,
    *,
    tolerance=None,
    plot=False,
    overwrite=False,
    patch_length=None,
):
    """Critical depletion of every fracture of a case; writes the outputs.

    tolerance : bisection bracket width in pore pressure [Pa]; default
    DEFAULT_REL_TOLERANCE * |pore_pressure.change|.
    patch_length : [m] also bisect the change at which each fracture's
    slipping length first reaches it (converges under mesh refinement where
    the first slip does not).
    Raises UsageError when the case has no [pore_pressure] or no fracture.
    """
    start = time.perf_counter()
    if spec.pore_pressure is None:
        raise UsageError(
            f"{spec.path}: xfemslip deplete needs a [pore_pressure] table "
            "(initial, change)"
        )
    if not spec.fractures:
        raise UsageError(f"{spec.path}: xfemslip deplete needs at least one fracture")
    change = spec.pore_pressure.change
    if change is None:
        raise UsageError(
            f"{spec.path}: pore_pressure.field: xfemslip deplete scales one "
            "pore-pressure change from 0 to find the first slip; a change from a "
            "file is followed by xfemslip run, one load step per field or more"
        )
    if change == 0.0:
        raise UsageError(
            f"{spec.path}: pore_pressure.change = 0: xfemslip deplete needs a "
            "non-zero pore-pressure change to search for the first slip"
        )
    if patch_length is not None and not patch_length > 0.0:
        raise UsageError(f"--patch-length must be > 0 m, got {patch_length!r}")
    tolerance = resolved_tolerance(spec, tolerance)
    report = DepletionReport(onsets=[], tolerance=tolerance, patch_length=patch_length)

    def annotate(result, model) -> None:
        result.depletion = depletion_table(report)

    def finish(done, folder: Path) -> None:
        """The tables and figures, into the output set before it is swapped in."""
        # a failed step keeps what converged, as `run` does
        report.rows = _table_rows(done.result, change, len(done.model.fractures))
        report.out_dir = done.out_dir
        names = write_tables(report, folder)
        if plot:
            from xfemslip.plot.depletion import plot_field, plot_slip_vs_depletion

            names.append(plot_slip_vs_depletion(report, folder, name=spec.name))
            if done.results:
                names.append(plot_field(done.model, done.results[-1], folder))
        report.written = [done.out_dir / Path(name).name for name in names]

    done = solve_and_write(
        spec,
        out_dir,
        overwrite,
        (
            (
                lambda solver, model: weakening_path(
                    solver, model, report.onsets, patch_length
                )
            )
            if any(f.weakening is not None for f in spec.fractures)
            else (
                lambda solver, model: critical_depletion(
                    solver,
                    model,
                    spec.loading.steps,
                    tolerance,
                    report.onsets,
                    patch_length,
                )
            )
        ),
        finish,
        # the series' time is the size of the pore-pressure change reached
        # [Pa]: increasing over the steps, whichever its sign
        step_time=lambda load_factor: abs(load_factor * change),
        annotate=annotate,
    )
    report.wall_time_s = time.perf_counter() - start
    if done.failure is not None:
        raise done.failure
    return report


def depletion_table(report: DepletionReport) -> DepletionTable:
    """What the report found, as result.h5 keeps it (``/depletion``)."""
    o = report.onsets

    def col(name):
        return np.array([getattr(a, name) for a in o], float)

    return DepletionTable(
        dp_lower=col("dp_lower"),
        dp_upper=col("dp_upper"),
        x=col("x"),
        y=col("y"),
        at_singularity=np.array([a.at_singularity for a in o], bool),
        singularity=tuple(a.singularity for a in o),
        dp_patch=col("dp_patch"),
        dp_seismic=col("dp_seismic"),
        nucleation_length=col("nucleation_length"),
        x_nucleation=col("x_nucleation"),
        y_nucleation=col("y_nucleation"),
        patch_length=np.nan if report.patch_length is None else report.patch_length,
        tolerance=report.tolerance,
    )


def write_tables(report: DepletionReport, out_dir: Path) -> list:
    """critical_depletion.csv and slip_vs_depletion.csv; returns their paths."""
    crit = out_dir / "critical_depletion.csv"
    with atomic_path(crit) as tmp, tmp.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(
            [
                "fracture",
                "dp_critical_Pa",
                "dp_lower_Pa",
                "dp_upper_Pa",
                "tolerance_Pa",
                "x_first_slip_m",
                "y_first_slip_m",
                "dp_linear_Pa",
                "first_slip_at_singularity",
                "singularity",
                "patch_length_m",
                "dp_patch_length_Pa",
                "dp_seismic_Pa",
                "nucleation_length_m",
                "x_nucleation_m",
                "y_nucleation_m",
            ]
        )
        length = report.patch_length if report.patch_length is not None else np.nan
        for o in report.onsets:
            w.writerow(
                [
                    o.fracture,
                    f"{o.dp_critical:.9g}",
                    f"{o.dp_lower:.9g}",
                    f"{o.dp_upper:.9g}",
                    f"{report.tolerance:.6g}",
                    f"{o.x:.6g}",
                    f"{o.y:.6g}",
                    f"{o.dp_linear:.9g}",
                    "true" if o.at_singularity else "false",
                    o.singularity,
                    f"{length:.6g}",
                    f"{o.dp_patch:.9g}",
                    f"{o.dp_seismic:.9g}",
                    f"{o.nucleation_length:.6g}",
                    f"{o.x_nucleation:.6g}",
                    f"{o.y_nucleation:.6g}",
                ]
            )
    table = out_dir / "slip_vs_depletion.csv"
    with atomic_path(table) as tmp, tmp.open("w", newline="") as fh:
        w = csv.writer(fh)
        n = len(report.onsets)
        head = ["step", "load_factor", "dp_Pa"]
        for i in range(n):
            head += [f"max_abs_slip_{i}_m", f"slip_length_{i}_m"]
        head += [f"mean_slip_{i}_m" for i in range(n)]
        w.writerow(head)
        for step, lam, dp, per, means in report.rows:
            row = [step, f"{lam:.9g}", f"{dp:.9g}"]
            for s, length in per:
                row += [f"{s:.9g}", f"{length:.9g}"]
            row += [f"{m:.9g}" for m in means]
            w.writerow(row)
    return [crit, table]


def depletion_lines(table: DepletionTable, compression_positive=False) -> list[str]:
    """What ``deplete`` found, in words, from what result.h5 keeps
    (``/depletion``): per fracture its first slip, whether it sits at a
    singular point (then mesh-dependent), and the change at which the
    slipping patch reached the asked length."""
    cp = compression_positive
    name = display.change_label(cp)

    def change(dp: float) -> str:
        return display.pressure_change(dp, cp)

    lines = [
        f"critical depletion (bisection to {display.pressure(table.tolerance)}; "
        f"{name} {'> 0: a drop' if cp else '< 0: a depletion'}):"
    ]
    for i, dp in enumerate(table.dp_critical):
        if not np.isfinite(dp):
            lines.append(f"  fracture {i}: does not slip")
            continue
        text = (
            f"  fracture {i}: first slip at {name} = {change(dp)} at "
            f"({display.number(table.x[i], 4)}, {display.number(table.y[i], 4)}) m"
        )
        if table.at_singularity[i]:
            text += (
                f", at {table.singularity[i]} where the stress is singular "
                "(mesh-dependent)"
            )
        lines.append(text)
        if np.isfinite(table.dp_seismic[i]):
            lines.append(
                f"    the slip turns seismic at {name} = {change(table.dp_seismic[i])} "
                f"(nucleation length {display.length(table.nucleation_length[i])})"
            )
        if np.isfinite(table.patch_length):
            reached = table.dp_patch[i]
            lines.append(
                f"    slipping over {display.length(table.patch_length)} "
                + (
                    f"from {name} = {change(reached)}"
                    if np.isfinite(reached)
                    else "not reached"
                )
            )
    return lines


def format_report(report: DepletionReport, compression_positive=False) -> str:
    """The two tables as text, for the CLI, in MPa, m and mm
    (:mod:`xfemslip.display`)."""
    cp = compression_positive
    name = display.change_label(cp)

    def mpa(dp: float) -> str:
        return display.number(display.megapascals(dp, cp))

    rows, notes = [], []
    for o in report.onsets:
        if np.isnan(o.dp_upper):
            rows.append([str(o.fracture), "no slip", "", "", ""])
            continue
        lo, hi = sorted((mpa(o.dp_lower), mpa(o.dp_upper)), key=float)
        rows.append(
            [
                str(o.fracture),
                mpa(o.dp_critical),
                f"[{lo}, {hi}]",
                f"({display.number(o.x, 4)}, {display.number(o.y, 4)})",
                mpa(o.dp_linear),
            ]
        )
        if o.at_singularity:
            notes.append(
                f"fracture {o.fracture}: first slip at {o.singularity}, where the "
                "stress is singular: this depletion depends on the mesh"
            )
        if np.isfinite(o.dp_seismic):
            notes.append(
                f"fracture {o.fracture}: the slip turns seismic at {name} = "
                f"{display.pressure_change(o.dp_seismic, cp)}: nucleation length "
                f"{display.length(o.nucleation_length)} at "
                f"({display.number(o.x_nucleation, 4)}, "
                f"{display.number(o.y_nucleation, 4)})"
            )
    sense = "a drop > 0" if cp else "< 0 = depletion"
    lines = [
        display.convention(cp),
        f"critical depletion (pore-pressure change at first slip; {sense}), "
        f"bisection tolerance {display.pressure(report.tolerance)}:",
        display.table(
            [
                "fracture",
                f"{name}_critical [MPa]",
                "bracket [MPa]",
                "first slip at (x, y) [m]",
                f"{name}_linear [MPa]",
            ],
            rows,
        ),
        *notes,
    ]
    if report.patch_length is not None:
        lines.append(
            f"slipping over {display.length(report.patch_length)} (converges with "
            "the mesh): "
            + ", ".join(
                f"fracture {o.fracture} "
                + (
                    f"at {name} = {display.pressure_change(o.dp_patch, cp)}"
                    if np.isfinite(o.dp_patch)
                    else "not reached"
                )
                for o in report.onsets
            )
        )
    lines.append(
        "slip vs depletion (max |slip| that slid [mm] / slipping length [m] per "
        "fracture):"
    )
    n = len(report.onsets)
    lines.append(
        display.table(
            ["step", f"{name} [MPa]", *(f"frac {i}" for i in range(n))],
            [
                [
                    str(step),
                    display.number(display.megapascals(dp, cp), 5),
                    *(
                        f"{display.number(s * 1e3, 4)} / {display.number(length, 4)}"
                        for s, length in per
                    ),
                ]
                for step, _lam, dp, per, _means in report.rows
            ],
        )
    )
    return "\n".join(lines)
