"""``[pore_pressure.field]``: pressure changes dp(x, y) from a file -> a
``PressureFieldSpec`` whose ``field`` interpolates them
(xfemslip.geometry.sampled).

Formats (by the file's suffix):

- ``.csv``: a header line naming the columns (``x`` and ``y``, any case,
  and the ``columns`` asked for, exactly; other columns are ignored), then
  one row per point; blank lines and lines starting with ``#`` are skipped.
  When the points form a full tensor grid (every pair of the distinct x and
  distinct y values present once) the fields are bilinear on that grid,
  otherwise linear on the Delaunay triangulation of the points;
- ``.vtu`` (XML) or ``.vtk`` (legacy), read by meshio: a 2D mesh (points
  with one z) of triangles, quads, pixels or polygons; ``columns`` names
  point arrays (linear on the cells split into triangles) or cell arrays
  (constant on each cell), all of one kind, one component each.

Every problem names the file (and the CSV line, the array, the point or
cell) and what was expected.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np

from xfemslip.case.files import (
    MAX_CSV_BYTES,
    MAX_VTK_BYTES,
    UnreadableInput,
    add_capped,
    input_size,
    quote,
    read_input,
)
from xfemslip.case.specs import PressureFieldSpec
from xfemslip.case.tables import Table, check_number, exact, show, suggest
from xfemslip.errors import CaseError
from xfemslip.geometry.sampled import GridField, TriangleField

__all__ = [
    "FIELD_KEYS",
    "FIELD_SUFFIXES",
    "OUTSIDE_RULES",
    "read_field_table",
    "read_pressure_field",
]

FIELD_KEYS = ("file", "columns", "outside")
FIELD_SUFFIXES = (".csv", ".vtu", ".vtk")
OUTSIDE_RULES = ("error", "nearest")
# A z coordinate within this (relative to the points' extent in x and y) of
# the first point's is the same plane.
PLANE_TOL = 1.0e-9
# meshio cell types: the corner nodes of 2D cells, in order around the cell
# (a pixel's nodes run 0 1 3 2); 0D and 1D cells are skipped; 3D refused.
CORNERS = {
    "triangle": [0, 1, 2],
    "triangle6": [0, 1, 2],
    "triangle7": [0, 1, 2],
    "quad": [0, 1, 2, 3],
    "quad8": [0, 1, 2, 3],
    "quad9": [0, 1, 2, 3],
    "pixel": [0, 1, 3, 2],
}
SKIPPED = ("vertex", "line", "line3", "poly_vertex", "poly_line")
SOLID = (
    "tetra",
    "tetra10",
    "hexahedron",
    "hexahedron20",
    "hexahedron27",
    "wedge",
    "wedge15",
    "pyramid",
    "pyramid13",
    "voxel",
    "polyhedron",
)


class _Bad(Exception):
    """One problem of the file (``str`` without the file's name), or several."""

    def __init__(self, *messages: str):
        super().__init__(messages[0] if messages else "")
        self.messages = list(messages)


# --------------------------------------------------------------------------- #
# The case keys
# --------------------------------------------------------------------------- #


def _read_columns(table: Table) -> tuple[str, ...] | None:
    """``columns``: a non-empty array of distinct non-empty names."""
    value = table.data.get("columns")
    if value is None:
        table.error("columns", 'required key missing: name them, e.g. ["dp"]')
        return None
    if not isinstance(value, list) or not value:
        table.error(
            "columns", f"expected a non-empty array of names, got {show(value)}"
        )
        return None
    names = []
    for i, v in enumerate(value):
        if not isinstance(v, str) or not v.strip():
            table.problems.append(
                (f"{table.key('columns')}[{i}]", f"expected a name, got {show(v)}")
            )
            return None
        names.append(v.strip())
    twice = [n for n, c in Counter(names).items() if c > 1]
    if twice:
        table.error("columns", f"names {twice[0]!r} twice (one field per name)")
        return None
    return tuple(names)


def _read_outside(table: Table) -> str | float | None:
    """``outside``: "error" (default), "nearest" or a value [Pa]."""
    value = table.data.get("outside", "error")
    if isinstance(value, str):
        return table.choice("outside", OUTSIDE_RULES, "error")
    if isinstance(value, bool) or not isinstance(value, int | float):
        table.error(
            "outside",
            f'expected "error", "nearest" or a pressure change in Pa, got '
            f"{show(value)}",
        )
        return None
    return check_number(value, table.key("outside"), table.problems)


def read_field_table(pore: Table, folder: Path) -> PressureFieldSpec | None:
    """``[pore_pressure.field]`` of the ``[pore_pressure]`` table: the keys
    and the file they name, read and checked (problems recorded, None)."""
    table = pore.table("field", FIELD_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    name = table.string("file")
    columns = _read_columns(table)
    outside = _read_outside(table)
    if name is not None and Path(name).suffix.lower() not in FIELD_SUFFIXES:
        table.error("file", f"expected a .csv, .vtu or .vtk file, got {name!r}")
    if (
        len(table.problems) > start
        or name is None
        or columns is None
        or outside is None
    ):
        return None
    file = folder / name
    try:
        kind, field = _load(file, columns, outside)
    except _Bad as bad:
        add_capped(
            table.problems, table.key("file"), [f"{file}: {m}" for m in bad.messages]
        )
        return None
    return PressureFieldSpec(
        file=file, columns=columns, outside=outside, kind=kind, field=field
    )


def read_pressure_field(path, columns, outside="error"):
    """The field of a pressure file for a script: ``values(xy)`` (n, 2) [m] ->
    (n_fields, n) [Pa] (xfemslip.geometry.sampled).

    path : a .csv, .vtu or .vtk file; columns : the CSV columns or VTK array
    names, one field each; outside : "error" | "nearest" | a value [Pa].
    Raises CaseError naming the file for anything it cannot read.
    """
    try:
        return _load(Path(path), tuple(columns), outside)[1]
    except _Bad as bad:
        raise CaseError(path, [("", m) for m in bad.messages]) from None


def _load(file: Path, columns: tuple[str, ...], outside):
    """(kind, field) of a file; _Bad with what is wrong."""
    if file.suffix.lower() == ".csv":
        return _from_csv(file, columns, outside)
    return _from_vtk(file, columns, outside)


# --------------------------------------------------------------------------- #
# CSV
# --------------------------------------------------------------------------- #


def _csv_header(line: str, columns: tuple[str, ...]) -> list[int]:
    """Indices of x, y and the asked columns in the header."""
    names = [c.strip() for c in line.split(",")]
    lower = [n.lower() for n in names]
    bad = []
    for axis in ("x", "y"):
        if lower.count(axis) != 1:
            found = "twice" if lower.count(axis) > 1 else "no column"
            bad.append(
                f"line 1: {found} {axis!r}; the header needs x, y and "
                + ", ".join(columns)
            )
    for c in columns:
        if names.count(c) == 0:
            bad.append(f"line 1: no column {c!r}{suggest(c, tuple(names))}")
        elif names.count(c) > 1:
            bad.append(f"line 1: column {c!r} appears twice")
    if bad:
        raise _Bad(*bad)
    return [lower.index("x"), lower.index("y"), *(names.index(c) for c in columns)]


def _csv_rows(lines: list[str], at: list[int], names: list[str]):
    """(numbers (n, 2 + k), line numbers) of the data rows."""
    width = len(lines[0].split(","))
    rows, numbers, bad = [], [], []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = line.split(",")
        if len(fields) != width:
            bad.append(
                f"line {number}: expected {width} values, got {len(fields)}: "
                + quote(line)
            )
            continue
        row = []
        for i, name in zip(at, names, strict=True):
            text = fields[i].strip()
            try:
                value = float(text)
            except ValueError:
                bad.append(f"line {number}: {name} is not a number: {quote(text)}")
                break
            if not math.isfinite(value):
                bad.append(
                    f"line {number}: {name} must be finite, got {quote(text)} "
                    "(leave out the points without data)"
                )
                break
            row.append(value)
        else:
            rows.append(row)
            numbers.append(number)
    if bad:
        raise _Bad(*bad)
    return np.array(rows, dtype=np.float64).reshape(-1, len(at)), np.array(numbers)


def _duplicates(xy: np.ndarray, numbers: np.ndarray) -> None:
    """_Bad if two rows give the same point."""
    order = np.lexsort((xy[:, 1], xy[:, 0]))
    same = np.flatnonzero(np.all(xy[order[1:]] == xy[order[:-1]], axis=1))
    if same.size:
        a, b = sorted(numbers[order[same[0] : same[0] + 2]])
        x, y = xy[order[same[0]]]
        raise _Bad(
            f"lines {a} and {b} give the same point ({exact(x)}, {exact(y)}); "
            "each point once"
        )


def _from_csv(file: Path, columns: tuple[str, ...], outside):
    try:
        lines = read_input(file, MAX_CSV_BYTES).splitlines()
    except UnreadableInput as exc:
        raise _Bad(f"cannot read it: {exc}") from None
    if not lines:
        raise _Bad("empty file, expected a header line x,y," + ",".join(columns))
    at = _csv_header(lines[0], columns)
    data, numbers = _csv_rows(lines, at, ["x", "y", *columns])
    xy, values = data[:, :2], data[:, 2:].T
    if len(xy) < 3:
        raise _Bad(f"{len(xy)} point(s); at least 3 (or a 2 x 2 grid) are needed")
    _duplicates(xy, numbers)
    ux, uy = np.unique(xy[:, 0]), np.unique(xy[:, 1])
    if ux.size >= 2 and uy.size >= 2 and ux.size * uy.size == len(xy):
        i, j = np.searchsorted(ux, xy[:, 0]), np.searchsorted(uy, xy[:, 1])
        grid = np.empty((len(columns), uy.size, ux.size))
        grid[:, j, i] = values
        return "grid", GridField(ux, uy, grid, outside, str(file))
    # scipy.spatial costs about 0.2 s to import: only a file of scattered
    # points needs it, not every case read
    from scipy.spatial import Delaunay, QhullError

    try:
        tri = Delaunay(xy)
    except QhullError:
        raise _Bad(
            f"its {len(xy)} points lie on one line: no area to interpolate over"
        ) from None
    description = (
        f"the convex hull of its {len(xy)} points, linear on their Delaunay triangles"
    )
    field = TriangleField(
        xy,
        tri.simplices,
        point_values=values,
        outside=outside,
        source=str(file),
        description=description,
    )
    return "points", field


# --------------------------------------------------------------------------- #
# VTK / VTU
# --------------------------------------------------------------------------- #


def _read_mesh(file: Path):
    """meshio's Mesh of a capped regular file; _Bad if it cannot be read."""
    try:
        input_size(file, MAX_VTK_BYTES)
    except UnreadableInput as exc:
        raise _Bad(f"cannot read it: {exc}") from None
    import meshio  # 0.2 s of imports, only for this format

    # the format's own reader: meshio.read prints and exits on a bad file
    reader = meshio.vtu.read if file.suffix.lower() == ".vtu" else meshio.vtk.read
    try:
        return reader(str(file))
    except Exception as exc:  # any failure of the reader is the file's
        reason = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise _Bad(f"cannot read it as VTK: {reason}") from None


def _planar_points(points: np.ndarray) -> np.ndarray:
    """(m, 2) x and y of the mesh points; _Bad unless they share one z."""
    xy = points[:, :2]
    if points.shape[1] == 3 and len(points):
        extent = float(np.ptp(xy, axis=0).max()) or 1.0
        z = points[:, 2]
        off = np.flatnonzero(np.abs(z - z[0]) > PLANE_TOL * extent)
        if off.size:
            raise _Bad(
                f"point {off[0]} has z = {exact(z[off[0]])}, point 0 z = "
                f"{exact(z[0])}: a 2D section (all points at one z) is expected"
            )
    return np.ascontiguousarray(xy, dtype=np.float64)


def _triangles(mesh):
    """(triangles (t, 3), cell_of (t,), blocks): the 2D cells split into
    triangles, the 2D cell each comes from (numbered over the 2D blocks in
    order) and the indices of the 2D blocks."""
    tris, owner, blocks, count = [], [], [], 0
    for b, block in enumerate(mesh.cells):
        kind, data = block.type, np.asarray(block.data)
        if kind in SKIPPED:
            continue
        if kind in SOLID:
            raise _Bad(f"has 3D cells ({kind}): a 2D section is expected")
        if kind in CORNERS:
            ring = data[:, CORNERS[kind]]
        elif kind.startswith("polygon"):
            ring = data
        else:
            raise _Bad(f"has cells of type {kind!r}, which are not read")
        k = ring.shape[1]
        fan = np.stack([ring[:, [0, i, i + 1]] for i in range(1, k - 1)], axis=1)
        tris.append(fan.reshape(-1, 3))
        owner.append(np.repeat(np.arange(count, count + len(ring)), k - 2))
        blocks.append(b)
        count += len(ring)
    if not tris:
        raise _Bad("has no 2D cells (triangles, quads, pixels or polygons)")
    return np.concatenate(tris), np.concatenate(owner), blocks


def _array(mesh, name: str, blocks: list[int]):
    """("point" | "cell", (m,) or (c,) values) of one named array."""
    if name in mesh.point_data:
        kind, a = "point", np.asarray(mesh.point_data[name], dtype=np.float64)
    elif name in mesh.cell_data:
        kind = "cell"
        parts = [np.asarray(mesh.cell_data[name][b], dtype=np.float64) for b in blocks]
        a = np.concatenate(parts)
    else:
        known = sorted([*mesh.point_data, *mesh.cell_data])
        listed = ", ".join(repr(k) for k in known) or "none"
        hint = suggest(name, tuple(known)) if known else ""
        raise _Bad(f"has no array named {name!r}{hint} (its arrays: {listed})")
    if a.ndim == 2 and a.shape[1] == 1:
        a = a[:, 0]
    if a.ndim != 1:
        raise _Bad(f"{kind} array {name!r} has {a.shape[1]} components, expected 1")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise _Bad(
            f"{kind} array {name!r} is {a[bad[0]]} at {kind} {bad[0]} (every "
            "value must be finite)"
        )
    return kind, a


def _from_vtk(file: Path, columns: tuple[str, ...], outside):
    mesh = _read_mesh(file)
    triangles, cell_of, blocks = _triangles(mesh)
    xy = _planar_points(np.asarray(mesh.points, dtype=np.float64))
    arrays = [_array(mesh, name, blocks) for name in columns]
    kinds = {kind for kind, _ in arrays}
    if len(kinds) > 1:
        raise _Bad(
            "columns name point arrays and cell arrays together; give arrays of "
            "one kind"
        )
    values = np.stack([a for _, a in arrays])
    cells = int(cell_of.max()) + 1
    if kinds == {"point"}:
        description = f"the {cells} cells of its mesh, linear on their triangles"
        field = TriangleField(
            xy,
            triangles,
            point_values=values,
            outside=outside,
            source=str(file),
            description=description,
        )
        return "mesh points", field
    description = f"the {cells} cells of its mesh, constant on each"
    field = TriangleField(
        xy,
        triangles,
        cell_values=values,
        cell_of=cell_of,
        outside=outside,
        source=str(file),
        description=description,
    )
    return "mesh cells", field
