"""``[pore_pressure]`` and ``[reservoir]`` -> ``PorePressureSpec``, ``ReservoirSpec``.

Private helper of :mod:`xfemslip.case`, which stays the ONLY entry point for
validating user input (house style: case.py is the only place user input is
validated); import the public names from ``xfemslip.case``, not from here.

Both tables are optional; a case without them runs exactly as before.
"""

from __future__ import annotations

import numpy as np

from xfemslip.case_specs import PorePressureSpec, ReservoirSpec
from xfemslip.case_tables import (
    _POSITIVE,
    Range,
    _check_number,
    _frozen,
    _show,
    _Table,
)

PORE_PRESSURE_KEYS = ("initial", "change", "biot", "region")
PORE_PRESSURE_REGIONS = ("all", "reservoir")
RESERVOIR_KEYS = ("box", "boxes", "E", "nu")


def _read_pore_pressure(root: _Table) -> PorePressureSpec | None:
    """[pore_pressure]: initial, change [Pa], biot in (0, 1], region."""
    table = root.table("pore_pressure", PORE_PRESSURE_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    initial = table.number("initial")
    change = table.number("change")
    biot = table.number("biot", 1.0, Range(0.0, 1.0, lo_open=True))
    region = table.choice("region", PORE_PRESSURE_REGIONS, "all")
    if region == "reservoir" and not root.has("reservoir"):
        table.error(
            "region",
            'is "reservoir" but the case has no [reservoir] table (give '
            '[reservoir] box = [x0, y0, x1, y1], or region = "all")',
        )
    loading = root.data.get("loading")
    has_initial = isinstance(loading, dict) and "initial_stress" in loading
    if initial not in (None, 0.0) and not has_initial:
        table.error(
            "initial",
            f"= {initial!r} needs loading.initial_stress (the in-situ total "
            "stress the initial pore pressure is in equilibrium with)",
        )
    if len(table.problems) > start:
        return None
    return PorePressureSpec(initial=initial, change=change, biot=biot, region=region)


def _check_box(value, key: str, problems: list) -> tuple | None:
    """[x0, y0, x1, y1] with x0 < x1 and y0 < y1 [m]."""
    if not isinstance(value, list) or len(value) != 4:
        problems.append(
            (
                key,
                f"expected an array [x0, y0, x1, y1] of 4 numbers, got {_show(value)}",
            )
        )
        return None
    items = [_check_number(v, f"{key}[{i}]", problems) for i, v in enumerate(value)]
    if any(v is None for v in items):
        return None
    x0, y0, x1, y1 = items
    if not (x0 < x1 and y0 < y1):
        problems.append(
            (key, f"must satisfy x0 < x1 and y0 < y1, got {[x0, y0, x1, y1]}")
        )
        return None
    return tuple(items)


def _read_boxes(table: _Table) -> list | None:
    """``box = [..]`` or ``boxes = [[..], ..]`` (exactly one of them)."""
    if table.has("box") == table.has("boxes"):
        table.error(
            None,
            "give exactly one of box = [x0, y0, x1, y1] or boxes = [[x0, y0, x1, "
            "y1], ...]",
        )
        return None
    if table.has("box"):
        box = _check_box(table.data["box"], table.key("box"), table.problems)
        return None if box is None else [box]
    value = table.data["boxes"]
    if not isinstance(value, list) or not value:
        table.error("boxes", f"expected a non-empty array of boxes, got {_show(value)}")
        return None
    boxes = [
        _check_box(v, f"{table.key('boxes')}[{i}]", table.problems)
        for i, v in enumerate(value)
    ]
    return None if any(b is None for b in boxes) else boxes


def _read_reservoir(root: _Table, grid) -> ReservoirSpec | None:
    """[reservoir]: boxes and the reservoir's E [Pa] and nu [-]."""
    table = root.table("reservoir", RESERVOIR_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    boxes = _read_boxes(table)
    E = table.number("E", rule=_POSITIVE)
    nu = table.number("nu", rule=Range(0.0, 0.5, hi_open=True))
    if boxes is not None and grid is not None:
        x, y = grid.mesh.x, grid.mesh.y
        cx, cy = 0.5 * (x[1:] + x[:-1]), 0.5 * (y[1:] + y[:-1])
        if not any(
            np.any((cx > b[0]) & (cx < b[2])) and np.any((cy > b[1]) & (cy < b[3]))
            for b in boxes
        ):
            key = "box" if table.has("box") else "boxes"
            table.error(
                key,
                "contains no element centre of the mesh (a cell belongs to the "
                "reservoir when its centre lies inside a box)",
            )
    if len(table.problems) > start:
        return None
    return ReservoirSpec(boxes=_frozen(boxes), E=E, nu=nu)
