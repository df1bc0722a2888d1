"""The ``[vary]`` table of a sweep file: key paths, value lists and ranges.

Private helper of :mod:`xfemslip.studies.sweep` (which re-exports the public names):
``parse_key_path`` / ``set_key_path`` address a case key such as
``fractures[0].angle``; ``expand_range`` turns ``{start, stop, step|num}``
into values; ``read_vary`` checks the whole table and records each problem
with its key path.
"""

from __future__ import annotations

import math
import re

from xfemslip.case.quantities import key_value
from xfemslip.case.tables import Table, show

RANGE_KEYS = ("start", "stop", "step", "num")
MAX_CASES = 10_000  # a typo in a range must not start a million runs
RANGE_RTOL = 1e-9  # stop is on the grid when within this many steps of it
MAX_SHOWN_KEYS = 6  # keys listed in a message about all of them

_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_-]*)((?:\[\d+\])*)$")


# --------------------------------------------------------------------------- #
# Key paths
# --------------------------------------------------------------------------- #


def parse_key_path(key: str) -> list[str | int] | None:
    """``"fractures[0].angle"`` -> ``["fractures", 0, "angle"]``; None if malformed."""
    parts: list[str | int] = []
    for segment in key.split("."):
        match = _SEGMENT.match(segment)
        if match is None:
            return None
        parts.append(match.group(1))
        parts += [int(i) for i in re.findall(r"\[(\d+)\]", match.group(2))]
    return parts


def key_parts(key: str) -> list[str | int]:
    """The parts of a key path that parse_key_path has accepted."""
    parts = parse_key_path(key)
    if parts is None:
        raise ValueError(f"malformed key path {key!r}")
    return parts


def _where(parts: list[str | int], upto: int) -> str:
    """Key path text of ``parts[:upto]``."""
    text = ""
    for part in parts[:upto]:
        text += f"[{part}]" if isinstance(part, int) else f".{part}" if text else part
    return text or "the case"


def set_key_path(document: dict, parts: list[str | int], value) -> str | None:
    """Set ``value`` at ``parts`` in ``document`` (in place); a message if it
    cannot.  Missing tables on the way are created; array items must exist."""
    node = document
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(part, int):
            if not isinstance(node, list):
                return f"{_where(parts, depth)} is not an array in the base case"
            if part >= len(node):
                return (
                    f"{_where(parts, depth)} has {len(node)} item(s) in the base "
                    f"case, so index {part} does not exist"
                )
        elif not isinstance(node, dict):
            return f"{_where(parts, depth)} is not a table in the base case"
        elif not last and part not in node:
            if isinstance(parts[depth + 1], int):
                return f"the base case has no {_where(parts, depth + 1)}"
            node[part] = {}
        if last:
            node[part] = value
        else:
            node = node[part]
    return None


# --------------------------------------------------------------------------- #
# [vary]
# --------------------------------------------------------------------------- #


def _flatten_vary(table: dict, prefix: str = "") -> list[tuple[str, object]]:
    """(key path, spec) pairs; nested tables (``material.E = [...]``) joined by
    dots.  A table with a key of RANGE_KEYS is a range, not a nesting level."""
    out = []
    for name, value in table.items():
        key = f"{prefix}.{name}" if prefix else name
        if isinstance(value, dict) and value and not set(value) & set(RANGE_KEYS):
            out += _flatten_vary(value, key)
        else:
            out.append((key, value))
    return out


def _number(value, key: str, problems: list) -> float | int | None:
    """A finite TOML number (not a boolean) that a float can hold."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        problems.append((key, f"expected a number, got {show(value)}"))
        return None
    if not _fits_float(value):
        problems.append((key, f"must be finite, got {show(value)}"))
        return None
    return value


def _fits_float(value) -> bool:
    """A finite float, or an integer within the float range."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _count_text(count) -> str:
    """A count for a message: exact up to 1e12, else like 1.23e+45."""
    return str(count) if count <= 10**12 else f"{float(count):.3g}"


def _step_count(start, stop, step) -> float:
    """Number of values start, start + step, ... up to stop (inf when the
    count itself overflows, e.g. step = 1e-310 over a span of 1)."""
    try:
        return math.floor((stop - start) / step + RANGE_RTOL) + 1
    except OverflowError:
        return math.inf


