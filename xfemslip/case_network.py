"""``[network]``: many fractures from a CSV file of segments and/or a random
network (``[network.generate]``) -> more ``FractureSpec`` entries.

Private helper of :mod:`xfemslip.case`, which stays the ONLY entry point for
validating user input (house style: case.py is the only place user input is
validated); import the public names from ``xfemslip.case``, not from here.

Numbering (``FractureSpec.index``, ``/fractures/<i>`` of result.h5): the
inline ``[[fractures]]`` first, in file order; then the fractures of
``network.file`` in the order of their first row; then the generated ones in
placement order.  ``FractureSpec.source`` says where each came from, and
``xfemslip check`` prints it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from xfemslip import dfn
from xfemslip.case_csv import CSV_TOLERANCE, _add_capped
from xfemslip.case_fractures import _read_tip
from xfemslip.case_grid import _Grid
from xfemslip.case_polyline import _segment_meets_box, _self_intersection
from xfemslip.case_specs import FractureSpec
from xfemslip.case_tables import (
    _NON_NEGATIVE,
    _POSITIVE,
    Range,
    _exact,
    _fmt,
    _frozen,
    _range_problem,
    _show,
    _suggest,
    _Table,
)

NETWORK_KEYS = ("file", "generate", "friction", "cohesion", "kn", "kt", "tip")
PROPERTY_RULES = {
    "friction": _NON_NEGATIVE,
    "cohesion": _NON_NEGATIVE,
    "kn": _POSITIVE,
    "kt": _POSITIVE,
}
SEGMENT_COLUMNS = ("x0", "y0", "x1", "y1")
OPTIONAL_COLUMNS = ("fracture", *PROPERTY_RULES)
GENERATE_KEYS = (
    "seed",
    "count",
    "p20",
    "p21",
    "region",
    "orientation",
    "length",
    "sets",
    "intersections",
    "min_spacing",
    "outside",
    "min_length",
)
SET_KEYS = ("weight", "orientation", "length")
ORIENTATION_KEYS = ("distribution", "mean", "kappa", "std")
LENGTH_KEYS = ("distribution", "value", "exponent", "min", "max", "median", "sigma")
MAX_NETWORK_FRACTURES = 5_000  # per source (file rows, generated count)
# A truncated lognormal keeping less than this share of its mass would make
# the resampling loop spin: refused.
MIN_LOGNORMAL_MASS = 1e-4


# --------------------------------------------------------------------------- #
# CSV of segments
# --------------------------------------------------------------------------- #


def _csv_header(line: str | None, file: Path) -> tuple[list[str], list[str]]:
    """(columns, problems) of the header line."""
    if line is None:
        return [], [f"{file} line 1: empty file, expected the header x0,y0,x1,y1"]
    columns = [c.strip().lower() for c in line.split(",")]
    allowed = SEGMENT_COLUMNS + OPTIONAL_COLUMNS
    bad = [
        f"{file} line 1: unknown column {c!r}{_suggest(c, allowed)}"
        for c in columns
        if c not in allowed
    ]
    bad += [
        f"{file} line 1: column {c!r} appears twice"
        for c in sorted({c for c in columns if columns.count(c) > 1})
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
        return None, f"{name} is not a number: {text!r}"
    if not math.isfinite(value):
        return None, f"{name} must be finite, got {text!r}"
    message = _range_problem(value, PROPERTY_RULES.get(name), name)
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
                f"({','.join(columns)}), got {len(fields)}: {line.strip()!r}"
            )
            continue
        row, problems = {}, []
        for name, text in zip(columns, fields, strict=True):
            row[name], problem = _csv_cell(name, text)
            if problem:
                problems.append(problem)
        p0, p1 = (row.get("x0"), row.get("y0")), (row.get("x1"), row.get("y1"))
        if not problems and p0 == p1:
            problems.append(
                f"zero-length segment: (x0, y0) = (x1, y1) = "
                f"({_exact(p0[0])}, {_exact(p0[1])})"
            )
        bad += [f"{file} line {number}: {p}" for p in problems]
        if not problems:
            rows.append((number, row))
    return rows, bad


def _group_rows(rows: list) -> list[tuple[str, list]]:
    """Rows grouped by the ``fracture`` column in order of first appearance; a
    row without a fracture id is a fracture of its own."""
    groups: dict[object, list] = {}
    for number, row in rows:
        fid = row.get("fracture")
        groups.setdefault(fid if fid is not None else ("row", number), []).append(
            (number, row)
        )
    return [(k if isinstance(k, str) else None, g) for k, g in groups.items()]


def _lines_text(group: list) -> str:
    """``line 4`` or ``lines 4, 5, 9``."""
    numbers = [str(n) for n, _ in group]
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
                f"{file} line {number}: fracture {fid!r} continues at "
                f"({_exact(start[0])}, {_exact(start[1])}) but its segment on line "
                f"{prev} ends at ({_exact(points[-1][0])}, {_exact(points[-1][1])}); "
                "the rows of a fracture must chain end to start"
            )
        points.append((row["x1"], row["y1"]))
    return (None if bad else np.array(points, dtype=np.float64)), bad


def _group_properties(group: list, fid, file: Path, defaults: dict):
    """(properties, problems): per-row values (equal across a fracture's rows),
    else the [network] defaults; friction must come from one or the other."""
    props, bad = {}, []
    for name in PROPERTY_RULES:
        given = [(n, r[name]) for n, r in group if r.get(name) is not None]
        values = {v for _, v in given}
        if len(values) > 1:
            (n1, v1), (n2, v2) = given[0], next(g for g in given if g[1] != given[0][1])
            bad.append(
                f"{file} lines {n1} and {n2}: fracture {fid!r} has {name} "
                f"{_fmt(v1)} and {_fmt(v2)}; its rows must agree"
            )
        props[name] = given[0][1] if given else defaults.get(name)
    if props["friction"] is None and not bad:
        bad.append(
            f"{file} {_lines_text(group)}: no friction: give it in a friction "
            "column or as network.friction"
        )
    return props, bad


def _read_segments_file(
    table: _Table, grid: _Grid | None, folder: Path, defaults: dict
) -> list[tuple[np.ndarray, dict, str]] | None:
    """``network.file``: [(points, properties, source)] per fracture, or None."""
    name = table.string("file")
    if name is None:
        return None
    file, key = folder / name, table.key("file")
    try:
        lines = file.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        table.error(
            "file", f"cannot read {file}: {getattr(exc, 'strerror', None) or exc}"
        )
        return None
    columns, bad = _csv_header(lines[0] if lines else None, file)
    if bad:
        _add_capped(table.problems, key, bad)
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
        label = f"fracture {fid!r}, " if fid is not None else ""
        out.append((points, props, f"network.file {name}: {label}{_lines_text(group)}"))
    if not rows and not bad:
        bad.append(f"{file}: no segment rows after the header")
    if len(out) > MAX_NETWORK_FRACTURES:
        bad.append(f"{file}: {len(out)} fractures, more than {MAX_NETWORK_FRACTURES}")
    _add_capped(table.problems, key, bad)
    return None if bad else out


def _shape_problem(points: np.ndarray, grid: _Grid | None) -> str | None:
    """Self-intersection, or a fracture wholly outside the domain."""
    pair = _self_intersection(points)
    if pair is not None:
        i, j = pair
        return f"self-intersecting polyline: segments {i} and {j} touch or cross"
    if grid is None:
        return None
    lo = grid.origin
    hi = (lo[0] + grid.size[0], lo[1] + grid.size[1])
    if not any(
        _segment_meets_box(a, b, lo, hi)
        for a, b in zip(points[:-1], points[1:], strict=True)
    ):
        return (
            f"lies outside the domain [{_fmt(lo[0])}, {_fmt(hi[0])}] x "
            f"[{_fmt(lo[1])}, {_fmt(hi[1])}]"
        )
    return None


# --------------------------------------------------------------------------- #
# [network.generate]
# --------------------------------------------------------------------------- #


def _only_with(table: _Table, kind: str, used: tuple[str, ...]) -> None:
    """Keys of the law's table that this distribution does not use."""
    for name in table.data:
        if name != "distribution" and name not in used:
            table.error(name, f'not used with distribution = "{kind}"')


def _read_orientation(parent: _Table) -> dfn.Orientation | None:
    """``orientation = { distribution = .., mean = .., kappa | std = .. }`` [deg]."""
    table = parent.table("orientation", ORIENTATION_KEYS, required=True)
    if table is None:
        return None
    start = len(table.problems)
    kind = table.choice("distribution", dfn.ORIENTATIONS)
    if kind is None:
        return None
    used = {"uniform": (), "von_mises": ("mean", "kappa"), "normal": ("mean", "std")}
    _only_with(table, kind, used[kind])
    values = {}
    if kind != "uniform":
        values["mean"] = table.number("mean")
    if kind == "von_mises":
        values["kappa"] = table.number("kappa", rule=Range(0.0, 1.0e6))
    if kind == "normal":
        values["std"] = table.number("std", rule=Range(0.0, 360.0))
    if len(table.problems) > start:
        return None
    return dfn.Orientation(kind=kind, **values)


def _read_length(parent: _Table) -> dfn.LengthLaw | None:
    """``length = { distribution = .., ... }`` [m]."""
    table = parent.table("length", LENGTH_KEYS, required=True)
    if table is None:
        return None
    start = len(table.problems)
    kind = table.choice("distribution", dfn.LENGTHS)
    if kind is None:
        return None
    used = {
        "constant": ("value",),
        "power_law": ("exponent", "min", "max"),
        "lognormal": ("median", "sigma", "min", "max"),
    }
    _only_with(table, kind, used[kind])
    if kind == "constant":
        value = table.number("value", rule=_POSITIVE)
        return None if value is None else dfn.LengthLaw(kind=kind, value=value)
    if kind == "power_law":  # min and max required; optional truncation otherwise
        lmin, lmax = (
            table.number("min", rule=_POSITIVE),
            table.number("max", rule=_POSITIVE),
        )
    else:
        lmin, lmax = (
            table.number("min", None, _POSITIVE),
            table.number("max", None, _POSITIVE),
        )
    if lmin is not None and lmax is not None and lmax <= lmin:
        table.error("max", f"must be > min = {_fmt(lmin)}, got {lmax!r}")
    if kind == "power_law":
        exponent = table.number("exponent", rule=Range(-10.0, 10.0))
        if len(table.problems) > start:
            return None
        return dfn.LengthLaw(kind=kind, exponent=exponent, lmin=lmin, lmax=lmax)
    median = table.number("median", rule=_POSITIVE)
    sigma = table.number("sigma", rule=Range(0.0, 10.0, lo_open=True))
    if len(table.problems) > start:
        return None
    law = dfn.LengthLaw(kind=kind, median=median, sigma=sigma, lmin=lmin, lmax=lmax)
    mass = _lognormal_mass(law)
    if mass < MIN_LOGNORMAL_MASS:
        table.error(
            None,
            f"[min, max] holds only {mass:.2g} of the lognormal's probability; "
            f"at least {MIN_LOGNORMAL_MASS:g} is needed",
        )
        return None
    return law


def _lognormal_mass(law: dfn.LengthLaw) -> float:
    """P(min <= L <= max) of a lognormal law."""

    def cdf(x):
        return 0.5 * (
            1.0 + math.erf((math.log(x / law.median)) / (law.sigma * math.sqrt(2)))
        )

    hi = cdf(law.lmax) if law.lmax is not None else 1.0
    lo = cdf(law.lmin) if law.lmin is not None else 0.0
    return hi - lo


def _read_sets(table: _Table) -> tuple[dfn.FractureSet, ...] | None:
    """``orientation`` + ``length`` (one set), or ``sets = [{weight, orientation,
    length}, ...]``."""
    single = [k for k in ("orientation", "length") if table.has(k)]
    if table.has("sets"):
        if single:
            table.error("sets", f"give either sets or {' and '.join(single)}, not both")
            return None
        value = table.data["sets"]
        if not isinstance(value, list) or not value:
            table.error(
                "sets", f"expected a non-empty array of tables, got {_show(value)}"
            )
            return None
        out = []
        for i, item in enumerate(value):
            if not isinstance(item, dict):
                table.error(f"sets[{i}]", f"expected a table, got {_show(item)}")
                out.append(None)
                continue
            sub = _Table(item, table.key(f"sets[{i}]"), table.problems, SET_KEYS)
            weight = sub.number("weight", rule=_POSITIVE)
            orientation, length = _read_orientation(sub), _read_length(sub)
            ok = None not in (weight, orientation, length)
            out.append(
                dfn.FractureSet(weight=weight, orientation=orientation, length=length)
                if ok
                else None
            )
        return None if any(s is None for s in out) else tuple(out)
    orientation, length = _read_orientation(table), _read_length(table)
    if orientation is None or length is None:
        return None
    return (dfn.FractureSet(weight=1.0, orientation=orientation, length=length),)


def _read_region(table: _Table) -> tuple[float, float, float, float] | None | bool:
    """``region = [[x0, y0], [x1, y1]]`` (lower-left, upper-right) -> (x0, x1, y0, y1);
    None when not given, False when invalid."""
    if not table.has("region"):
        return None
    value = table.data["region"]
    corners = value if isinstance(value, list) and len(value) == 2 else None
    if corners is None or not all(
        isinstance(c, list)
        and len(c) == 2
        and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in c
        )
        for c in corners
    ):
        table.error(
            "region",
            f"expected [[x0, y0], [x1, y1]] (lower-left and upper-right corners, m), "
            f"got {_show(value)}",
        )
        return False
    (x0, y0), (x1, y1) = corners
    if not (x1 > x0 and y1 > y0):
        table.error(
            "region",
            f"upper-right corner must be above and right of lower-left, got {value}",
        )
        return False
    return (float(x0), float(x1), float(y0), float(y1))


