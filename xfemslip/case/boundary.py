"""``[boundary]`` -> ``BoundarySpec``: one ``EdgeSpec`` per edge, from a word
(``"traction"``, ``"free"``), a table of components or a CSV file of
``x,y,ux,uy`` rows (the points must lie on the edge; the values are
interpolated to the edge's nodes).
"""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import NamedTuple

import numpy as np

from xfemslip.case.files import CSV_TOLERANCE, add_capped, csv_lines, quote
from xfemslip.case.grid import Grid
from xfemslip.case.specs import EDGES, BoundarySpec, EdgeSpec
from xfemslip.case.tables import Table, exact, frozen, show

EDGE_KEYS = ("ux", "uy", "traction", "file")
EDGE_WORDS = ("traction", "free")


CSV_HEADER = ("x", "y", "ux", "uy")


class _EdgeFrame(NamedTuple):
    """Where an edge is: coordinate axis along it, fixed coordinate across it."""

    along: int  # 0: the edge runs along x (bottom, top); 1: along y
    at: float  # the fixed coordinate (y of bottom/top, x of left/right) [m]
    nodes: np.ndarray  # node coordinates along the edge, increasing [m]


def _edge_frame(edge: str, grid: Grid) -> _EdgeFrame:
    """Geometry of one edge of the rectilinear mesh."""
    assert grid.mesh is not None  # the edges are read once the mesh is known
    x, y = grid.mesh.x, grid.mesh.y
    return {
        "bottom": _EdgeFrame(0, float(y[0]), x),
        "top": _EdgeFrame(0, float(y[-1]), x),
        "left": _EdgeFrame(1, float(x[0]), y),
        "right": _EdgeFrame(1, float(x[-1]), y),
    }[edge]


def _csv_row(line: str) -> list[float] | str:
    """Four finite numbers of one CSV row, or what is wrong with it."""
    fields = line.split(",")
    if len(fields) != 4:
        return f"expected 4 values x,y,ux,uy, got {len(fields)}: {quote(line)}"
    row = []
    for name, text in zip(CSV_HEADER, fields, strict=True):
        try:
            value = float(text)
        except ValueError:
            return f"{name} is not a number: {quote(text)}"
        if not math.isfinite(value):
            return f"{name} must be finite, got {quote(text)}"
        row.append(value)
    return row


def _read_csv(file: Path, key: str, problems: list) -> tuple[np.ndarray, list] | None:
    """Rows (m, 4) ``[x, y, ux, uy]`` of a boundary CSV file and their line numbers."""
    lines = csv_lines(file, key, problems)
    if lines is None:
        return None
    header = tuple(c.strip().lower() for c in lines[0].split(",")) if lines else ()
    if header != CSV_HEADER:
        got = quote(lines[0]) if lines else "an empty file"
        problems.append((key, f"{file} line 1: header must be x,y,ux,uy, got {got}"))
        return None
    rows, numbers, bad = [], [], []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        row = _csv_row(line)
        if isinstance(row, str):
            bad.append(f"{file} line {number}: {row}")
        else:
            rows.append(row)
            numbers.append(number)
    add_capped(problems, key, bad)
    if bad:
        return None
    return np.array(rows, dtype=np.float64).reshape(-1, 4), numbers


def _csv_points_on_edge(rows, numbers, frame, edge, file, tol) -> list[str]:
    """Messages for points off the edge's line or beyond its ends."""
    axis = "xy"[frame.along]
    across = "yx"[frame.along]
    lo, hi = float(frame.nodes[0]), float(frame.nodes[-1])
    bad = []
    for (x, y, _, _), number in zip(rows, numbers, strict=True):
        s, t = (x, y) if frame.along == 0 else (y, x)
        where = f"{file} line {number}: point ({exact(x)}, {exact(y)})"
        if abs(t - frame.at) > tol:
            bad.append(
                f"{where} is not on the {edge} edge ({across} = {exact(frame.at)})"
            )
        elif s < lo - tol or s > hi + tol:
            bad.append(
                f"{where} lies beyond the {edge} edge "
                f"({axis} in [{exact(lo)}, {exact(hi)}])"
            )
    return bad


def _csv_edge_values(rows, numbers, frame, edge, file, tol) -> np.ndarray | str:
    """Interpolate the CSV values to the edge's nodes, or say what is wrong."""
    s = rows[:, frame.along]
    order = np.argsort(s, kind="stable")
    s, values, numbers = s[order], rows[order, 2:], [numbers[i] for i in order]
    close = np.flatnonzero(np.diff(s) <= tol)
    for i in close:
        if np.any(values[i] != values[i + 1]):
            first, second = (", ".join(map(exact, v)) for v in values[i : i + 2])
            return (
                f"{file} lines {numbers[i]} and {numbers[i + 1]}: the same point "
                f"with different values (ux, uy) = ({first}) and ({second})"
            )
    keep = np.ones(s.size, dtype=bool)
    keep[close + 1] = False
    s, values = s[keep], values[keep]
    if s.size < 2:
        return f"{file}: needs at least 2 distinct points along the edge, got {s.size}"
    lo, hi = float(frame.nodes[0]), float(frame.nodes[-1])
    if s[0] > lo + tol or s[-1] < hi - tol:
        axis = "xy"[frame.along]
        return (
            f"{file}: points cover {axis} in [{exact(s[0])}, {exact(s[-1])}] but "
            f"the {edge} edge spans [{exact(lo)}, {exact(hi)}]; the file must "
            "cover the edge end to end"
        )
    return np.column_stack(
        [
            np.interp(frame.nodes, s, values[:, 0]),
            np.interp(frame.nodes, s, values[:, 1]),
        ]
    )


def _edge_from_csv(table: Table, edge: str, grid: Grid | None, folder: Path):
    """``{ file = "edge.csv" }``: both components at every node, from the file."""
    for other in ("ux", "uy", "traction"):
        if table.has(other):
            table.error(
                other,
                "cannot be combined with file (the file prescribes both components)",
            )
    name = table.string("file")
    if name is None:
        return None
    file = folder / name
    key = table.key("file")
    start = len(table.problems)
    parsed = _read_csv(file, key, table.problems)
    if parsed is None or grid is None or len(table.problems) > start:
        return None
    rows, numbers = parsed
    frame = _edge_frame(edge, grid)
    tol = CSV_TOLERANCE * max(grid.size)
    bad = _csv_points_on_edge(rows, numbers, frame, edge, file, tol)
    add_capped(table.problems, key, bad)
    if bad:
        return None
    values = _csv_edge_values(rows, numbers, frame, edge, file, tol)
    if isinstance(values, str):
        table.error("file", values)
        return None
    return EdgeSpec(kind="displacement", values=frozen(values), source=str(file))


def _edge_from_table(table: Table, edge: str, grid: Grid | None):
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
        kind="displacement", values=frozen(values), traction=traction, source="table"
    )


def _read_edge(boundary: Table, edge: str, grid: Grid | None, folder: Path):
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
            f"got {show(value)}{hint}",
        )
        return None
    table = boundary.table(edge, EDGE_KEYS)
    assert table is not None  # the value is a table (checked above)
    if table.has("file"):
        return _edge_from_csv(table, edge, grid, folder)
    return _edge_from_table(table, edge, grid)


def read_boundary(root: Table, grid: Grid | None, folder: Path):
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
