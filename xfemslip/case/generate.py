"""``[network.generate]``: the random-network table -> ``dfn.DfnParams``,
and its realization in the domain (read by :mod:`xfemslip.case.network`).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from xfemslip.case.grid import Grid
from xfemslip.case.segments import MAX_NETWORK_FRACTURES
from xfemslip.case.tables import (
    MAX_COORDINATE,
    NON_NEGATIVE,
    POSITIVE,
    Range,
    Table,
    complete,
    fmt,
    show,
)
from xfemslip.geometry import dfn
from xfemslip.geometry.box import Box

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
# A truncated lognormal keeping less than this share of its mass would make
# the resampling loop spin: refused.
MIN_LOGNORMAL_MASS = 1e-4


def _only_with(table: Table, kind: str, used: tuple[str, ...]) -> None:
    """Keys of the law's table that this distribution does not use."""
    for name in table.data:
        if name != "distribution" and name not in used:
            table.error(name, f'not used with distribution = "{kind}"')


def _read_orientation(parent: Table) -> dfn.Orientation | None:
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


def _read_length(parent: Table) -> dfn.LengthLaw | None:
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
        value = table.number("value", rule=POSITIVE)
        return None if value is None else dfn.LengthLaw(kind=kind, value=value)
    if kind == "power_law":  # min and max required; optional truncation otherwise
        lmin, lmax = (
            table.number("min", rule=POSITIVE),
            table.number("max", rule=POSITIVE),
        )
    else:
        lmin, lmax = (
            table.number("min", None, POSITIVE),
            table.number("max", None, POSITIVE),
        )
    if lmin is not None and lmax is not None and lmax <= lmin:
        table.error("max", f"must be > min = {fmt(lmin)}, got {lmax!r}")
    if kind == "power_law":
        exponent = table.number("exponent", rule=Range(-10.0, 10.0))
        if len(table.problems) > start:
            return None
        law = dfn.LengthLaw(kind=kind, exponent=exponent, lmin=lmin, lmax=lmax)
        return _drawable(table, law)
    median = table.number("median", rule=POSITIVE)
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
    return _drawable(table, law)


def _drawable(table: Table, law: dfn.LengthLaw) -> dfn.LengthLaw | None:
    """The law, if its mean and (power law) its inverse CDF at 0 and 1 come
    out finite and in [min, max]; values such as min = 1e-300 with exponent
    2.5 overflow (min**(1 - exponent) = 1e450)."""
    try:
        with np.errstate(all="ignore"):  # an overflow is the answer, not a warning
            mean = dfn.mean_length(law)
            ends = (
                dfn.power_law_ppf(np.array([0.0, 1.0]), law.exponent, *law.bounds)
                if law.kind == "power_law"
                else np.array([mean, mean])
            )
    except (OverflowError, ZeroDivisionError, ValueError):
        mean, ends = math.nan, np.array([math.nan, math.nan])
    lo = law.lmin if law.lmin is not None else 0.0
    hi = law.lmax if law.lmax is not None else math.inf
    slack = 1e-6 * (hi - lo) if math.isfinite(hi - lo) else 0.0
    inside = np.all((ends >= lo - slack) & (ends <= hi + slack))
    if math.isfinite(mean) and np.all(np.isfinite(ends)) and inside:
        return law
    values = ", ".join(
        f"{name} = {getattr(law, attr)!r}"
        for name, attr in (
            ("exponent", "exponent"),
            ("median", "median"),
            ("sigma", "sigma"),
            ("min", "lmin"),
            ("max", "lmax"),
        )
        if table.has(name)
    )
    table.error(
        None,
        f"the {law.kind} law with {values} cannot be drawn in floating point "
        "(its mean length or its inverse CDF overflows); use bounds closer "
        "to the fracture lengths of the domain",
    )
    return None


def _lognormal_mass(law: dfn.LengthLaw) -> float:
    """P(min <= L <= max) of a lognormal law."""

    def cdf(x):
        return 0.5 * (
            1.0 + math.erf((math.log(x / law.median)) / (law.sigma * math.sqrt(2)))
        )

    hi = cdf(law.lmax) if law.lmax is not None else 1.0
    lo = cdf(law.lmin) if law.lmin is not None else 0.0
    return hi - lo


