"""How big an event the slip is: per fracture and load step, and in words.

Per fracture and converged load step, from the slip that slid up to that step
(``plastic_slip``: cumulative from the in-situ state, the elastic give of the
penalty left out, so a stuck fracture has none): the seismic moment per unit
out-of-plane length M0' = int mu |d| ds, the crack-model static stress drop,
the max |d|, the slipping length and the moment magnitude
Mw = (2/3) (log10(M0' W) - 9.1) for an out-of-plane extent W
(:mod:`xfemslip.post.seismic`).  W is ``events.extent`` when the case gives it,
else the fracture's own slipping length; every magnitude is printed with the
W it used.

Everything comes from what the result stores: the slip and state of every
step, and per fracture (``Result.fracture_properties``) the shear modulus and
Poisson's ratio at each contact point and the ends of the fracture inside the
domain.  The integrals weigh each contact point with the stretch of fracture
it stands for (:func:`xfemslip.post.metrics.point_stretches`), like the sweep
metrics.

A run keeps them (:func:`event_table`, ``Result.events``, the ``/events``
group of ``result.h5``), and :func:`event_sizes` reads them from there.  A
result written by an older version lacks some of it: without
``plastic_slip`` its slip is the tangential jump (stuck points' elastic give
included), without the fracture properties there is no moment (mu unknown)
and the ends are estimated from the contact points; :func:`event_inputs`
says so in its ``note``, which the printouts show.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from xfemslip import display
from xfemslip.case.specs import CaseSpec
from xfemslip.conventions import SLIP
from xfemslip.post.metrics import point_stretches
from xfemslip.post.result import EventTable, Result
from xfemslip.post.seismic import moment_magnitude, moment_per_length, stress_drop

__all__ = [
    "CASE_COLUMNS",
    "FRACTURE_COLUMNS",
    "MAX_FRACTURE_COLUMNS",
    "EventInputs",
    "FractureEvent",
    "event_inputs",
    "event_sizes",
    "event_table",
    "fracture_metrics",
    "increment_line",
    "summary_lines",
]


@dataclass(frozen=True)
class FractureEvent:
    """The event size of one fracture at one load step (SI units)."""

    fracture: int  # case-file index
    slipped: bool  # a contact point in state SLIP at this step
    max_slip: float  # max |slip that slid| [m]
    slipping_length: float  # [m]
    moment_per_length: float  # M0' [N m / m]; NaN: mu unknown
    stress_drop: float  # moment-equivalent crack drop [Pa]; NaN: undefined
    extent: float  # the W of the magnitude [m] (0 without slip and extent)
    magnitude: float  # Mw for M0' W; -inf without moment
    # of this step alone: the slip it added (d_k - d_k-1, d_0 = 0 in situ)
    max_slip_increment: float = 0.0  # max |dd| [m]
    moment_per_length_increment: float = 0.0  # int mu |dd| ds [N m / m]

    @property
    def moment(self) -> float:
        """M0 = M0' W [N m]."""
        return self.moment_per_length * self.extent

    @property
    def magnitude_increment(self) -> float:
        """Mw of this step's slip alone, for the same W; -inf without."""
        return moment_magnitude(self.moment_per_length_increment * self.extent)


@dataclass(frozen=True)
class EventInputs:
    """What the event sizes need beyond the slip and state of the steps.

    Per fracture ``mu`` and ``nu`` at its contact points ((K,) arrays [Pa],
    [-]; NaN when the result does not store them), ``ends`` the arc-length
    range [m] of the fracture inside the domain; ``model`` the elastic model
    (plane strain or stress), ``extent`` W [m] or None (each fracture's
    slipping length), ``note`` what the numbers lack ("" when nothing).
    """

    mu: tuple[np.ndarray, ...]
    nu: tuple[np.ndarray, ...]
    model: str
    ends: tuple[tuple[float, float], ...]
    extent: float | None
    note: str = ""


