"""Typed reading of TOML tables: value checks, message helpers, ``Table``.

Each check returns the clean value, or None after recording a
``(key path, message)`` problem in the caller's list.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence
from typing import Any, NamedTuple, TypeVar

import numpy as np


class Range(NamedTuple):
    """Allowed interval of a number; ``None`` = unbounded on that side."""

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False


class Option(NamedTuple):
    """One ``[solver]`` option: the single source for validation and docs."""

    name: str
    type: type
    default: Any
    doc: str
    allowed: Range | tuple[str, ...]


REQUIRED = object()  # sentinel default: the key must be given
MAX_SUGGESTIONS = 20  # unknown keys of one table that get a 'did you mean'

POSITIVE = Range(0.0, lo_open=True)
NON_NEGATIVE = Range(0.0)
FINITE = Range()  # any finite number (every number of a case is finite)
POISSON = Range(0.0, 0.5, hi_open=True)  # nu of [material] and [reservoir]
BIOT = Range(0.0, 1.0, lo_open=True)  # pore_pressure.biot
# |x|, |y| of every point of a case [m]: the geometry squares distances, which
# must stay finite (1e150**2 = 1e300); a kilometre-scale model is at 1e3.
MAX_COORDINATE = 1e150
COORDINATE = Range(-MAX_COORDINATE, MAX_COORDINATE)


# --------------------------------------------------------------------------- #
# Value checks: each returns the clean value, or None after recording a problem
# --------------------------------------------------------------------------- #


def show(value: Any) -> str:
    """Type and value of a TOML value, for 'got ...' in messages."""
    if isinstance(value, bool):
        return f"boolean {'true' if value else 'false'}"
    if isinstance(value, int):
        return f"integer {value}"
    if isinstance(value, float):
        return f"float {value!r}"
    if isinstance(value, str):
        text = value if len(value) <= 40 else value[:37] + "..."
        return f"string {text!r}"
    if isinstance(value, list):
        return f"array of {len(value)} item{'' if len(value) == 1 else 's'}"
    if isinstance(value, dict):
        return "table"
    return f"{type(value).__name__} {value}"


def exact(value: float) -> str:
    """Shortest text that reads back to the same float (numpy scalars too)."""
    return repr(float(value))


def fmt(value: float) -> str:
    """Short form of a number for messages and summaries."""
    return str(value) if isinstance(value, int) else f"{value:.6g}"


def range_problem(value: float, rule: Range | None, label: str) -> str | None:
    """Message if ``value`` is outside ``rule``, else None."""
    if rule is None:
        return None
    below = rule.lo is not None and (
        value <= rule.lo if rule.lo_open else value < rule.lo
    )
    above = rule.hi is not None and (
        value >= rule.hi if rule.hi_open else value > rule.hi
    )
    if not (below or above):
        return None
    lo_op, hi_op = ("<" if rule.lo_open else "<="), ("<" if rule.hi_open else "<=")
    if rule.lo is not None and rule.hi is not None:
        text = f"must satisfy {fmt(rule.lo)} {lo_op} {label} {hi_op} {fmt(rule.hi)}"
    elif rule.lo is not None:
        text = f"must be {'>' if rule.lo_open else '>='} {fmt(rule.lo)}"
    elif rule.hi is not None:
        text = f"must be {hi_op} {fmt(rule.hi)}"
    else:
        return None
    return f"{text}, got {value!r}"


def check_number(
    value: Any, key: str, problems: list, rule: Range | None = None, label: str = ""
) -> float | None:
    """A finite float (TOML integers accepted, booleans not) within ``rule``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        problems.append((key, f"expected a number, got {show(value)}"))
        return None
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        problems.append((key, f"must be finite, got {number!r}"))
        return None
    message = range_problem(number, rule, label or key.rsplit(".", 1)[-1])
    if message:
        problems.append((key, message))
        return None
    return number


def check_integer(
    value: Any, key: str, problems: list, rule: Range | None = None, label: str = ""
) -> int | None:
    """A TOML integer (not a float, not a boolean) within ``rule``."""
    if isinstance(value, bool) or not isinstance(value, int):
        problems.append((key, f"expected an integer, got {show(value)}"))
        return None
    message = range_problem(value, rule, label or key.rsplit(".", 1)[-1])
    if message:
        problems.append((key, message))
        return None
    return value


# What a key a user tries means in this case format, where its name alone
# would not say (an unknown key's message adds it).
KEY_HINTS = {
    "layers": "rock units are [[units]] tables (layers between horizons, "
    "polygons, or layers displaced by a fault)",
    "gravity": "gravity = g goes in loading.initial_stress, with the units' densities",
    "density": "a density goes in [material] or in a [[units]] table",
    "gradient_yy": "depth gradients go in loading.initial_stress with a datum",
    "gradient_xx": "depth gradients go in loading.initial_stress with a datum",
}


def suggest(word: str, allowed: tuple[str, ...]) -> str:
    """'; did you mean ...?' or the list of allowed words (pypa/build _find_typo),
    or what the key means in this format (KEY_HINTS)."""
    if word in KEY_HINTS and word not in allowed:
        return f" ({KEY_HINTS[word]})"
    close = difflib.get_close_matches(word, allowed, n=1)
    if close:
        return f"; did you mean {close[0]!r}?"
    return "; allowed: " + ", ".join(allowed)