def _read_sets(table: Table) -> tuple[dfn.FractureSet, ...] | None:
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
                "sets", f"expected a non-empty array of tables, got {show(value)}"
            )
            return None
        out: list[dfn.FractureSet | None] = []
        for i, item in enumerate(value):
            if not isinstance(item, dict):
                table.error(f"sets[{i}]", f"expected a table, got {show(item)}")
                out.append(None)
                continue
            sub = Table(item, table.key(f"sets[{i}]"), table.problems, SET_KEYS)
            weight = sub.number("weight", rule=POSITIVE)
            orientation, length = _read_orientation(sub), _read_length(sub)
            if weight is None or orientation is None or length is None:
                out.append(None)
                continue
            out.append(
                dfn.FractureSet(weight=weight, orientation=orientation, length=length)
            )
        sets = complete(out)
        return None if sets is None else tuple(sets)
    orientation, length = _read_orientation(table), _read_length(table)
    if orientation is None or length is None:
        return None
    return (dfn.FractureSet(weight=1.0, orientation=orientation, length=length),)


def _read_region(table: Table) -> Box | Literal[False] | None:
    """``region = [[x0, y0], [x1, y1]]`` (lower-left, upper-right) -> a Box;
    None when not given, False when invalid."""
    if not table.has("region"):
        return None
    value = table.data["region"]
    corners = value if isinstance(value, list) and len(value) == 2 else None
    if corners is None or not all(
        isinstance(c, list)
        and len(c) == 2
        and all(
            isinstance(v, int | float)
            and not isinstance(v, bool)
            and abs(v) <= MAX_COORDINATE  # False for NaN, inf, 1e400
            for v in c
        )
        for c in corners
    ):
        table.error(
            "region",
            "expected [[x0, y0], [x1, y1]] (lower-left and upper-right corners, "
            f"m, within +-{MAX_COORDINATE:g}), got {show(value)}",
        )
        return False
    (x0, y0), (x1, y1) = corners
    if not (x1 > x0 and y1 > y0):
        table.error(
            "region",
            f"upper-right corner must be above and right of lower-left, got {value}",
        )
        return False
    return Box.from_corners(x0, y0, x1, y1)


def _read_count(table: Table) -> dict | None:
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
        value = table.number(name, rule=POSITIVE)
    return None if value is None else {name: value}


def read_generate(table: Table) -> dfn.DfnParams | None:
    """``[network.generate]`` -> DfnParams (validated, not yet realized)."""
    start = len(table.problems)
    seed = table.integer("seed", rule=NON_NEGATIVE)
    count = _read_count(table)
    region = _read_region(table)
    sets = _read_sets(table)
    intersections = table.choice("intersections", dfn.INTERSECTIONS, "allow")
    spacing = table.number("min_spacing", 0.0, NON_NEGATIVE)
    if spacing and intersections != "avoid":
        table.error("min_spacing", 'only used with intersections = "avoid"')
    outside = table.choice("outside", dfn.OUTSIDE, "clip")
    min_length = table.number("min_length", 0.0, NON_NEGATIVE)
    if len(table.problems) > start or region is False or count is None or sets is None:
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


def _expected_count(params: dfn.DfnParams, box: Box) -> float:
    """The count ``dfn.resolve_count`` rounds, as a float that may be inf or
    NaN (p21 = 1e308), so that it is checked before it is converted."""
    if params.count is not None:
        return float(params.count)
    area = (params.region or box).area
    if params.p20 is not None:
        return params.p20 * area
    total = sum(s.weight for s in params.sets)
    mean = sum(s.weight / total * dfn.mean_length(s.length) for s in params.sets)
    assert params.p21 is not None  # exactly one of count, p20, p21
    return params.p21 * area / mean


def realize(
    table: Table, params: dfn.DfnParams, grid: Grid, existing: np.ndarray
) -> dfn.Network | None:
    """The network of ``params`` in the domain; a problem if it does not fit."""
    box = grid.box
    expected = _expected_count(params, box)
    if not expected <= MAX_NETWORK_FRACTURES + 0.5:  # NaN and inf too
        key = next(k for k in ("count", "p20", "p21") if table.has(k))
        table.error(
            key,
            f"asks for {expected:.4g} fractures over the region, more than "
            f"{MAX_NETWORK_FRACTURES}",
        )
        return None
    network = dfn.generate(params, box, existing)
    if network.placed < network.requested:
        table.error(
            None,
            f"placed only {network.placed} of {network.requested} fractures in "
            f"{network.candidates} random draws (intersections = "
            f'"{params.intersections}", min_spacing = {fmt(params.min_spacing)} m, '
            f'outside = "{params.outside}", min_length = {fmt(params.min_length)} m); '
            "ask for fewer or shorter fractures, or relax these rules",
        )
        return None
    return network