def _contact_ends(s: np.ndarray) -> tuple[float, float]:
    """The ends of a fracture estimated from its contact points alone: half a
    spacing beyond the first and the last."""
    if s.size < 2:
        return (float(s[0]), float(s[0])) if s.size else (0.0, 0.0)
    return float(s[0] - 0.5 * (s[1] - s[0])), float(s[-1] + 0.5 * (s[-1] - s[-2]))


def _stored(result: Result) -> bool:
    """Whether the result keeps its event sizes for every step."""
    return result.events is not None and result.events.max_slip.shape[0] == len(
        result.steps
    )


# What a result written by an older version lacks, in words.
NO_PLASTIC_SLIP = (
    "this result has no plastic_slip (written by an older version): its slip, "
    "M0' and Mw count the tangential jump, the elastic give of stuck points "
    "included; run the case again for the slip that slid"
)
NO_PROPERTIES = (
    "this result has no shear modulus of its fractures (written by an older "
    "version): no moment, stress drop or Mw; fracture ends estimated from the "
    "contact points"
)


def event_inputs(result: Result, spec: CaseSpec | None = None) -> EventInputs:
    """The :class:`EventInputs` of ``result``, from what it stores; W is
    ``events.extent`` of ``spec`` (the case it ran) when given, else the one
    its ``/events`` recorded, else each fracture's slipping length."""
    fields = result.steps[-1].fractures if result.steps else []
    extent = None
    if spec is not None:
        extent = spec.events.extent if spec.events is not None else None
    elif result.events is not None and result.events.extent_given:
        extent = (
            float(result.events.extent.flat[0]) if result.events.extent.size else None
        )
    notes = []
    if any(ff.plastic_slip is None for step in result.steps for ff in step.fractures):
        notes.append(NO_PLASTIC_SLIP)
    props = result.fracture_properties
    if props is not None and len(props) == len(fields):
        mu = tuple(np.asarray(p.shear_modulus, float) for p in props)
        nu = tuple(np.asarray(p.poisson_ratio, float) for p in props)
        ends = tuple(p.ends for p in props)
    else:
        mu = tuple(np.full(np.shape(ff.s), np.nan) for ff in fields)
        nu = mu
        ends = tuple(_contact_ends(np.asarray(ff.s, float)) for ff in fields)
        if not _stored(result):
            notes.append(NO_PROPERTIES)
    model = str(result.attrs.get("material_model", "plane_strain"))
    return EventInputs(mu, nu, model, ends, extent, "; ".join(notes))


def _fracture_event(index, ff, inputs: EventInputs, before=None) -> FractureEvent:
    """``before``: the fracture's slid slip at the step before (None: in situ)."""
    s, slid, state = np.asarray(ff.s, float), np.asarray(ff.slid, float), ff.state
    step_slip = slid - (np.asarray(before, float) if before is not None else 0.0)
    stretch = point_stretches(s, *inputs.ends[index])
    mu, nu = inputs.mu[index], inputs.nu[index]
    m0 = moment_per_length(mu, stretch, slid)
    length = float(np.sum(stretch[np.asarray(state) == SLIP]))
    extent = inputs.extent if inputs.extent is not None else length
    return FractureEvent(
        fracture=index,
        slipped=bool(np.any(np.asarray(state) == SLIP)),
        max_slip=float(np.max(np.abs(slid))) if slid.size else 0.0,
        slipping_length=length,
        moment_per_length=m0,
        stress_drop=stress_drop(mu, nu, inputs.model, stretch, slid, length),
        extent=extent,
        magnitude=moment_magnitude(m0 * extent),
        max_slip_increment=float(np.max(np.abs(step_slip))) if slid.size else 0.0,
        moment_per_length_increment=moment_per_length(mu, stretch, step_slip),
    )


def _computed(result: Result, inputs: EventInputs) -> list[list[FractureEvent]]:
    out, before = [], None
    for step in result.steps:
        out.append(
            [
                _fracture_event(i, ff, inputs, before[i].slid if before else None)
                for i, ff in enumerate(step.fractures)
            ]
        )
        before = step.fractures
    return out