def _read_count(table: _Table) -> dict | None:
    """Exactly one of count, p20 [1/m^2], p21 [m/m^2]."""
    given = [k for k in ("count", "p20", "p21") if table.has(k)]
    if len(given) != 1:
        table.error(
            None if given else "count",
            "give exactly one of count, p20 (fractures per m^2) or p21 "
            f"(fracture length per m^2), got {', '.join(given) if given else 'none'}",
        )
        return None
    name = given[0]
    if name == "count":
        value = table.integer("count", rule=Range(0, MAX_NETWORK_FRACTURES))
    else:
        value = table.number(name, rule=_POSITIVE)
    return None if value is None else {name: value}


def _read_generate(table: _Table) -> dfn.DfnParams | None:
    """``[network.generate]`` -> DfnParams (validated, not yet realized)."""
    start = len(table.problems)
    seed = table.integer("seed", rule=_NON_NEGATIVE)
    count = _read_count(table)
    region = _read_region(table)
    sets = _read_sets(table)
    intersections = table.choice("intersections", dfn.INTERSECTIONS, "allow")
    spacing = table.number("min_spacing", 0.0, _NON_NEGATIVE)
    if spacing and intersections != "avoid":
        table.error("min_spacing", 'only used with intersections = "avoid"')
    outside = table.choice("outside", dfn.OUTSIDE, "clip")
    min_length = table.number("min_length", 0.0, _NON_NEGATIVE)
    if len(table.problems) > start or region is False:
        return None
    return dfn.DfnParams(
        seed=seed,
        region=region,
        sets=sets,
        intersections=intersections,
        min_spacing=spacing,
        outside=outside,
        min_length=min_length,
        **count,
    )


