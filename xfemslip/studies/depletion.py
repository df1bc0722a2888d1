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

from xfemslip.contact.interface import COMMITTED
from xfemslip.conventions import SLIP
from xfemslip.errors import ConvergenceError, UsageError
from xfemslip.io.atomic import atomic_path
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

    @property
    def dp_critical(self) -> float:
        """Midpoint of the bracket [Pa]."""
        return 0.5 * (self.dp_lower + self.dp_upper)


@dataclass
class DepletionReport:
    onsets: list
    rows: list = field(default_factory=list)  # slip vs depletion table rows
    tolerance: float = 0.0  # [Pa]
    out_dir: Path | None = None
    wall_time_s: float = 0.0
    written: list = field(default_factory=list)


def _history(contact):
    """Copy of the committed friction history of a contact set."""
    return tuple(getattr(contact, name).copy() for name in COMMITTED)


def _restore(contact, history) -> None:
    for name, value in zip(COMMITTED, history, strict=True):
        setattr(contact, name, value.copy())


def _slipping(contact, res, fi) -> np.ndarray:
    """Patches of fracture fi in state SLIP."""
    return (contact.fracture == fi) & (res.state == SLIP)


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
    """Slip vs depletion rows: step, load factor, dp, and per fracture the max
    slip and the slipping length of its event sizes (``result.events``,
    :mod:`xfemslip.post.events`: the slip that slid, the elastic give of stuck
    points left out), from the in-situ state (step 0) on; n fractures."""
    rows = [(0, 0.0, 0.0, [(0.0, 0.0)] * n)]
    events = result.events
    for k, step in enumerate(result.steps):
        per = [
            (float(events.max_slip[k, i]), float(events.slipping_length[k, i]))
            for i in range(n)
        ]
        rows.append((step.step, step.load_factor, step.load_factor * change, per))
    return rows


def critical_depletion(solver, model, steps, tolerance, onsets=None):
    """Run the steps with bisection of every fracture's first slip.

    Returns (onsets, results).  ``tolerance`` [Pa] is the final bracket width
    in pore pressure.  ``onsets``: a list to fill with one FractureOnset per
    fracture (a new one when None); after a ConvergenceError it holds the
    onsets found before.
    """
    if onsets is None:
        onsets = []
    onsets[:] = [FractureOnset(fracture=fr.index) for fr in model.fractures]
    try:
        _step_and_bisect(solver, model, steps, tolerance, onsets)
    finally:
        _drop_nonlinear(onsets)
    return onsets, solver.completed


def _step_and_bisect(solver, model, steps, tolerance, onsets) -> None:
    """The loop of critical_depletion: fills ``onsets`` in place."""
    change = model.pore.change
    contact = model.contact
    n_frac = len(model.fractures)
    found = [False] * n_frac
    centres = _patch_centres(model)
    pn0, pt0 = contact.pn0.copy(), contact.pt_committed.copy()
    for fi in range(n_frac):
        found[fi] = _slips_in_situ(solver.in_situ, contact, onsets[fi], fi, centres)
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
        new = [
            fi
            for fi in range(n_frac)
            if not found[fi] and _slipping(contact, res, fi).any()
        ]
        for fi in new:
            found[fi] = True
            bracket = _Bracket(before, u_before, lam0, lam1, k, steps, prev_res)
            pn_lo, pt_lo = _bisect(
                solver, contact, onsets[fi], fi, bracket, tolerance, centres, change
            )
            lam_lo = onsets[fi].dp_lower / change if change else 0.0
            onsets[fi].dp_linear = change * _linear_onset(
                contact, fi, pn0, pt0, lam_lo, pn_lo, pt_lo
            )
        _restore(contact, after)
        prev_res = res
        lam0 = lam1


def _slips_in_situ(zero, contact, onset, fi, centres) -> bool:
    """A fracture whose in-situ shear is already above the friction limit
    slips at dp = 0 (the first load step releases the excess: see
    ContactSet.in_situ_force); its onset is the initial state, found without
    bisection, at the patch with the largest excess.  Returns whether it does."""
    over = np.nonzero(_slipping(contact, zero, fi))[0]
    if over.size == 0:
        return False
    excess = np.abs(contact.kt[over] * contact.slip_committed[over]) - np.abs(
        zero.pt[over]
    )
    onset.dp_lower = onset.dp_upper = onset.dp_linear = 0.0
    onset.x, onset.y = (float(v) for v in centres[over[np.argmax(excess)]])
    logger.info(
        "fracture %d: slips in situ, before any depletion (its initial shear "
        "traction is above the friction limit on %d patch(es))",
        onset.fracture,
        over.size,
    )
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
        logger.info("bisection trial at load factor %.6g: cutting the step", lam)
        _restore(contact, bracket.history)
        solver._advance(bracket.u, bracket.lam0, lam, bracket.step, bracket.steps)
        return solver.completed.pop().contact


