"""``[pore_pressure]`` and ``[reservoir]`` -> ``PorePressureSpec``, ``ReservoirSpec``.

Both tables are optional; a case without them runs exactly as before.
"""

from __future__ import annotations

import numpy as np

from xfemslip.case.specs import PorePressureSpec, ReservoirSpec
from xfemslip.case.tables import (
    BIOT,
    COORDINATE,
    POISSON,
    POSITIVE,
    Table,
    check_number,
    frozen,
    show,
)
from xfemslip.geometry.regions import in_boxes, in_polygon, polygon_problem

PORE_PRESSURE_KEYS = ("initial", "change", "biot", "region")
PORE_PRESSURE_REGIONS = ("all", "reservoir")
RESERVOIR_KEYS = ("box", "boxes", "polygon", "E", "nu")


def read_pore_pressure(root: Table) -> PorePressureSpec | None:
    """[pore_pressure]: initial, change [Pa], biot in (0, 1], region."""
    table = root.table("pore_pressure", PORE_PRESSURE_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    initial = table.number("initial")
    change = table.number("change")
    biot = table.number("biot", 1.0, BIOT)
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
                f"expected an array [x0, y0, x1, y1] of 4 numbers, got {show(value)}",
            )
        )
        return None
    items = [
        check_number(v, f"{key}[{i}]", problems, COORDINATE)
        for i, v in enumerate(value)
    ]
    if any(v is None for v in items):
        return None
    x0, y0, x1, y1 = items
    if not (x0 < x1 and y0 < y1):
        problems.append(
            (key, f"must satisfy x0 < x1 and y0 < y1, got {[x0, y0, x1, y1]}")
        )
        return None
    return tuple(items)


def _read_polygon(table: Table) -> list | None:
    """``polygon = [[x, y], ...]``: at least 3 vertices of a simple polygon [m]."""
    key = table.key("polygon")
    value = table.data["polygon"]
    if not isinstance(value, list) or len(value) < 3:
        table.error(
            "polygon",
            f"expected an array of at least 3 vertices [[x, y], ...], got "
            f"{show(value)}",
        )
        return None
    vertices = []
    for i, v in enumerate(value):
        if not isinstance(v, list) or len(v) != 2:
            table.problems.append(
                (
                    f"{key}[{i}]",
                    f"expected a vertex [x, y] of 2 numbers, got {show(v)}",
                )
            )
            return None
        xy = [
            check_number(c, f"{key}[{i}][{j}]", table.problems, COORDINATE)
            for j, c in enumerate(v)
        ]
        if any(c is None for c in xy):
            return None
        vertices.append(xy)
    why = polygon_problem(np.array(vertices))
    if why is not None:
        table.error("polygon", why)
        return None
    return vertices


def _read_boxes(table: Table) -> list | None:
    """``box = [..]`` or ``boxes = [[..], ..]`` (one of them, or a polygon)."""
    if table.has("box") == table.has("boxes"):
        table.error(
            None,
            "give exactly one of box = [x0, y0, x1, y1], boxes = [[x0, y0, x1, "
            "y1], ...] or polygon = [[x, y], ...]",
        )
        return None
    if table.has("box"):
        box = _check_box(table.data["box"], table.key("box"), table.problems)
        return None if box is None else [box]
    value = table.data["boxes"]
    if not isinstance(value, list) or not value:
        table.error("boxes", f"expected a non-empty array of boxes, got {show(value)}")
        return None
    boxes = [
        _check_box(v, f"{table.key('boxes')}[{i}]", table.problems)
        for i, v in enumerate(value)
    ]
    return None if any(b is None for b in boxes) else boxes


def read_reservoir(root: Table, grid) -> ReservoirSpec | None:
    """[reservoir]: boxes or a polygon, and the reservoir's E [Pa] and nu [-]."""
    table = root.table("reservoir", RESERVOIR_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    polygon = None
    if table.has("polygon"):
        if table.has("box") or table.has("boxes"):
            table.error(
                None,
                "give exactly one of box = [x0, y0, x1, y1], boxes = [[x0, y0, "
                "x1, y1], ...] or polygon = [[x, y], ...]",
            )
        else:
            polygon = _read_polygon(table)
        boxes = None if polygon is None else []
    else:
        boxes = _read_boxes(table)
    E = table.number("E", rule=POSITIVE)
    nu = table.number("nu", rule=POISSON)
    if boxes is not None and grid is not None:
        x, y = grid.mesh.x, grid.mesh.y
        cx, cy = np.meshgrid(0.5 * (x[1:] + x[:-1]), 0.5 * (y[1:] + y[:-1]))
        centres = np.column_stack([cx.ravel(), cy.ravel()])
        if polygon is not None:
            inside = in_polygon(centres, np.array(polygon))
        else:
            inside = in_boxes(centres, np.array(boxes).reshape(-1, 4))
        if not np.any(inside):
            key = (
                "polygon"
                if polygon is not None
                else "box"
                if table.has("box")
                else "boxes"
            )
            table.error(
                key,
                "contains no element centre of the mesh (a cell belongs to the "
                "reservoir when its centre lies inside)",
            )
    if len(table.problems) > start:
        return None
    return ReservoirSpec(
        boxes=frozen(np.array(boxes, float).reshape(-1, 4)),
        E=E,
        nu=nu,
        polygon=None if polygon is None else frozen(polygon),
    )