def _realize(
    table: _Table, params: dfn.DfnParams, grid: _Grid, existing: np.ndarray
) -> dfn.Network | None:
    """The network of ``params`` in the domain; a problem if it does not fit."""
    (x0, y0), (w, h) = grid.origin, grid.size
    box = (x0, x0 + w, y0, y0 + h)
    wanted = dfn.resolve_count(params, box)
    if wanted > MAX_NETWORK_FRACTURES:
        table.error(
            None, f"asks for {wanted} fractures, more than {MAX_NETWORK_FRACTURES}"
        )
        return None
    network = dfn.generate(params, box, existing)
    if network.placed < network.requested:
        table.error(
            None,
            f"placed only {network.placed} of {network.requested} fractures in "
            f"{network.candidates} random draws (intersections = "
            f'"{params.intersections}", min_spacing = {_fmt(params.min_spacing)} m, '
            f'outside = "{params.outside}", min_length = {_fmt(params.min_length)} m); '
            "ask for fewer or shorter fractures, or relax these rules",
        )
        return None
    return network


# --------------------------------------------------------------------------- #
# [network]
# --------------------------------------------------------------------------- #


def network_table(root: _Table) -> _Table | None:
    """The [network] table reader (None if not a table)."""
    return root.table("network", NETWORK_KEYS)


