"""``[[units]]`` and ``[reservoir]`` -> ``UnitSpec`` tuple: rock units and
their regions.

A unit is a layer between two horizons (``top``, ``base``), a layer
displaced across a fault (``top``, ``base`` and ``offset``), boxes or a
polygon; each may give E, nu, biot, density, its pore-pressure change
(``change``, or one per side of its fault for a displaced layer) and an
overpressure.  What a unit leaves out is the host's (``[material]``,
``[pore_pressure] biot``).  The one ``[reservoir]`` table is the unit
"reservoir" (its E and nu required, as always).

Polygon and box edges that lie within ``SNAP_CELLS`` local cell sizes of a
fracture, along it, are moved onto it, each end sliding along its other
edge (:func:`snap_to_fractures`): an edge
typed a few millimetres off a fault would otherwise put a sliver of the
wrong rock and pressure beside it, which moves the onset of slip (the
loading jumps at the wrong place along the fault).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from xfemslip.case.specs import RegionSpec, ReservoirSpec, UnitSpec
from xfemslip.case.tables import (
    BIOT,
    COORDINATE,
    NON_NEGATIVE,
    POISSON,
    POSITIVE,
    Range,
    Table,
    check_number,
    complete,
    frozen,
    show,
)
from xfemslip.geometry.regions import fault_x, in_region, polygon_problem

UNIT_KEYS = (
    "name",
    "top",
    "base",
    "offset",
    "box",
    "boxes",
    "polygon",
    "E",
    "nu",
    "biot",
    "density",
    "change",
    "overpressure",
)
OFFSET_KEYS = ("fracture", "throw", "lowered")
SIDES = ("left", "right")
RESERVOIR_KEYS = ("box", "boxes", "polygon", "E", "nu")
# A polygon or box edge whose two ends lie within this many local cell sizes
# of a fracture's line, along the fracture, is moved onto it.  A tenth of a
# cell is far below what the mesh resolves as a separate feature and far
# above the rounding of coordinates typed to a few decimals.
SNAP_CELLS = 0.1
NU_RANGE = POISSON
BIOT_RANGE = BIOT
MAX_UNITS = 1000


# --------------------------------------------------------------------------- #
# Boxes and polygons (shared with [reservoir])
# --------------------------------------------------------------------------- #


def check_box(value, key: str, problems: list) -> tuple | None:
    """[x0, y0, x1, y1] with x0 < x1 and y0 < y1 [m]."""
    if not isinstance(value, list) or len(value) != 4:
        problems.append(
            (
                key,
                f"expected an array [x0, y0, x1, y1] of 4 numbers, got {show(value)}",
            )
        )
        return None
    items = complete(
        [
            check_number(v, f"{key}[{i}]", problems, COORDINATE)
            for i, v in enumerate(value)
        ]
    )
    if items is None:
        return None
    x0, y0, x1, y1 = items
    if not (x0 < x1 and y0 < y1):
        problems.append(
            (key, f"must satisfy x0 < x1 and y0 < y1, got {[x0, y0, x1, y1]}")
        )
        return None
    return tuple(items)


def read_polygon(table: Table) -> list | None:
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


ONE_SHAPE = (
    "give exactly one of box = [x0, y0, x1, y1], boxes = [[x0, y0, x1, y1], "
    "...] or polygon = [[x, y], ...]"
)


def read_boxes(table: Table) -> list | None:
    """``box = [..]`` or ``boxes = [[..], ..]`` (one of them)."""
    if table.has("box") == table.has("boxes"):
        table.error(None, ONE_SHAPE)
        return None
    if table.has("box"):
        box = check_box(table.data["box"], table.key("box"), table.problems)
        return None if box is None else [box]
    value = table.data["boxes"]
    if not isinstance(value, list) or not value:
        table.error("boxes", f"expected a non-empty array of boxes, got {show(value)}")
        return None
    boxes = [
        check_box(v, f"{table.key('boxes')}[{i}]", table.problems)
        for i, v in enumerate(value)
    ]
    return None if any(b is None for b in boxes) else boxes


def _shape(table: Table) -> RegionSpec | None:
    """A region from ``box``/``boxes`` or ``polygon``."""
    if table.has("polygon"):
        if table.has("box") or table.has("boxes"):
            table.error(None, ONE_SHAPE)
            return None
        polygon = read_polygon(table)
        if polygon is None:
            return None
        return RegionSpec(kind="polygon", polygon=frozen(polygon))
    boxes = read_boxes(table)
    if boxes is None:
        return None
    return RegionSpec(kind="boxes", boxes=frozen(np.array(boxes, float).reshape(-1, 4)))


def _cell_centres(grid) -> np.ndarray:
    x, y = grid.mesh.x, grid.mesh.y
    cx, cy = np.meshgrid(0.5 * (x[1:] + x[:-1]), 0.5 * (y[1:] + y[:-1]))
    return np.column_stack([cx.ravel(), cy.ravel()])


UNIT_NO_CENTRE = (
    "contains no element centre of the mesh (a cell belongs to the unit its "
    "centre lies in)"
)
RESERVOIR_NO_CENTRE = (
    "contains no element centre of the mesh (a cell belongs to the reservoir "
    "when its centre lies inside)"
)


# --------------------------------------------------------------------------- #
# Snapping edges onto fractures
# --------------------------------------------------------------------------- #


def _local_sizes(grid, points) -> np.ndarray:
    """(k,) the larger side of the mesh cell holding each of ``points``
    (k, 2) [m] (the nearest cell for a point outside the mesh)."""
    points = np.atleast_2d(points)
    size = np.zeros(len(points))
    for axis, v in ((grid.mesh.x, points[:, 0]), (grid.mesh.y, points[:, 1])):
        k = np.clip(np.searchsorted(axis, v) - 1, 0, axis.size - 2)
        size = np.maximum(size, axis[k + 1] - axis[k])
    return size


def _segments(fractures):
    """(fracture index, start a, unit tangent t, normal n, length L) of every
    straight segment of the fractures, in order."""
    for fr in fractures:
        F = np.asarray(fr.points, float)
        for a, b in zip(F[:-1], F[1:], strict=True):
            L = float(np.hypot(*(b - a)))
            t = (b - a) / L
            yield fr.index, a, t, np.array([-t[1], t[0]]), L


def _near_fractures(P, fractures, grid) -> np.ndarray:
    """Indices (ascending) of the closed polygon P's edges that may lie
    within SNAP_CELLS local cell sizes of a fracture's line, and their
    neighbours (snapping an edge moves both its ends): a vectorised sieve
    of the per-edge test (_nearest_line), twice as wide, so that a polygon
    of many thousand edges is not tested edge by edge against every
    segment."""
    Q = np.roll(P, -1, axis=0)
    tol = 2.0 * SNAP_CELLS * _local_sizes(grid, 0.5 * (P + Q))
    near = np.zeros(len(P), bool)
    for _, a, t, n, L in _segments(fractures):
        dp, dq = np.abs((P - a) @ n), np.abs((Q - a) @ n)
        sp, sq = (P - a) @ t, (Q - a) @ t
        along = (np.maximum(sp, sq) >= -tol) & (np.minimum(sp, sq) <= L + tol)
        near |= (np.maximum(dp, dq) <= tol) & along
    hit = np.nonzero(near)[0]
    return np.unique(np.concatenate([hit - 1, hit, hit + 1]) % len(P))


def _nearest_line(fractures, p, q, tol):
    """(fracture index, distance, a point on its line, its unit tangent) of
    the first fracture segment whose line passes within ``tol`` of both p and
    q with p-q lying along it, or None."""
    for index, a, t, n, L in _segments(fractures):
        dp, dq = float((p - a) @ n), float((q - a) @ n)
        if max(abs(dp), abs(dq)) > tol or (dp == 0.0 and dq == 0.0):
            continue
        sp, sq = sorted((float((p - a) @ t), float((q - a) @ t)))
        if sq < -tol or sp > L + tol:  # beside the segment, not along it
            continue
        return index, max(abs(dp), abs(dq)), a, t
    return None


def _onto_line(v, towards, a, t):
    """v moved onto the line (a, t) along the edge from ``towards`` to v (so
    the neighbouring edge keeps its direction: a corner on a horizon stays on
    it), or straight across when that edge runs along the line."""
    e = v - towards
    den = e[0] * t[1] - e[1] * t[0]
    n = np.array([-t[1], t[0]])
    if abs(den) <= 1e-9 * float(np.hypot(*e)):
        return v - float((v - a) @ n) * n
    w = a - towards
    k = (w[0] * t[1] - w[1] * t[0]) / den
    return towards + k * e


def snap_to_fractures(region: RegionSpec, fractures, grid):
    """(region, snapped): the region with every polygon/box edge that lies
    within SNAP_CELLS local cell sizes of a fracture, along it, moved onto it
    (each end slides along its other edge, so corners stay on their
    horizons; boxes become a polygon then), and (edge name, fracture,
    distance [m]) of each edge moved."""
    if grid is None or not fractures or region.kind not in ("polygon", "boxes"):
        return region, ()
    if region.kind == "boxes":
        boxes = np.asarray(region.boxes, float).reshape(-1, 4)
        if len(boxes) > 1:
            return region, ()  # boxes of a union cannot all be one polygon
        x0, y0, x1, y1 = boxes[0]
        P = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
        names = [f"box: y0 = {y0:g}", f"box: x1 = {x1:g}", f"box: y1 = {y1:g}"]
        names.append(f"box: x0 = {x0:g}")
    else:
        P = np.array(region.polygon, float)
        names = [f"polygon edge {i}" for i in range(len(P))]
    k = len(P)
    moved = []
    for i in _near_fractures(P, fractures, grid):
        j = (i + 1) % k
        tol = SNAP_CELLS * float(_local_sizes(grid, 0.5 * (P[i] + P[j]))[0])
        hit = _nearest_line(fractures, P[i], P[j], tol)
        if hit is not None:
            index, distance, a, t = hit
            P[i] = _onto_line(P[i], P[(i - 1) % k], a, t)
            P[j] = _onto_line(P[j], P[(j + 1) % k], a, t)
            moved.append((names[i], index, distance))
    if not moved:
        return region, ()
    if polygon_problem(P) is not None:
        return region, ()  # snapping would fold the polygon: keep it as typed
    return RegionSpec(kind="polygon", polygon=frozen(P)), tuple(moved)


# --------------------------------------------------------------------------- #
# [[units]]
# --------------------------------------------------------------------------- #


def _hanging_wall(fault: np.ndarray, y: float) -> str | None:
    """The side ("left"/"right") above the fault line at height y (the
    hanging wall), or None where the fault is vertical there."""
    dy = 1e-6 * max(1.0, float(np.ptp(fault[:, 1])))
    x_up, x_down = fault_x(np.array([y + dy, y - dy]), fault)
    if x_down == x_up:
        return None
    return "right" if x_down > x_up else "left"


def _fault_problem(points: np.ndarray) -> str | None:
    """Why a polyline cannot bound a displaced layer (it must be strictly
    monotone in y), or None."""
    dy = np.diff(np.asarray(points, float)[:, 1])
    if np.all(dy > 0) or np.all(dy < 0):
        return None
    return (
        "is not strictly monotone in y (a displaced layer needs a fault that "
        "rises or falls along its whole length)"
    )


def _offset(table: Table, fractures, top, base) -> dict | None:
    """``offset = { fracture = k, throw = .., lowered = .. }``."""
    sub = table.table("offset", OFFSET_KEYS)
    if sub is None:
        return None
    k = sub.integer("fracture", rule=Range(0, 10**9))
    throw = sub.number("throw", rule=NON_NEGATIVE)
    lowered = sub.choice("lowered", SIDES, None)
    if k is None or throw is None or (sub.has("lowered") and lowered is None):
        return None
    if fractures is None:
        return None
    if k >= len(fractures):
        sub.error(
            "fracture",
            f"names fractures[{k}], but the case has {len(fractures)} fracture(s)",
        )
        return None
    fault = np.asarray(fractures[k].points, float)
    why = _fault_problem(fault)
    if why is not None:
        sub.error("fracture", f"fractures[{k}] {why}")
        return None
    if lowered is None and top is not None and base is not None:
        lowered = _hanging_wall(fault, 0.5 * (top + base))
        if lowered is None:
            sub.error(
                "lowered",
                f"required key missing: fractures[{k}] is vertical, so it has no "
                'hanging wall; say which side is lowered ("left" or "right")',
            )
            return None
    return {"fracture": k, "throw": throw, "lowered": lowered, "fault": fault}


def _layer(table: Table, fractures) -> RegionSpec | None:
    """A layer between ``top`` and ``base``, displaced by ``offset`` if given."""
    top, base = table.number("top"), table.number("base")
    if top is not None and base is not None and not top > base:
        table.error("top", f"must be above base, got top {top:g} <= base {base:g}")
        return None
    offset = _offset(table, fractures, top, base) if table.has("offset") else None
    if top is None or base is None or (table.has("offset") and offset is None):
        return None
    if offset is None:
        return RegionSpec(kind="layer", top=top, base=base)
    return RegionSpec(
        kind="offset",
        top=top,
        base=base,
        fault=frozen(offset["fault"]),
        fracture=offset["fracture"],
        throw=offset["throw"],
        lowered=offset["lowered"],
    )


def _change(table: Table, region: RegionSpec | None):
    """(change, change_sides): ``change = dp`` or, for a displaced layer,
    ``change = { left = .., right = .. }`` (its two compartments) [Pa]."""
    if not table.has("change"):
        return None, None
    value = table.data["change"]
    if not isinstance(value, dict):
        return table.number("change"), None
    if region is not None and region.kind != "offset":
        table.error(
            "change",
            "gives one change per side of a fault, which only a displaced "
            "layer (top, base and offset) has; give one number",
        )
        return None, None
    sub = Table(value, table.key("change"), table.problems, SIDES)
    left, right = sub.number("left"), sub.number("right")
    if left is None or right is None:
        return None, None
    return None, (left, right)


def _shape_key_of(data) -> str:
    """The key that gave a unit (a TOML table) its region, for messages."""
    for key in ("top", "polygon", "box", "boxes"):
        if isinstance(data, dict) and key in data:
            return key
    return "top"


def _read_unit(table: Table, index: int, ctx: dict) -> UnitSpec | None:
    """One [[units]] entry."""
    start = len(table.problems)
    name = table.string("name", f"unit {index}")
    layered = table.has("top") or table.has("base") or table.has("offset")
    shaped = any(table.has(k) for k in ("box", "boxes", "polygon"))
    if layered and shaped:
        table.error(
            None,
            "give a unit either as a layer (top and base, optionally offset) or "
            "as box, boxes or polygon, not both",
        )
        return None
    if not layered and not shaped:
        table.error(
            None,
            "required key missing: give top and base (a layer), or box, boxes "
            "or polygon",
        )
        return None
    region = _layer(table, ctx["fractures"]) if layered else _shape(table)
    host = ctx["material"]
    E = table.number("E", host.E if host else None, POSITIVE)
    nu = table.number("nu", host.nu if host else None, NU_RANGE)
    biot = table.number("biot", None, BIOT_RANGE)
    density = table.number("density", None, POSITIVE)
    change, sides = _change(table, region)
    overpressure = table.number("overpressure", 0.0)
    if len(table.problems) > start or region is None or E is None or nu is None:
        return None
    return UnitSpec(
        name=name,
        region=region,
        E=E,
        nu=nu,
        biot=biot,
        density=density,
        change=change,
        change_sides=sides,
        overpressure=overpressure,
    )


def read_units(root: Table, fractures, material) -> tuple[UnitSpec, ...] | None:
    """``[[units]]`` (after ``[material]`` and ``[[fractures]]``: a unit
    takes the host's constants it leaves out, and a displaced layer its
    fault).  Names are unique."""
    value = root.data.get("units", [])
    if not isinstance(value, list):
        root.error(
            "units",
            f"expected an array of tables [[units]], got {show(value)} (write "
            "[[units]], not [units])",
        )
        return None
    if len(value) > MAX_UNITS:
        root.error("units", f"has {len(value):,} units, more than {MAX_UNITS:,}")
        return None
    if value and root.has("reservoir"):
        root.error(
            "reservoir",
            "give the rock units as [[units]] (a [[units]] entry named "
            '"reservoir" replaces [reservoir]), not both',
        )
        return None
    ctx = {"fractures": fractures or (), "material": material}
    read: list[UnitSpec | None] = []
    for i, item in enumerate(value):
        if not isinstance(item, dict):
            root.error(f"units[{i}]", f"expected a table, got {show(item)}")
            read.append(None)
            continue
        table = Table(item, f"units[{i}]", root.problems, UNIT_KEYS)
        read.append(_read_unit(table, i, ctx))
    specs = complete(read)
    if specs is None:
        return None
    names = [s.name for s in specs]
    for i, name in enumerate(names):
        if name in names[:i]:
            root.error(f"units[{i}].name", f"repeats the name {name!r}")
            return None
    return tuple(specs)


# --------------------------------------------------------------------------- #
# [reservoir]
# --------------------------------------------------------------------------- #


def read_reservoir(root: Table) -> ReservoirSpec | None:
    """[reservoir]: boxes or a polygon, and the reservoir's E [Pa] and nu [-]
    (its edges are snapped and its cells checked by :func:`settle_units`
    once the mesh is known)."""
    value = root.data.get("reservoir")
    if isinstance(value, list):
        root.error(
            "reservoir",
            "expected one table [reservoir], got an array of tables (several "
            "rock units are [[units]] tables)",
        )
        return None
    table = root.table("reservoir", RESERVOIR_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    region = _shape(table)
    E = table.number("E", rule=POSITIVE)
    nu = table.number("nu", rule=NU_RANGE)
    if len(table.problems) > start or region is None:
        return None
    return _reservoir_spec(region, E, nu)


def _reservoir_spec(region: RegionSpec, E, nu, snapped=()) -> ReservoirSpec:
    return ReservoirSpec(
        boxes=region.box_array if region.kind == "boxes" else frozen(np.zeros((0, 4))),
        E=E,
        nu=nu,
        polygon=region.polygon if region.kind == "polygon" else None,
        snapped=snapped,
    )


def settle_units(root: Table, units, reservoir, fractures, grid):
    """(units, reservoir) once the mesh is known: every polygon or box edge
    within SNAP_CELLS of a fracture snapped onto it, and a region that holds
    no element centre an error (recorded; the units or reservoir are then
    None)."""
    if grid is None or grid.mesh is None:
        return units, reservoir
    fractures = fractures or ()
    if reservoir is not None:
        region, snapped = snap_to_fractures(
            reservoir_unit(reservoir).region, fractures, grid
        )
        if not in_region(_cell_centres(grid), region).any():
            key = _shape_key_of(root.data.get("reservoir", {}))
            root.error(f"reservoir.{key}", RESERVOIR_NO_CENTRE)
            return units, None
        reservoir = _reservoir_spec(region, reservoir.E, reservoir.nu, snapped)
    if not units:
        return units, reservoir
    out = []
    items = root.data.get("units", [])
    for i, unit in enumerate(units):
        region, snapped = snap_to_fractures(unit.region, fractures, grid)
        if not in_region(_cell_centres(grid), region).any():
            root.error(f"units[{i}].{_shape_key_of(items[i])}", UNIT_NO_CENTRE)
            return None, reservoir
        out.append(replace(unit, region=region, snapped=snapped))
    return tuple(out), reservoir


def reservoir_unit(reservoir: ReservoirSpec) -> UnitSpec:
    """The [reservoir] table as the unit named "reservoir"."""
    if reservoir.polygon is not None:
        region = RegionSpec(kind="polygon", polygon=reservoir.polygon)
    else:
        region = RegionSpec(kind="boxes", boxes=reservoir.boxes)
    return UnitSpec(
        name="reservoir",
        region=region,
        E=reservoir.E,
        nu=reservoir.nu,
        snapped=reservoir.snapped,
    )