def _from_table(table: EventTable) -> list[list[FractureEvent]]:
    steps, n = table.max_slip.shape
    out = []
    for k in range(steps):
        row = []
        for i in range(n):
            m0, w = float(table.moment_per_length[k, i]), float(table.extent[k, i])
            row.append(
                FractureEvent(
                    fracture=i,
                    slipped=bool(table.slipped[k, i]),
                    max_slip=float(table.max_slip[k, i]),
                    slipping_length=float(table.slipping_length[k, i]),
                    moment_per_length=m0,
                    stress_drop=float(table.stress_drop[k, i]),
                    extent=w,
                    magnitude=moment_magnitude(m0 * w),
                    max_slip_increment=float(table.max_slip_increment[k, i]),
                    moment_per_length_increment=float(
                        table.moment_per_length_increment[k, i]
                    ),
                )
            )
        out.append(row)
    return out


def event_sizes(result: Result, inputs: EventInputs) -> list[list[FractureEvent]]:
    """Per converged load step, the :class:`FractureEvent` of every fracture:
    those the result keeps (``result.events``) when it has them, else
    computed from its fields."""
    if result.events is not None and _stored(result):
        return _from_table(result.events)
    return _computed(result, inputs)


def event_table(result: Result, inputs: EventInputs) -> EventTable | None:
    """The :class:`~xfemslip.post.result.EventTable` of ``result``'s steps
    (None without a converged step)."""
    if not result.steps:
        return None
    sizes = _computed(result, inputs)
    n = len(result.steps[0].fractures)

    def column(name, dtype=float):
        return np.array(
            [[getattr(e, name) for e in row] for row in sizes], dtype=dtype
        ).reshape(len(sizes), n)

    return EventTable(
        slipped=column("slipped", bool),
        max_slip=column("max_slip"),
        slipping_length=column("slipping_length"),
        moment_per_length=column("moment_per_length"),
        stress_drop=column("stress_drop"),
        extent=column("extent"),
        extent_given=inputs.extent is not None,
        max_slip_increment=column("max_slip_increment"),
        moment_per_length_increment=column("moment_per_length_increment"),
    )


# --------------------------------------------------------------------------- #
# In words

MOMENT_HEAD = "M0' [N m/m]"
W_SOURCE = {True: "events.extent", False: "the slipping length"}
# --------------------------------------------------------------------------- #


def _w_text(event: FractureEvent, inputs: EventInputs) -> str:
    return f"W = {event.extent:.3g} m ({W_SOURCE[inputs.extent is not None]})"


def _mw_text(event: FractureEvent) -> str:
    return f"{event.magnitude:.2f}" if math.isfinite(event.magnitude) else "-"


def summary_lines(
    events: list[FractureEvent], inputs: EventInputs, also: str = ""
) -> list[str]:
    """The per-fracture table of one step and the "what happened" line
    (``also`` appended to it after a semicolon, e.g. the permeability)."""
    if not events:
        return ["no fracture in this result"]
    head = [
        "fracture",
        "slipped",
        "max slip [mm]",
        "slipping [m]",
        MOMENT_HEAD,
        "drop [MPa]",
        "Mw",
        f"W [m] ({W_SOURCE[inputs.extent is not None]})",
    ]
    rows = []
    for e in events:
        drop = f"{e.stress_drop / 1e6:.3g}" if math.isfinite(e.stress_drop) else "-"
        m0 = e.moment_per_length
        moment = f"{m0:.4g}" if math.isfinite(m0) else "-"
        # W only beside a magnitude
        w = f"{e.extent:.3g}" if math.isfinite(e.magnitude) else "-"
        rows.append(
            [
                str(e.fracture),
                "yes" if e.slipped else "no",
                f"{e.max_slip * 1e3:.4g}",
                f"{e.slipping_length:.4g}",
                moment,
                drop,
                _mw_text(e),
                w,
            ]
        )
    lines = display.table(head, rows, left=(7,)).splitlines()
    lines.append(what_happened(events, inputs) + (f"; {also}" if also else ""))
    if inputs.note:
        lines.append(f"note: {inputs.note}")
    return lines