def _segments_of(polylines) -> np.ndarray:
    """(m, 2, 2) segments of a list of (k, 2) polylines."""
    parts = [np.stack([p[:-1], p[1:]], axis=1) for p in polylines]
    return np.concatenate(parts) if parts else np.zeros((0, 2, 2))


def _read_network(
    root: _Table, grid: _Grid | None, folder: Path, inline: tuple
) -> tuple[FractureSpec, ...] | None:
    """``[network]``: the CSV file's fractures, then the generated ones,
    numbered after the ``inline`` [[fractures]] (which, with the file's,
    the generated ones keep away from under intersections = "avoid")."""
    first_index = len(inline)
    table = network_table(root)
    if table is None:
        return None
    if not table.present:
        return ()
    start = len(table.problems)
    defaults = {
        name: table.number(name, None, rule) for name, rule in PROPERTY_RULES.items()
    }
    tip, radius = _read_tip(table)
    if not table.has("file") and not table.has("generate"):
        table.error(None, 'expected file = "segments.csv" and/or a generate table')
    found: list[tuple[np.ndarray, dict, str]] = []
    if table.has("file"):
        found += _read_segments_file(table, grid, folder, defaults) or []
    if table.has("generate"):
        gen = table.table("generate", GENERATE_KEYS)
        params = _read_generate(gen) if gen is not None else None
        if (
            params is not None
            and defaults["friction"] is None
            and not table.has("friction")
        ):
            table.error(
                "friction",
                "required key missing: the generated fractures take it from here",
            )
        if params is not None and grid is not None and len(table.problems) == start:
            others = [f.points for f in inline] + [p for p, _, _ in found]
            network = _realize(gen, params, grid, _segments_of(others))
            for k, seg in enumerate(network.segments if network is not None else ()):
                found.append(
                    (
                        seg,
                        defaults,
                        f"network.generate #{k} (set {network.set_index[k]})",
                    )
                )
    if len(table.problems) > start:
        return None
    return tuple(
        FractureSpec(
            index=first_index + k,
            points=_frozen(points),
            friction=props["friction"],
            cohesion=props["cohesion"] if props["cohesion"] is not None else 0.0,
            kn=props["kn"],
            kt=props["kt"],
            tip=tip,
            tip_radius=radius,
            source=source,
        )
        for k, (points, props, source) in enumerate(found)
    )
