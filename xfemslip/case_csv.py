"""Boundary CSV files (``{ file = "edge.csv" }``): read the rows, check that the
points lie on the edge, interpolate the values to the edge's nodes.

Private helper of :mod:`xfemslip.case`, which stays the ONLY entry point for
validating user input (house style: case.py is the only place user input is
validated); import the public names from ``xfemslip.case``, not from here.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np

from xfemslip.case_files import MAX_CSV_BYTES, UnreadableInput, read_input
from xfemslip.case_grid import _Grid
from xfemslip.case_specs import EdgeSpec
from xfemslip.case_tables import _exact, _frozen, _Table

CSV_HEADER = ("x", "y", "ux", "uy")
# CSV points count as on an edge / at its ends within this fraction of the
# largest domain size (rounding of coordinates printed by another program).
CSV_TOLERANCE = 1e-9
# At most this many row problems are listed per CSV file (then a count).
MAX_CSV_PROBLEMS = 10


class _EdgeFrame(NamedTuple):
    """Where an edge is: coordinate axis along it, fixed coordinate across it."""

    along: int  # 0: the edge runs along x (bottom, top); 1: along y
    at: float  # the fixed coordinate (y of bottom/top, x of left/right) [m]
    nodes: np.ndarray  # node coordinates along the edge, increasing [m]


def _edge_frame(edge: str, grid: _Grid) -> _EdgeFrame:
    """Geometry of one edge of the rectilinear mesh."""
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
        return f"expected 4 values x,y,ux,uy, got {len(fields)}: {_quote(line)}"
    row = []
    for name, text in zip(CSV_HEADER, fields, strict=True):
        try:
            value = float(text)
        except ValueError:
            return f"{name} is not a number: {_quote(text)}"
        if not math.isfinite(value):
            return f"{name} must be finite, got {_quote(text)}"
        row.append(value)
    return row


def _csv_lines(file: Path, key: str, problems: list) -> list[str] | None:
    """The lines of a CSV input file (read with the MAX_CSV_BYTES cap), or
    None after recording why it cannot be read."""
    try:
        return read_input(file, MAX_CSV_BYTES).splitlines()
    except UnreadableInput as exc:
        problems.append((key, f"cannot read {file}: {exc}"))
        return None


def _quote(text: str, limit: int = 60) -> str:
    """``repr`` of a CSV line or field for a message, cut to ``limit`` chars."""
    text = text.strip()
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit]!r}... ({len(text)} characters)"


def _read_csv(file: Path, key: str, problems: list) -> tuple[np.ndarray, list] | None:
    """Rows (m, 4) ``[x, y, ux, uy]`` of a boundary CSV file and their line numbers."""
    lines = _csv_lines(file, key, problems)
    if lines is None:
        return None
    header = tuple(c.strip().lower() for c in lines[0].split(",")) if lines else ()
    if header != CSV_HEADER:
        got = _quote(lines[0]) if lines else "an empty file"
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
    _add_capped(problems, key, bad)
    if bad:
        return None
    return np.array(rows, dtype=np.float64).reshape(-1, 4), numbers


def _add_capped(problems: list, key: str, messages: list[str]) -> None:
    """Record at most MAX_CSV_PROBLEMS messages, then how many were left out."""
    problems.extend((key, m) for m in messages[:MAX_CSV_PROBLEMS])
    if len(messages) > MAX_CSV_PROBLEMS:
        problems.append((key, f"... and {len(messages) - MAX_CSV_PROBLEMS} more rows"))


def _csv_points_on_edge(rows, numbers, frame, edge, file, tol) -> list[str]:
    """Messages for points off the edge's line or beyond its ends."""
    axis = "xy"[frame.along]
    across = "yx"[frame.along]
    lo, hi = float(frame.nodes[0]), float(frame.nodes[-1])
    bad = []
    for (x, y, _, _), number in zip(rows, numbers, strict=True):
        s, t = (x, y) if frame.along == 0 else (y, x)
        where = f"{file} line {number}: point ({_exact(x)}, {_exact(y)})"
        if abs(t - frame.at) > tol:
            bad.append(
                f"{where} is not on the {edge} edge ({across} = {_exact(frame.at)})"
            )
        elif s < lo - tol or s > hi + tol:
            bad.append(
                f"{where} lies beyond the {edge} edge "
                f"({axis} in [{_exact(lo)}, {_exact(hi)}])"
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
            first, second = (", ".join(map(_exact, v)) for v in values[i : i + 2])
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
            f"{file}: points cover {axis} in [{_exact(s[0])}, {_exact(s[-1])}] but "
            f"the {edge} edge spans [{_exact(lo)}, {_exact(hi)}]; the file must "
            "cover the edge end to end"
        )
    return np.column_stack(
        [
            np.interp(frame.nodes, s, values[:, 0]),
            np.interp(frame.nodes, s, values[:, 1]),
        ]
    )


def _edge_from_csv(table: _Table, edge: str, grid: _Grid | None, folder: Path):
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
    _add_capped(table.problems, key, bad)
    if bad:
        return None
    values = _csv_edge_values(rows, numbers, frame, edge, file, tol)
    if isinstance(values, str):
        table.error("file", values)
        return None
    return EdgeSpec(kind="displacement", values=_frozen(values), source=str(file))
