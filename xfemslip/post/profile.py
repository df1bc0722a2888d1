"""Profiles along the fractures: what a fault carries, point by point.

Per converged load step, fracture and contact point (sorted by arc length):
where it is (s, x, y and the depth below the case's datum), the slip that
slid, the shear and effective normal tractions, the fluid pressure, the
Coulomb utilisation |p_T| / (c + f max(0, -p_N')) (1 where the point slips
or is open; :func:`xfemslip.post.fields.coulomb_utilisation`) and its change
from the step before (from the in-situ state for the first), and the rock
units on its two faces.  Everything is read from the result
(:class:`~xfemslip.post.result.Result`: its steps and
``fracture_properties``), so a written ``result.h5`` gives the same table.
``profile.csv`` of a run holds it; ``xfemslip plot --figure profile`` draws
it.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from xfemslip.post.result import Result

__all__ = ["PROFILE_COLUMNS", "depth_datum", "face_units", "profile_rows"]

PROFILE_COLUMNS = (
    "step",
    "load_factor",
    "fracture",
    "s_m",
    "x_m",
    "y_m",
    "depth_m",
    "slip_m",
    "shear_traction_Pa",
    "effective_normal_traction_Pa",
    "fluid_pressure_Pa",
    "utilisation",
    "utilisation_change",
    "state",
    "unit_plus",
    "unit_minus",
)


def depth_datum(result: Result) -> float | None:
    """The y [m] of zero depth the case gives (``depth_datum`` attribute),
    or None."""
    value = result.attrs.get("depth_datum")
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def face_units(prop, s: np.ndarray) -> tuple[list[str], list[str]]:
    """The units on the + and - faces at arc lengths ``s`` (K,) of a fracture
    whose properties ``prop`` (FractureProperties) carry its breaks; empty
    names without them."""
    if prop is None or prop.breaks is None or not prop.units_plus:
        return [""] * len(s), [""] * len(s)
    k = np.searchsorted(np.asarray(prop.breaks, float), s)
    return [prop.units_plus[i] for i in k], [prop.units_minus[i] for i in k]


def _cell(value) -> str | float | int:
    """A CSV cell: numbers as they are, NaN and None empty."""
    if value is None:
        return ""
    if isinstance(value, float) and not math.isfinite(value):
        return ""
    return value


def profile_rows(result: Result) -> Iterator[tuple]:
    """The rows of PROFILE_COLUMNS for every step, fracture and point."""
    datum = depth_datum(result)
    props = result.fracture_properties or []
    before: dict[int, np.ndarray] = {}
    for step in result.steps:
        for i, ff in enumerate(step.fractures):
            prop = props[i] if i < len(props) else None
            use = ff.utilisation
            if i in before:
                previous = before[i]
            elif prop is not None and prop.in_situ_utilisation is not None:
                previous = prop.in_situ_utilisation
            else:
                previous = None
            change = (
                use - previous
                if use is not None and previous is not None
                else np.full(ff.s.size, np.nan)
            )
            if use is not None:
                before[i] = use
            normal = (
                ff.effective_normal_traction
                if ff.effective_normal_traction is not None
                else ff.normal_traction
            )
            plus, minus = face_units(prop, ff.s)
            for k in range(ff.s.size):
                x, y = (float(v) for v in ff.points[k])
                yield (
                    step.step,
                    float(step.load_factor),
                    i,
                    float(ff.s[k]),
                    x,
                    y,
                    _cell(None if datum is None else datum - y),
                    float(ff.slid[k]),
                    float(ff.shear_traction[k]),
                    float(normal[k]),
                    _cell(
                        None
                        if ff.fluid_pressure is None
                        else float(ff.fluid_pressure[k])
                    ),
                    _cell(None if use is None else float(use[k])),
                    _cell(float(change[k])),
                    int(ff.state[k]),
                    plus[k],
                    minus[k],
                )
