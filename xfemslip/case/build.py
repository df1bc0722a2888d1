"""Case text from Python values: the one case builder.

Tests, benchmarks and the verification problems describe a case as nested
mappings and lists, exactly as the case file holds it (``case-format.md``),
and turn it into TOML here; the text then goes through ``loads_case`` like any
file, so a built case is validated like a written one.

>>> text = case_text({"mesh": {"elements": [4, 4]}, "domain": {"size": [1.0, 1.0]}})
>>> print(text.splitlines()[0])
[mesh]

Values may be NumPy scalars and arrays, tuples and paths; entries that are
``None`` are left out (so a builder can pass an optional key through), and a
value with no TOML form raises TypeError naming its key path.  Floats keep
their full precision (TOML writes the shortest repr that reads back to the
same double).  A case derived from another one (a shipped file, a base
table) sets dotted keys with ``file_case`` / ``with_keys`` rather than
editing text.
"""

from __future__ import annotations

import datetime
import tomllib
from collections.abc import Mapping
from pathlib import Path, PurePath
from typing import Any

import numpy as np
import tomli_w

__all__ = ["case_text", "file_case", "plain", "stress_table", "with_keys"]


def plain(value: Any, path: str = "") -> Any:
    """``value`` as TOML-ready Python: dicts without None entries, lists for
    tuples and arrays, Python numbers for NumPy scalars, str for paths.

    A value with no TOML form (None inside a list, a complex number, an
    arbitrary object) raises TypeError naming its key path, e.g.
    ``fractures[0].points[1]: None has no TOML form``.
    """
    if isinstance(value, Mapping):
        return {
            str(k): plain(v, f"{path}.{k}" if path else str(k))
            for k, v in value.items()
            if v is not None
        }
    if isinstance(value, np.ndarray):
        return plain(value.tolist(), path)
    if isinstance(value, list | tuple):
        return [plain(v, f"{path}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, np.bool_ | bool):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, PurePath):
        return str(value)
    if isinstance(value, int | float | str):
        return value
    if isinstance(value, datetime.date | datetime.time):
        return value
    raise TypeError(f"{path or 'case'}: {value!r} has no TOML form")


def case_text(table: Mapping[str, Any]) -> str:
    """The TOML text of a case given as a mapping (top-level keys before the
    tables, as TOML requires; ``tomli_w`` orders them)."""
    return tomli_w.dumps(plain(table))


def stress_table(stress) -> dict[str, float] | None:
    """``(xx, yy, xy)`` [Pa] as the ``{ xx, yy, xy }`` table of ``[loading]``
    (None stays None)."""
    if stress is None:
        return None
    xx, yy, xy = (float(v) for v in stress)
    return {"xx": xx, "yy": yy, "xy": xy}


def with_keys(table: Mapping[str, Any], **dotted: Any) -> dict[str, Any]:
    """A deep copy of ``table`` with the values at dotted key paths set,
    ``with_keys(case, **{"mesh.elements": [20, 20]})``; a list index is a
    number in the path (``"fractures.0.friction"``), and None removes the
    key (``{"loading.initial_stress": None}``)."""
    out = plain(table)
    for path, value in dotted.items():
        parts = path.split(".")
        node = out
        for part in parts[:-1]:
            node = (
                node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
            )
        last = parts[-1]
        if isinstance(node, list):
            node[int(last)] = plain(value, path)
        elif value is None:
            node.pop(last, None)
        else:
            node[last] = plain(value, path)
    return out


def file_case(path: str | Path, **dotted: Any) -> dict[str, Any]:
    """The tables of the case file at ``path`` (a shipped case, say), with the
    values at dotted key paths set as ``with_keys`` does; ``case_text`` of
    it is the file with those values changed (its comments are not kept)."""
    with open(path, "rb") as f:
        return with_keys(tomllib.load(f), **dotted)
