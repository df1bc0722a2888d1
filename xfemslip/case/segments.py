"""``network.file``: a CSV file of fracture segments -> polylines with their
contact parameters (read by :mod:`xfemslip.case.network`).
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from xfemslip.case.files import (
    CSV_TOLERANCE,
    MAX_CSV_PROBLEMS,
    add_capped,
    csv_lines,
    quote,
)
from xfemslip.case.fractures import segment_meets_box, self_intersection
from xfemslip.case.grid import Grid
from xfemslip.case.tables import (
    COORDINATE,
    NON_NEGATIVE,
    POSITIVE,
    Table,
    exact,
    fmt,
    range_problem,
    suggest,
)

PROPERTY_RULES = {
    "friction": NON_NEGATIVE,
    "cohesion": NON_NEGATIVE,
    "kn": POSITIVE,
    "kt": POSITIVE,
}
SEGMENT_COLUMNS = ("x0", "y0", "x1", "y1")
OPTIONAL_COLUMNS = ("fracture", *PROPERTY_RULES)
MAX_NETWORK_FRACTURES = 5_000  # per source (file rows, generated count)


def _csv_header(line: str | None, file: Path) -> tuple[list[str], list[str]]:
    """(columns, problems) of the header line; a suggestion for the first few
    unknown columns only (a header of a million columns is answered at once)."""
    if line is None:
        return [], [f"{file} line 1: empty file, expected the header x0,y0,x1,y1"]
    columns = [c.strip().lower() for c in line.split(",")]
    allowed = SEGMENT_COLUMNS + OPTIONAL_COLUMNS
    unknown = [c for c in columns if c not in allowed]
    if len(unknown) > MAX_CSV_PROBLEMS:
        first = ", ".join(quote(c) for c in unknown[:3])
        bad = [
            f"{file} line 1: {len(unknown)} unknown columns ({first}, ...); "
            "allowed: " + ", ".join(allowed)
        ]
    else:
        bad = [
            f"{file} line 1: unknown column {quote(c)}{suggest(c, allowed)}"
            for c in unknown
        ]
    counts = Counter(c for c in columns if c in allowed)
    bad += [
        f"{file} line 1: column {c!r} appears twice"
        for c in sorted(c for c, n in counts.items() if n > 1)
    ]
    missing = [c for c in SEGMENT_COLUMNS if c not in columns]
    if missing:
        bad.append(
            f"{file} line 1: missing column(s) {', '.join(missing)}; the header "
            "needs x0,y0,x1,y1 (optional: " + ", ".join(OPTIONAL_COLUMNS) + ")"
        )
    return columns, bad


def _csv_cell(name: str, text: str) -> tuple[object, str | None]:
    """(value, problem) of one cell; empty optional cells are None."""
    text = text.strip()
    if name == "fracture":
        return (text or None), None
    if not text:
        if name in SEGMENT_COLUMNS:
            return None, f"{name} is empty"
        return None, None
    try:
        value = float(text)
    except ValueError:
        return None, f"{name} is not a number: {quote(text)}"
    if not math.isfinite(value):
        return None, f"{name} must be finite, got {quote(text)}"
    rule = COORDINATE if name in SEGMENT_COLUMNS else PROPERTY_RULES.get(name)
    message = range_problem(value, rule, name)
    return value, (f"{name} {message}" if message else None)


def _csv_rows(lines: list[str], columns: list[str], file: Path):
    """[(line number, {column: value})] and problems; blank and # lines skipped."""
    rows, bad = [], []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = line.split(",")
        if len(fields) != len(columns):
            bad.append(
                f"{file} line {number}: expected {len(columns)} values "
                f"({','.join(columns)}), got {len(fields)}: {quote(line)}"
            )
            continue
        row: dict[str, Any] = {}
        problems: list[str] = []
        for name, text in zip(columns, fields, strict=True):
            row[name], problem = _csv_cell(name, text)
            if problem:
                problems.append(problem)
        p0, p1 = (row["x0"], row["y0"]), (row["x1"], row["y1"])
        if not problems and p0 == p1:
            problems.append(
                f"zero-length segment: (x0, y0) = (x1, y1) = "
                f"({exact(p0[0])}, {exact(p0[1])})"
            )
        bad += [f"{file} line {number}: {p}" for p in problems]
        if not problems:
            rows.append((number, row))
    return rows, bad


def _fracture_count(lines: list[str], columns: list[str]) -> int:
    """Fractures of the file from its ``fracture`` column alone (a row without
    an id is a fracture of its own), counted before any number is read."""
    rows = (
        line.split(",")
        for line in lines[1:]
        if line.strip() and not line.lstrip().startswith("#")
    )
    if "fracture" not in columns:
        return sum(1 for _ in rows)
    at = columns.index("fracture")
    ids, single = set(), 0
    for fields in rows:
        fid = fields[at].strip() if at < len(fields) else ""
        if fid:
            ids.add(fid)
        else:
            single += 1
    return len(ids) + single