def expand_range(spec: dict, key: str, problems: list) -> list | None:
    """``{start, stop, step}`` or ``{start, stop, num}`` -> list of values."""
    unknown = [k for k in spec if k not in RANGE_KEYS]
    if unknown:
        problems.append(
            (
                key,
                f"unknown range key {unknown[0]!r}; a range has start, stop and "
                "step or num",
            )
        )
        return None
    if "start" not in spec or "stop" not in spec or ("step" in spec) == ("num" in spec):
        problems.append(
            (
                key,
                "a range needs start, stop and exactly one of step or num, got "
                "keys " + ", ".join(sorted(spec)),
            )
        )
        return None
    start = _number(spec["start"], f"{key}.start", problems)
    stop = _number(spec["stop"], f"{key}.stop", problems)
    if start is None or stop is None:
        return None
    if not _fits_float(stop - start):
        problems.append(
            (
                key,
                f"stop - start = {stop!r} - {start!r} overflows the float range; "
                "no range of values can span it",
            )
        )
        return None
    if "num" in spec:
        num = spec["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            problems.append(
                (f"{key}.num", f"expected an integer >= 1, got {show(num)}")
            )
            return None
        if num > MAX_CASES:
            problems.append((f"{key}.num", f"must be <= {MAX_CASES}, got {num}"))
            return None
        if num == 1:
            return [start]
        return [start + (stop - start) * i / (num - 1) for i in range(num)]
    step = _number(spec["step"], f"{key}.step", problems)
    if step is None:
        return None
    if step == 0 or (stop - start) / step < 0:
        problems.append(
            (
                f"{key}.step",
                f"must be non-zero and lead from start = {start} to "
                f"stop = {stop}, got {step}",
            )
        )
        return None
    count = _step_count(start, stop, step)
    if count > MAX_CASES:
        problems.append(
            (key, f"gives {_count_text(count)} values, more than {MAX_CASES}")
        )
        return None
    as_int = all(isinstance(v, int) for v in (start, stop, step))
    return [
        start + i * step if as_int else float(start + i * step)
        for i in range(int(count))
    ]


def _in_si(spec: dict, key: str, where: str, problems: list) -> dict | None:
    """A range's start, stop and step written with units ("-40 MPa") in the
    unit of the case key they vary; None after recording a unit the key
    refuses."""
    out = dict(spec)
    for name in ("start", "stop", "step"):
        if name in out:
            value, why = key_value(key, out[name])
            if why is not None:
                problems.append((f"{where}.{name}", why))
                return None
            out[name] = value
    return out


def _values_in_si(values: list, key: str, where: str, problems: list) -> list | None:
    """The listed values, those written with units ("5 GPa") in the unit of
    the case key (so the parameters, case names and summary.csv hold SI
    numbers); None after recording a unit the key refuses."""
    out = []
    for i, item in enumerate(values):
        value, why = key_value(key, item)
        if why is not None:
            problems.append((f"{where}[{i}]", why))
            return None
        out.append(value)
    return out


def read_vary(root: Table, combine: str | None) -> list[tuple[str, list]]:
    """[vary] -> [(key path, values)], checked: paths, lists, ranges, overlaps."""
    table = root.table("vary", None, required=True)
    if table is None:
        return []
    if not table.data:
        table.error(None, "expected at least one key path = values")
        return []
    out = []
    for key, spec in _flatten_vary(table.data):
        where = f'vary."{key}"'
        if parse_key_path(key) is None:
            root.problems.append(
                (
                    where,
                    "not a key path; expected dotted case keys with optional "
                    "[index], e.g. fractures[0].angle",
                )
            )
            continue
        if isinstance(spec, dict):
            si = _in_si(spec, key, where, root.problems)
            values = None if si is None else expand_range(si, where, root.problems)
        elif isinstance(spec, list) and spec:
            values = _values_in_si(spec, key, where, root.problems)
        else:
            root.problems.append(
                (
                    where,
                    "expected a non-empty array of values or a range table "
                    f"{{start, stop, step|num}}, got {show(spec)}",
                )
            )
            values = None
        if values is not None:
            out.append((key, values))
    _check_overlaps(out, root.problems)
    if combine == "zip" and len({len(v) for _, v in out}) > 1:
        sizes = ", ".join(f"{k} has {len(v)}" for k, v in out[:MAX_SHOWN_KEYS])
        more = ", ..." if len(out) > MAX_SHOWN_KEYS else ""
        root.problems.append(("combine", f'"zip" needs equal lengths: {sizes}{more}'))
    else:
        _check_count(out, combine, root.problems)
    return out


def case_count(vary: list[tuple[str, list]], combine: str | None) -> int:
    """Number of cases of ``vary``, computed without expanding it."""
    if not vary:
        return 0
    if combine == "zip":
        return min(len(values) for _, values in vary)
    return math.prod(len(values) for _, values in vary)


def _check_count(vary: list, combine: str | None, problems: list) -> None:
    """Refuse more than MAX_CASES cases before any is built."""
    count = case_count(vary, combine)
    if count <= MAX_CASES:
        return
    sizes = " x ".join(f"{len(v)} ({k})" for k, v in vary[:MAX_SHOWN_KEYS])
    if len(vary) > MAX_SHOWN_KEYS:
        sizes += f" x ... ({len(vary)} keys)"
    problems.append(
        (
            "vary",
            f"gives {_count_text(count)} cases ({sizes}), more than {MAX_CASES}",
        )
    )


def _check_overlaps(vary: list, problems: list) -> None:
    """Two keys where one contains the other (``fractures[0]`` and
    ``fractures[0].angle``, or the same key twice) would depend on their
    order: refused.  Each key looks up its own prefixes among the keys before
    and after it, so the check is linear in the number of keys."""
    first: dict[tuple, str] = {}
    for key, _ in vary:
        parts = tuple(key_parts(key))
        if parts in first:
            problems.append((f'vary."{key}"', f'overlaps vary."{first[parts]}"'))
        first.setdefault(parts, key)
    for key, _ in vary:
        parts = tuple(key_parts(key))
        problems.extend(
            (f'vary."{key}"', f'overlaps vary."{first[parts[:n]]}"')
            for n in range(1, len(parts))
            if parts[:n] in first
        )