def check_choice(
    value: Any, key: str, problems: list, choices: tuple[str, ...]
) -> str | None:
    """One of the strings ``choices``."""
    if not isinstance(value, str):
        allowed = ", ".join(f'"{c}"' for c in choices)
        problems.append((key, f"expected one of {allowed}, got {show(value)}"))
        return None
    if value not in choices:
        allowed = ", ".join(f'"{c}"' for c in choices)
        close = difflib.get_close_matches(value, choices, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        problems.append((key, f"must be one of {allowed}, got {value!r}{hint}"))
        return None
    return value


T = TypeVar("T")


def complete(items: Sequence[T | None]) -> list[T] | None:
    """The items, or None when one is None (its problem is recorded)."""
    out = [item for item in items if item is not None]
    return out if len(out) == len(items) else None


def check_vector(value: Any, key: str, problems: list, n: int, check) -> tuple | None:
    """An array of exactly ``n`` items, each passed through ``check(item, key)``."""
    if not isinstance(value, list) or len(value) != n:
        problems.append((key, f"expected an array of {n} numbers, got {show(value)}"))
        return None
    items = [check(item, f"{key}[{i}]") for i, item in enumerate(value)]
    return None if any(item is None for item in items) else tuple(items)


def frozen(values) -> np.ndarray:
    """A read-only float64 copy (specs are immutable, arrays included)."""
    array = np.array(values, dtype=np.float64)
    array.setflags(write=False)
    return array


class Table:
    """Typed access to one TOML table; records every problem with its key path."""

    def __init__(
        self,
        data: dict,
        path: str,
        problems: list,
        allowed: tuple[str, ...] | None = None,
        present: bool = True,
    ):
        self.data = data
        self.path = path
        self.problems = problems
        self.present = present  # False: an optional table the file leaves out
        where = f" in [{path}]" if path else ""
        unknown = [n for n in data if allowed is not None and n not in allowed]
        for k, name in enumerate(unknown):
            # a suggestion for the first few; thousands of unknown keys are
            # a wrong file, and difflib on each would take seconds
            hint = suggest(name, allowed or ()) if k < MAX_SUGGESTIONS else ""
            self.error(name, f"unknown key {name!r}{where}{hint}")

    def key(self, name: str | None) -> str:
        """Key path of ``name`` in this table (the table's own path for None)."""
        if name is None:
            return self.path
        return f"{self.path}.{name}" if self.path else name

    def error(self, name: str | None, message: str) -> None:
        """Record a problem at ``name`` (None: the table itself)."""
        self.problems.append((self.key(name), message))

    def has(self, name: str) -> bool:
        """Whether the file gives ``name`` in this table."""
        return name in self.data

    def _get(self, name: str, default: Any, hint: str = "") -> tuple[bool, Any]:
        """(found, value); a missing required key is recorded."""
        if name in self.data:
            return True, self.data[name]
        if default is REQUIRED:
            self.error(name, "required key missing" + hint)
            return False, None
        return False, default

    def number(self, name, default=REQUIRED, rule=None, hint=""):
        """A finite number (float) within ``rule``."""
        found, value = self._get(name, default, hint)
        if not found:
            return value
        return check_number(value, self.key(name), self.problems, rule)

    def integer(self, name, default=REQUIRED, rule=None):
        """An integer within ``rule``."""
        found, value = self._get(name, default)
        if not found:
            return value
        return check_integer(value, self.key(name), self.problems, rule)

    def choice(self, name, choices, default=REQUIRED):
        """One of the strings ``choices``."""
        found, value = self._get(name, default)
        if not found:
            return value
        return check_choice(value, self.key(name), self.problems, choices)

    def boolean(self, name, default=REQUIRED):
        """true or false."""
        found, value = self._get(name, default)
        if found and not isinstance(value, bool):
            self.error(name, f"expected true or false, got {show(value)}")
            return None
        return value

    def string(self, name, default=REQUIRED):
        """A non-empty string."""
        found, value = self._get(name, default)
        if found and (not isinstance(value, str) or not value.strip()):
            self.error(name, f"expected a non-empty string, got {show(value)}")
            return None
        return value

    def numbers(self, name, n, default=REQUIRED, rule=None, hint=""):
        """A fixed-length array of finite numbers, e.g. ``size = [1.0, 1.0]``."""
        found, value = self._get(name, default, hint)
        if not found:
            return value

        def check(item, key):
            return check_number(item, key, self.problems, rule)

        return check_vector(value, self.key(name), self.problems, n, check)

    def table(self, name, allowed, required=False) -> Table | None:
        """Sub-table reader; an absent optional table reads as empty."""
        if name not in self.data:
            if required:
                self.error(name, "required key missing")
                return None
            return Table({}, self.key(name), self.problems, present=False)
        value = self.data[name]
        if not isinstance(value, dict):
            self.error(name, f"expected a table, got {show(value)}")
            return None
        return Table(value, self.key(name), self.problems, allowed)
