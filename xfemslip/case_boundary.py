"""``[boundary]`` -> ``BoundarySpec``: one ``EdgeSpec`` per edge, from a word
(``"traction"``, ``"free"``), a table of components or a CSV file
(``case_csv.py``).

Private helper of :mod:`xfemslip.case`, which stays the ONLY entry point for
validating user input (house style: case.py is the only place user input is
validated); import the public names from ``xfemslip.case``, not from here.
"""

from __future__ import annotations

import difflib
from pathlib import Path

import numpy as np

from xfemslip.case_csv import _edge_frame, _edge_from_csv
from xfemslip.case_grid import _Grid
from xfemslip.case_specs import EDGES, BoundarySpec, EdgeSpec
from xfemslip.case_tables import _frozen, _show, _Table

EDGE_KEYS = ("ux", "uy", "traction", "file")
EDGE_WORDS = ("traction", "free")


def _edge_from_table(table: _Table, edge: str, grid: _Grid | None):
    """``{ ux = .., uy = .., traction = .. }``: prescribed components."""
    start = len(table.problems)
    ux, uy = table.number("ux", None), table.number("uy", None)
    traction = table.boolean("traction", False)
    given = [c for c in ("ux", "uy") if table.has(c)]
    if not given:
        table.error(
            None,
            'prescribes nothing: give ux and/or uy, or file = "..."; '
            'for no constraint write "free" or "traction"',
        )
        return None
    if traction and len(given) == 2:
        table.error(
            "traction",
            "traction = true needs a free component, but ux and uy are both prescribed",
        )
        return None
    if len(table.problems) > start or grid is None:
        return None
    values = np.full((_edge_frame(edge, grid).nodes.size, 2), np.nan)  # NaN: free
    for component, value in enumerate((ux, uy)):
        if value is not None:
            values[:, component] = value
    return EdgeSpec(
        kind="displacement", values=_frozen(values), traction=traction, source="table"
    )


def _read_edge(boundary: _Table, edge: str, grid: _Grid | None, folder: Path):
    """One edge entry -> EdgeSpec (None after recording a problem)."""
    if not boundary.has(edge):
        return EdgeSpec(kind="free", source="default")
    value = boundary.data[edge]
    if isinstance(value, str) and value in EDGE_WORDS:
        return EdgeSpec(kind=value)
    if not isinstance(value, dict):
        close = (
            difflib.get_close_matches(value, EDGE_WORDS, n=1)
            if isinstance(value, str)
            else []
        )
        hint = f"; did you mean {close[0]!r}?" if close else ""
        boundary.error(
            edge,
            f'must be "traction", "free", a table such as '
            f'{{ ux = 0.0, uy = 0.0 }} or {{ file = "{edge}.csv" }}, '
            f"got {_show(value)}{hint}",
        )
        return None
    table = boundary.table(edge, EDGE_KEYS)
    if table.has("file"):
        return _edge_from_csv(table, edge, grid, folder)
    return _edge_from_table(table, edge, grid)


def _read_boundary(root: _Table, grid: _Grid | None, folder: Path):
    """[boundary] -> (BoundarySpec or None, edges that need loading.stress)."""
    table = root.table("boundary", EDGES, required=True)
    if table is None:
        return None, []
    edges = {edge: _read_edge(table, edge, grid, folder) for edge in EDGES}
    needs_stress = [
        e
        for e in EDGES
        if edges[e] is not None and (edges[e].kind == "traction" or edges[e].traction)
    ]
    if any(spec is None for spec in edges.values()):
        return None, needs_stress
    if not any(spec.kind == "displacement" for spec in edges.values()):
        table.error(
            None,
            "no displacement is prescribed on any edge: the body can move "
            "freely; prescribe at least one component (e.g. bottom = "
            "{ uy = 0.0 })",
        )
        return None, needs_stress
    return BoundarySpec(**edges), needs_stress