def _bisect(solver, contact, onset, fi, bracket, tolerance, centres, change):
    """Bracket the first slip of fracture fi in (lam0, lam1] (see module doc).

    Returns the patch tractions (p_N, p_T) at the stuck lower bracket.
    """
    lo, hi = bracket.lam0, bracket.lam1
    hi_res = solver.completed[-1].contact
    lo_res = bracket.res0
    width = tolerance / abs(change)
    while hi - lo > width:
        mid = 0.5 * (lo + hi)
        if onset.trials >= MAX_BISECTIONS or not lo < mid < hi:
            logger.warning(
                "fracture %d: bisection stopped after %d solves with the bracket "
                "%.3g Pa wide (the load factor cannot be split further)",
                onset.fracture,
                onset.trials,
                (hi - lo) * abs(change),
            )
            break
        res = _trial(solver, contact, bracket, mid)
        onset.trials += 1
        if _slipping(contact, res, fi).any():
            hi, hi_res = mid, res
        else:
            lo, lo_res = mid, res
    onset.dp_lower, onset.dp_upper = lo * change, hi * change
    first = np.nonzero(_slipping(contact, hi_res, fi))[0]
    # the patch with the largest utilisation |p_T| / (c - f p_N) at hi
    bound = contact.cohesion[first] - contact.friction[first] * hi_res.pn[first]
    util = np.abs(hi_res.pt[first]) / np.where(bound > 0.0, bound, np.inf)
    j = first[np.argmax(util)] if first.size else 0
    onset.x, onset.y = (float(v) for v in centres[j])
    logger.info(
        "fracture %d: first slip between dp = %.6g and %.6g Pa at (%.4g, %.4g) "
        "(%d bisection solves)",
        onset.fracture,
        onset.dp_lower,
        onset.dp_upper,
        onset.x,
        onset.y,
        onset.trials,
    )
    if lo_res is None:  # lo = 0: the initial state
        return contact.pn0.copy(), bracket.history[3].copy()
    return lo_res.pn, lo_res.pt


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


def deplete(spec, out_dir=None, *, tolerance=None, plot=False, overwrite=False):
    """Critical depletion of every fracture of a case; writes the outputs.

    tolerance : bisection bracket width in pore pressure [Pa]; default
    DEFAULT_REL_TOLERANCE * |pore_pressure.change|.
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
    tolerance = resolved_tolerance(spec, tolerance)
    report = DepletionReport(onsets=[], tolerance=tolerance)

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
        lambda solver, model: critical_depletion(
            solver, model, spec.loading.steps, tolerance, report.onsets
        ),
        finish,
        # the series' time is the size of the pore-pressure change reached
        # [Pa]: increasing over the steps, whichever its sign
        step_time=lambda load_factor: abs(load_factor * change),
    )
    report.wall_time_s = time.perf_counter() - start
    if done.failure is not None:
        raise done.failure
    return report


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
            ]
        )
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
                ]
            )
    table = out_dir / "slip_vs_depletion.csv"
    with atomic_path(table) as tmp, tmp.open("w", newline="") as fh:
        w = csv.writer(fh)
        n = len(report.onsets)
        head = ["step", "load_factor", "dp_Pa"]
        for i in range(n):
            head += [f"max_abs_slip_{i}_m", f"slip_length_{i}_m"]
        w.writerow(head)
        for step, lam, dp, per in report.rows:
            row = [step, f"{lam:.9g}", f"{dp:.9g}"]
            for s, length in per:
                row += [f"{s:.9g}", f"{length:.9g}"]
            w.writerow(row)
    return [crit, table]


def format_report(report: DepletionReport) -> str:
    """The two tables as text, for the CLI."""
    lines = [
        "critical depletion (pore-pressure change at first slip; < 0 = depletion), "
        f"bisection tolerance {report.tolerance:.4g} Pa:",
        f"{'fracture':>8} {'dp_critical [Pa]':>17} {'bracket [Pa]':>27} "
        f"{'first slip at (x, y) [m]':>26} {'dp_linear [Pa]':>15}",
    ]
    for o in report.onsets:
        if np.isnan(o.dp_upper):
            lines.append(f"{o.fracture:>8} {'no slip':>17}")
            continue
        lines.append(
            f"{o.fracture:>8} {o.dp_critical:>17.6g} "
            f"{f'[{o.dp_lower:.6g}, {o.dp_upper:.6g}]':>27} "
            f"{f'({o.x:.4g}, {o.y:.4g})':>26} {o.dp_linear:>15.6g}"
        )
    lines.append(
        "slip vs depletion (max |slip| that slid [m] / slipping length [m] per "
        "fracture):"
    )
    n = len(report.onsets)
    lines.append(
        f"{'step':>5} {'dp [Pa]':>12} "
        + " ".join(f"{f'frac {i}':>23}" for i in range(n))
    )
    for step, _lam, dp, per in report.rows:
        lines.append(
            f"{step:>5} {dp:>12.5g} "
            + " ".join(f"{s:>11.4g} / {length:>9.4g}" for s, length in per)
        )
    return "\n".join(lines)