def increment_line(events: list[FractureEvent], inputs: EventInputs) -> str:
    """One line: the slip this step added on each fracture that slips in it
    (max, M0' and Mw of the increment, same W as the step's table)."""
    parts = [
        f"fracture {e.fracture} +{e.max_slip_increment * 1e3:.3g} mm, "
        f"M0' +{e.moment_per_length_increment:.4g} N m/m, "
        f"Mw {_mw(e.magnitude_increment)}"
        for e in events
        if e.slipped
    ]
    if not parts:
        return "this step alone: no fracture slips"
    return "this step alone: " + "; ".join(parts)


def _mw(value: float) -> str:
    return f"{value:.2f}" if math.isfinite(value) else "-"


def what_happened(events: list[FractureEvent], inputs: EventInputs) -> str:
    """One line: how many fractures slipped, the largest slip and magnitude."""
    slipped = [e for e in events if e.slipped]
    n = len(events)
    if not slipped:
        top = max(events, key=lambda e: e.max_slip)
        if top.max_slip > 0.0:  # it slid at an earlier step and stuck again
            return (
                f"no fracture slips at this step ({n} in all); fracture "
                f"{top.fracture} slid {top.max_slip * 1e3:.3g} mm before"
            )
        return f"no fracture slipped ({n} in all)"
    top = max(slipped, key=lambda e: e.max_slip)
    big = max(slipped, key=lambda e: e.moment if math.isfinite(e.moment) else -1.0)
    noun = "fracture" if n == 1 else "fractures"
    line = (
        f"{len(slipped)} of {n} {noun} slipped; max slip {top.max_slip * 1e3:.3g} mm "
        f"on fracture {top.fracture} over {top.slipping_length:.3g} m; "
        f"Mw {_mw_text(big)} for {_w_text(big, inputs)}"
    )
    if big.fracture != top.fracture:
        line += f" on fracture {big.fracture}"
    return line


# --------------------------------------------------------------------------- #
# Sweep columns

# per fracture i, up to MAX_FRACTURE_COLUMNS fractures: fracture<i>_<name>
FRACTURE_COLUMNS = (
    "slipped",
    "max_slip_m",
    "slip_length_m",
    "moment_per_length_Nm_per_m",
    "Mw",
)
MAX_FRACTURE_COLUMNS = 10
# per case: the largest magnitude, the W it used, the block's permeability
# ratios (k over in situ, with [permeability])
CASE_COLUMNS = ("max_Mw", "Mw_extent", "k_xx_ratio", "k_yy_ratio")


def _number(value: float):
    """A finite float, or "" (no magnitude, no in-situ value)."""
    return float(value) if math.isfinite(value) else ""


def fracture_metrics(result: Result, spec: CaseSpec) -> dict:
    """The sweep columns of the final step of ``result`` (the case ``spec``):
    CASE_COLUMNS, and FRACTURE_COLUMNS of each fracture when there are at
    most MAX_FRACTURE_COLUMNS of them (a network's realizations have their
    own summary, :mod:`xfemslip.studies.dfn_summary`)."""
    if not result.steps:
        return {}
    inputs = event_inputs(result, spec)
    events = event_sizes(result, inputs)[-1]
    magnitudes = [e.magnitude for e in events if math.isfinite(e.magnitude)]
    out = {
        "max_Mw": max(magnitudes) if magnitudes else "",
        "Mw_extent": f"{inputs.extent:g} m" if inputs.extent else "slipping length",
        "k_xx_ratio": "",
        "k_yy_ratio": "",
    }
    if result.permeability is not None:
        rx, ry = result.permeability.ratio()
        out["k_xx_ratio"], out["k_yy_ratio"] = _number(rx), _number(ry)
    if len(events) <= MAX_FRACTURE_COLUMNS:
        for e in events:
            values = (
                e.slipped,
                e.max_slip,
                e.slipping_length,
                e.moment_per_length,
                _number(e.magnitude),
            )
            for name, value in zip(FRACTURE_COLUMNS, values, strict=True):
                out[f"fracture{e.fracture}_{name}"] = value
    return out