def _group_rows(rows: list) -> list[tuple[str | None, list]]:
    """Rows grouped by the ``fracture`` column in order of first appearance; a
    row without a fracture id is a fracture of its own."""
    groups: dict[object, list] = {}
    for number, row in rows:
        fid = row.get("fracture")
        groups.setdefault(fid if fid is not None else ("row", number), []).append(
            (number, row)
        )
    return [(k if isinstance(k, str) else None, g) for k, g in groups.items()]


def _lines_text(group: list, shown: int = 6) -> str:
    """``line 4``, ``lines 4, 5, 9`` or ``lines 4, 5, 9, ..., 812 (40 rows)``."""
    numbers = [str(n) for n, _ in group]
    if len(numbers) > shown:
        head = ", ".join(numbers[: shown - 1])
        return f"lines {head}, ..., {numbers[-1]} ({len(numbers)} rows)"
    return f"line{'s' if len(numbers) > 1 else ''} {', '.join(numbers)}"


def _chain(group: list, fid, file: Path, tol: float) -> tuple[np.ndarray | None, list]:
    """Polyline of one fracture's segments, each starting where the last ended."""
    first = group[0][1]
    points = [(first["x0"], first["y0"]), (first["x1"], first["y1"])]
    bad = []
    for (prev, _), (number, row) in zip(group[:-1], group[1:], strict=True):
        start = (row["x0"], row["y0"])
        if math.dist(start, points[-1]) > tol:
            bad.append(
                f"{file} line {number}: fracture {quote(fid)} continues at "
                f"({exact(start[0])}, {exact(start[1])}) but its segment on line "
                f"{prev} ends at ({exact(points[-1][0])}, {exact(points[-1][1])}); "
                "the rows of a fracture must chain end to start"
            )
        points.append((row["x1"], row["y1"]))
    return (None if bad else np.array(points, dtype=np.float64)), bad


def _group_properties(group: list, fid, file: Path, defaults: dict):
    """(properties, problems): per-row values (equal across a fracture's rows),
    else the [network] defaults; friction must come from one or the other.
    ``properties["given"]`` names those the rows give (a [network] friction
    law applies to a fracture only where they do not: case.friction)."""
    props: dict[str, Any] = {"given": set()}
    bad: list[str] = []
    for name in PROPERTY_RULES:
        given = [(n, r[name]) for n, r in group if r.get(name) is not None]
        if given:
            props["given"].add(name)
        values = {v for _, v in given}
        if len(values) > 1:
            (n1, v1), (n2, v2) = given[0], next(g for g in given if g[1] != given[0][1])
            bad.append(
                f"{file} lines {n1} and {n2}: fracture {quote(fid)} has {name} "
                f"{fmt(v1)} and {fmt(v2)}; its rows must agree"
            )
        props[name] = given[0][1] if given else defaults.get(name)
    if props["friction"] is None and not bad:
        bad.append(
            f"{file} {_lines_text(group)}: no friction: give it in a friction "
            "column or as network.friction"
        )
    return props, bad


def read_segments_file(
    table: Table, grid: Grid | None, folder: Path, defaults: dict
) -> list[tuple[np.ndarray, dict, str]] | None:
    """``network.file``: [(points, properties, source)] per fracture, or None."""
    name = table.string("file")
    if name is None:
        return None
    file, key = folder / name, table.key("file")
    lines = csv_lines(file, key, table.problems)
    if lines is None:
        return None
    columns, bad = _csv_header(lines[0] if lines else None, file)
    if bad:
        add_capped(table.problems, key, bad)
        return None
    count = _fracture_count(lines, columns)
    if count > MAX_NETWORK_FRACTURES:  # before a number is read
        table.error(
            "file", f"{file}: {count} fractures, more than {MAX_NETWORK_FRACTURES}"
        )
        return None
    rows, bad = _csv_rows(lines, columns, file)
    tol = CSV_TOLERANCE * max(grid.size) if grid is not None else 0.0
    out = []
    for fid, group in _group_rows(rows):
        points, chain_bad = _chain(group, fid, file, tol)
        props, prop_bad = _group_properties(group, fid, file, defaults)
        bad += chain_bad + prop_bad
        if points is None or prop_bad:
            continue
        where = f"{file} {_lines_text(group)}"
        shape = _shape_problem(points, grid)
        if shape:
            bad.append(f"{where}: {shape}")
            continue
        label = f"fracture {quote(fid)}, " if fid is not None else ""
        out.append((points, props, f"network.file {name}: {label}{_lines_text(group)}"))
    if not rows and not bad:
        bad.append(f"{file}: no segment rows after the header")
    add_capped(table.problems, key, bad)
    return None if bad else out


def _shape_problem(points: np.ndarray, grid: Grid | None) -> str | None:
    """Self-intersection, or a fracture wholly outside the domain."""
    pair = self_intersection(points)
    if pair is not None:
        i, j = pair
        return f"self-intersecting polyline: segments {i} and {j} touch or cross"
    if grid is None:
        return None
    lo, hi = grid.box.lo, grid.box.hi
    if not any(
        segment_meets_box(a, b, lo, hi)
        for a, b in zip(points[:-1], points[1:], strict=True)
    ):
        return (
            f"lies outside the domain [{fmt(lo[0])}, {fmt(hi[0])}] x "
            f"[{fmt(lo[1])}, {fmt(hi[1])}]"
        )
    return None
