"""``[[fractures]]`` -> ``FractureSpec`` tuple: polyline (``points`` or
``center``/``length``/``angle``), contact parameters (friction and cohesion:
:mod:`xfemslip.case.friction`) and tip treatment, and
the checks of a polyline (zero-length segments, self-intersection, a fracture
that misses the domain) that ``network.file`` shares.
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.case.friction import read_strength
from xfemslip.case.grid import Grid
from xfemslip.case.hydraulics import read_hydraulic
from xfemslip.case.specs import FractureSpec
from xfemslip.case.tables import (
    MAX_COORDINATE,
    NON_NEGATIVE,
    POSITIVE,
    Range,
    Table,
    check_number,
    check_vector,
    complete,
    exact,
    fmt,
    frozen,
    show,
)
from xfemslip.geometry.polyline import first_meeting

FRACTURE_KEYS = (
    "center",
    "length",
    "angle",
    "points",
    "point",
    "dip",
    "dip_direction",
    "top",
    "base",
    "fluid_pressure",
    "friction",
    "cohesion",
    "kn",
    "kt",
    "tip",
    "hydraulic",
)
TIP_KINDS = ("branch", "ramp")
TIP_KEYS = ("kind", "radius")
DIP_DIRECTIONS = ("right", "left")
# the fluid pressure in a fracture from the pore pressures of its two faces
# (xfemslip.fem.zones.fluid_value), or a number [Pa]
FLUID_RULES = ("mean", "higher", "lower")
DIP_KEYS = ("point", "dip", "dip_direction", "top", "base")


def _cos_sin_degrees(angle: float) -> tuple[float, float]:
    """cos and sin of ``angle`` [deg], exact at multiples of 45 degrees.

    math.cos(math.pi / 2) is 6e-17, not 0, and cos/sin(pi/4) differ in the last
    bit: reducing to [0, 45] and rotating by quarter turns keeps vertical,
    horizontal and diagonal fractures exactly on their lines.
    """
    turns, rest = divmod(angle, 90.0)  # rest in [0, 90)
    if rest == 45.0:
        c = s = math.sqrt(0.5)
    elif rest < 45.0:
        c, s = math.cos(math.radians(rest)), math.sin(math.radians(rest))
    else:  # 90 - rest is exact here (Sterbenz)
        s, c = math.cos(math.radians(90.0 - rest)), math.sin(math.radians(90.0 - rest))
    for _ in range(int(turns) % 4):
        c, s = -s, c  # rotate by +90 degrees
    return c + 0.0, s + 0.0  # + 0.0 turns -0.0 into 0.0


def _read_points(table: Table) -> np.ndarray | None:
    """``points``: an array of >= 2 points, each two finite numbers [m]."""
    value = table.data["points"]
    key = table.key("points")
    if not isinstance(value, list) or len(value) < 2:
        table.error(
            "points", f"expected an array of >= 2 points [x, y], got {show(value)}"
        )
        return None

    def check(v, k):
        return check_number(v, k, table.problems)

    points = [
        check_vector(p, f"{key}[{i}]", table.problems, 2, check)
        for i, p in enumerate(value)
    ]
    return (
        None if any(p is None for p in points) else np.array(points, dtype=np.float64)
    )


def _dip_points(table: Table) -> np.ndarray | None:
    """The two ends of a fault given as drawn: ``point`` on it, ``dip`` [deg]
    below the horizontal towards ``dip_direction`` ("right" = +x, default),
    and either ``length`` (centred on the point) or ``top`` and ``base`` (the
    y of its upper and lower end).  The upper end comes first, so t points
    down the dip."""
    extent = [k for k in ("length", "top", "base") if table.has(k)]
    if table.has("length") and (table.has("top") or table.has("base")):
        table.error(
            None, f"give either length or top and base, not both (got {extent})"
        )
        return None
    point = table.numbers("point", 2, hint=" (a point on the fault [x, y])")
    dip = table.number(
        "dip", rule=Range(0.0, 90.0, lo_open=True), hint=" (degrees below horizontal)"
    )
    direction = table.choice("dip_direction", DIP_DIRECTIONS, "right")
    if table.has("length") or not (table.has("top") or table.has("base")):
        length = table.number(
            "length", rule=POSITIVE, hint=" (or top and base: the y of its ends)"
        )
        top = base = None
    else:
        length = None
        top, base = table.number("top"), table.number("base")
        if top is not None and base is not None and not top > base:
            table.error("top", f"must be above base, got top {top:g} <= base {base:g}")
            return None
    if point is None or dip is None or direction is None:
        return None
    if length is None and (top is None or base is None):
        return None
    c, s = _cos_sin_degrees(dip)  # down the dip: (+-cos, -sin)
    down = np.array([c if direction == "right" else -c, -s])
    p = np.asarray(point, float)
    with np.errstate(over="ignore", invalid="ignore"):
        if length is not None:
            points = np.array([p - 0.5 * length * down, p + 0.5 * length * down])
        else:
            points = np.array(
                [p + (p[1] - top) / s * down, p + (p[1] - base) / s * down]
            )
    if not np.isfinite(points).all():
        table.error(None, "the fault's ends overflow")
        return None
    return points


def _fracture_points(table: Table) -> np.ndarray | None:
    """Polyline vertices from ``points``, from ``center``/``length``/``angle``,
    or from ``point``/``dip`` (:func:`_dip_points`)."""
    if table.has("dip") or table.has("point"):
        other = [k for k in ("points", "center", "angle") if table.has(k)]
        if other:
            table.error(
                None,
                "give a fault as point and dip, as points, or as center, length "
                f"and angle, not mixed (got dip/point and {', '.join(other)})",
            )
            return None
        return _dip_points(table)
    stray = [k for k in ("dip_direction", "top", "base") if table.has(k)]
    if stray:
        table.error(stray[0], "only used with point and dip")
        return None
    given = [k for k in ("center", "length", "angle") if table.has(k)]
    if given and table.has("points"):
        table.error(
            None,
            "give either points or center, length and angle, not both "
            f"(got points and {', '.join(given)})",
        )
        return None
    if table.has("points"):
        return _read_points(table)
    if not given:
        table.error(
            "points",
            "required key missing: give points = [[x0, y0], "
            "[x1, y1], ...] or center, length and angle",
        )
        return None
    hint = f" ({', '.join(given)} given: center, length and angle go together)"
    center = table.numbers("center", 2, hint=hint)
    length = table.number("length", rule=POSITIVE, hint=hint)
    angle = table.number("angle", hint=hint)
    if center is None or length is None or angle is None:
        return None
    c, s = _cos_sin_degrees(angle)
    with np.errstate(over="ignore", invalid="ignore"):
        half = 0.5 * length * np.array([c, s])
        points = np.array([np.asarray(center) - half, np.asarray(center) + half])
    if not np.isfinite(points).all():
        table.error(
            "length",
            f"center -/+ length/2 (cos angle, sin angle) overflows, "
            f"got length {exact(length)}",
        )
        return None
    return points


def _read_fracture(table: Table, index: int, grid: Grid | None) -> FractureSpec | None:
    """One [[fractures]] entry."""
    start = len(table.problems)
    points = _fracture_points(table)
    strength = read_strength(table)
    kn = table.number("kn", None, rule=POSITIVE)
    kt = table.number("kt", None, rule=POSITIVE)
    tip, radius = read_tip(table)
    hydraulic = read_hydraulic(table)
    fluid = read_fluid_rule(table)
    if points is not None and np.abs(points).max() > MAX_COORDINATE:
        table.error(
            "points" if table.has("points") else "length",
            f"a vertex lies beyond +-{MAX_COORDINATE:g} m (squared distances in "
            f"the geometry would overflow), got {exact(np.abs(points).max())}",
        )
        points = None
    if points is not None:
        _check_polyline(table, points, grid)
    if len(table.problems) > start:
        return None
    return FractureSpec(
        index=index,
        points=frozen(points),
        friction=strength.friction,
        cohesion=strength.cohesion,
        weakening=strength.weakening(),
        kn=kn,
        kt=kt,
        tip=tip,
        tip_radius=radius,
        hydraulic=hydraulic,
        fluid_pressure=fluid if fluid is not None else "mean",
    )


def read_fluid_rule(table: Table) -> str | float | None:
    """``fluid_pressure``: "mean" (default), "higher", "lower" of the pore
    pressures on the two faces, or a number [Pa] >= 0 (sealing: the fracture
    holds that pressure throughout)."""
    if not table.has("fluid_pressure"):
        return "mean"
    value = table.data["fluid_pressure"]
    if isinstance(value, str):
        return table.choice("fluid_pressure", FLUID_RULES)
    return table.number(
        "fluid_pressure",
        rule=NON_NEGATIVE,
        hint=' ("mean", "higher", "lower" or a pressure in Pa)',
    )


def read_tip(table: Table) -> tuple[str, float | None]:
    """``tip = "branch"`` / ``"ramp"``, or ``tip = { kind = .., radius = .. }``.

    branch: near-tip branch functions on the nodes within ``radius`` (m) of each
    tip (default: 4 tip-cell sizes); ramp: the jump falls linearly to zero
    across the tip cell.  Default "branch".
    """
    if not table.has("tip"):
        return "branch", None
    value = table.data["tip"]
    if isinstance(value, dict):
        sub = Table(value, table.key("tip"), table.problems, TIP_KEYS)
        kind = sub.choice("kind", TIP_KINDS, "branch")
        radius = sub.number("radius", None, rule=POSITIVE)
        if radius is not None and kind == "ramp":
            sub.error("radius", 'only used with kind = "branch"')
        return kind, radius
    return table.choice("tip", TIP_KINDS), None


def read_fractures(root: Table, grid: Grid | None) -> tuple[FractureSpec, ...] | None:
    """``[[fractures]]``: zero or more fracture tables."""
    value = root.data.get("fractures", [])
    if not isinstance(value, list):
        root.error(
            "fractures",
            f"expected an array of tables [[fractures]], got "
            f"{show(value)} (write [[fractures]], not [fractures])",
        )
        return None
    specs: list[FractureSpec | None] = []
    for i, item in enumerate(value):
        if not isinstance(item, dict):
            root.error(f"fractures[{i}]", f"expected a table, got {show(item)}")
            specs.append(None)
            continue
        table = Table(item, f"fractures[{i}]", root.problems, FRACTURE_KEYS)
        specs.append(_read_fracture(table, i, grid))
    read = complete(specs)
    return None if read is None else tuple(read)


# --------------------------------------------------------------------------- #
# Polyline checks
# --------------------------------------------------------------------------- #


def self_intersection(points: np.ndarray) -> tuple[int, int] | None:
    """First pair (i, j) of segments that cross, touch or fold back, else None
    (a sweep over the segments' boxes: the cost follows the pairs that come
    close, not all pairs)."""
    return first_meeting(points)


def segment_meets_box(a: np.ndarray, b: np.ndarray, lo, hi) -> bool:
    """Whether segment a-b has a point in the closed box [lo, hi] (Liang-Barsky)."""
    t0, t1 = 0.0, 1.0
    for axis in (0, 1):
        # Python floats: an overflow gives inf, which the min/max below handle.
        d = float(b[axis]) - float(a[axis])
        if d == 0.0:
            if not lo[axis] <= a[axis] <= hi[axis]:
                return False
            continue
        ta = (float(lo[axis]) - float(a[axis])) / d
        tb = (float(hi[axis]) - float(a[axis])) / d
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    return t0 <= t1


@np.errstate(over="ignore")
def _check_polyline(table: Table, points: np.ndarray, grid: Grid | None) -> None:
    """Zero-length segments, self-intersection, and a fracture off the domain."""
    name = "points" if table.has("points") else "length"
    lengths = np.hypot(*np.diff(points, axis=0).T)
    if not lengths.any():
        table.error(name, "fracture has zero length (all its points coincide)")
        return
    for j in np.flatnonzero(lengths == 0.0):
        x, y = points[j]
        table.error(
            f"points[{j + 1}]",
            f"repeats the previous point ({exact(x)}, {exact(y)}): zero-length segment",
        )
    if not lengths.all():
        return
    pair = self_intersection(points)
    if pair is not None:
        table.error(
            "points",
            f"self-intersecting polyline: segments {pair[0]} and "
            f"{pair[1]} touch or cross",
        )
    if grid is None:
        return
    lo, hi = grid.box.lo, grid.box.hi
    if not any(
        segment_meets_box(a, b, lo, hi)
        for a, b in zip(points[:-1], points[1:], strict=True)
    ):
        table.error(
            None,
            f"lies outside the domain [{fmt(lo[0])}, {fmt(hi[0])}] x "
            f"[{fmt(lo[1])}, {fmt(hi[1])}]",
        )
