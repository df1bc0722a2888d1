"""``[uncertainty.inputs]`` and ``[[uncertainty.correlation]]`` of a sweep
file: key paths with distribution tables, and the target rank correlation.

Private helper of :mod:`xfemslip.studies.uncertainty`: every problem is
recorded with its key path in the table's problem list (docs/sweep-format.md,
*Uncertainty*).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from xfemslip.case.load import value_rule
from xfemslip.case.tables import Range, Table, range_problem, show
from xfemslip.studies.sampling import KINDS, Distribution, score_correlation
from xfemslip.studies.vary import MAX_CASES, parse_key_path

MAX_INPUTS = 100
# Parameters of each distribution, in the order Distribution.params takes them.
PARAMETERS = {
    "uniform": ("low", "high"),
    "normal": ("mean", "std"),
    "lognormal": ("median", "sigma"),
    "triangular": ("low", "mode", "high"),
    "choice": ("values",),
}
TRUNCATABLE = ("normal", "lognormal")


# --------------------------------------------------------------------------- #
# Distributions
# --------------------------------------------------------------------------- #


def _read_distribution(table: Table) -> Distribution | None:
    """``{ distribution = "...", <parameters>, low/high truncation }``."""
    kind = table.choice("distribution", KINDS)
    if kind is None:
        return None
    names = PARAMETERS[kind]
    allowed = ("distribution", *names)
    if kind in TRUNCATABLE:
        allowed += ("low", "high")
    if kind == "choice":
        allowed += ("weights",)
    start = len(table.problems)
    for name in table.data:
        if name not in allowed:
            table.error(
                name,
                f"not a parameter of a {kind} distribution (it takes "
                f"{', '.join(allowed[1:])})",
            )
    if kind == "choice":
        return _read_choice(table, start)
    params = tuple(table.number(n) for n in names)
    low = table.number("low", None) if kind in TRUNCATABLE else None
    high = table.number("high", None) if kind in TRUNCATABLE else None
    if len(table.problems) > start:
        return None
    why = _parameter_problem(kind, params, low, high)
    if why:
        table.error(None, why)
        return None
    return Distribution(kind, params, low=low, high=high)


def _parameter_problem(kind: str, params: tuple, low, high) -> str:
    """Why the parameters of a continuous distribution are not usable, or ""."""
    if kind == "uniform" and not params[0] < params[1]:
        return f"uniform needs low < high, got low = {params[0]}, high = {params[1]}"
    if kind == "triangular" and not params[0] <= params[1] <= params[2]:
        return "triangular needs low <= mode <= high and low < high"
    if kind == "triangular" and not params[0] < params[2]:
        return "triangular needs low < high"
    if kind == "normal" and not params[1] > 0.0:
        return f"normal needs std > 0, got {params[1]}"
    if kind == "lognormal" and not (params[1] > 0.0 and params[0] != 0.0):
        return "lognormal needs median != 0 and sigma > 0"
    if low is not None and high is not None and not low < high:
        return f"truncation needs low < high, got low = {low}, high = {high}"
    if low is not None or high is not None:
        lo, hi = Distribution(kind, params, low=low, high=high)._cdf_bounds()
        if not hi - lo > 1e-12:  # the truncation holds no probability
            return (
                f"the truncation [{low}, {high}] holds no probability of the "
                f"{kind} distribution"
            )
    return ""


def _read_choice(table: Table, start: int) -> Distribution | None:
    """``{ distribution = "choice", values = [...], weights = [...] }``."""
    values = table.data.get("values")
    if not isinstance(values, list) or not values:
        table.error("values", f"expected a non-empty array, got {show(values)}")
        return None
    if len(values) > MAX_CASES:
        table.error("values", f"at most {MAX_CASES} values, got {len(values)}")
        return None
    numeric = all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
        for v in values
    )
    if not numeric:
        table.error("values", "expected finite numbers")
        return None
    weights = table.data.get("weights")
    if weights is not None:
        ok = (
            isinstance(weights, list)
            and len(weights) == len(values)
            and all(
                isinstance(w, int | float) and not isinstance(w, bool) and w >= 0
                for w in weights
            )
            and sum(weights) > 0
        )
        if not ok:
            table.error(
                "weights",
                f"expected {len(values)} numbers >= 0, not all 0 (one per value)",
            )
            return None
        # relative to the largest: weights of 1e308 must not sum to inf
        top = max(float(w) for w in weights)
        weights = tuple(float(w) / top for w in weights)
    if len(table.problems) > start:
        return None
    return Distribution("choice", tuple(float(v) for v in values), weights=weights)


# The smallest and largest quantile the samplers draw (their uniform numbers
# are multiples of 2^-53 in [0, 1)); a draw of exactly 0 is checked per sample.
TAILS = np.array([2.0**-53, 1.0 - 2.0**-53])


def draw_range(dist: Distribution) -> tuple[float, float]:
    """(lowest, highest) value ``dist`` draws: the quantiles at TAILS, or
    the values a choice can take; inf / NaN where a tail overflows."""
    if dist.kind == "choice":
        w = np.ones(len(dist.params)) if dist.weights is None else dist.weights
        values = np.asarray(dist.params, float)[np.asarray(w) > 0.0]
        return float(values.min()), float(values.max())
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lo, hi = sorted(dist.ppf(TAILS))
    return float(lo), float(hi)


def support_problem(key: str, dist: Distribution) -> str:
    """Why the values ``dist`` draws cannot be used for ``key``, or "": a
    tail that overflows (inf) or, for a lognormal, underflows to 0, or
    every value outside what the case format allows for the key
    (:func:`xfemslip.case.load.value_rule`).  A distribution partly outside
    is kept: its samples outside are refused one by one."""
    lo, hi = draw_range(dist)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return (
            f"the {dist.kind} distribution draws values beyond the largest "
            f"number (from {lo!r} to {hi!r}); narrow it"
        )
    if dist.kind == "lognormal" and (lo == 0.0 or hi == 0.0):
        return (
            "the lognormal distribution draws values that underflow to 0 "
            f"(sigma = {dist.params[1]!r} is too wide); narrow it"
        )
    rule = value_rule(key)
    if rule is None:
        return ""
    below = rule.lo is not None and (hi <= rule.lo if rule.lo_open else hi < rule.lo)
    above = rule.hi is not None and (lo >= rule.hi if rule.hi_open else lo > rule.hi)
    if below or above:
        inside = range_problem(hi if below else lo, rule, key.rsplit(".", 1)[-1])
        return (
            f"every value the {dist.kind} distribution draws ({lo:.6g} to "
            f"{hi:.6g}) is outside what the case format allows: {inside}"
        )
    return ""


def read_inputs(table: Table) -> tuple[list[str], list[Distribution]]:
    """[uncertainty.inputs]: key path -> distribution table."""
    inputs = table.table("inputs", None, required=True)
    if inputs is None:
        return [], []
    if not inputs.data:
        inputs.error(None, "expected at least one key path = distribution table")
        return [], []
    if len(inputs.data) > MAX_INPUTS:
        inputs.error(None, f"at most {MAX_INPUTS} inputs, got {len(inputs.data)}")
        return [], []
    keys, dists = [], []
    for key, value in _flatten(inputs.data):
        where = f'uncertainty.inputs."{key}"'
        if parse_key_path(key) is None:
            inputs.problems.append(
                (where, "not a key path; expected e.g. fractures[0].friction")
            )
            continue
        if not isinstance(value, dict):
            inputs.problems.append(
                (
                    where,
                    "expected a distribution table, e.g. { distribution = "
                    f'"uniform", low = 0.4, high = 0.7 }}, got {show(value)}',
                )
            )
            continue
        dist = _read_distribution(Table(value, where, inputs.problems))
        why = support_problem(key, dist) if dist is not None else ""
        if why:
            inputs.problems.append((where, why))
        elif dist is not None:
            keys.append(key)
            dists.append(dist)
    return keys, dists


def _flatten(table: dict, prefix: str = "") -> list[tuple[str, object]]:
    """(key path, table) pairs; an unquoted ``material.E = {..}`` is nested by
    TOML, a table with ``distribution`` is a leaf."""
    out = []
    for name, value in table.items():
        key = f"{prefix}.{name}" if prefix else name
        if isinstance(value, dict) and value and "distribution" not in value:
            out += _flatten(value, key)
        else:
            out.append((key, value))
    return out


def read_correlation(table: Table, keys: list[str]) -> np.ndarray | None:
    """[[uncertainty.correlation]] -> (d, d) target matrix, or None."""
    if not table.has("correlation"):
        return None
    entries = table.data["correlation"]
    where = table.key("correlation")
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        table.error("correlation", "expected [[uncertainty.correlation]] tables")
        return None
    matrix = np.eye(len(keys))
    for i, entry in enumerate(entries):
        item = Table(entry, f"{where}[{i}]", table.problems, ("keys", "rho"))
        pair = entry.get("keys")
        rho = item.number("rho", rule=Range(-1.0, 1.0, lo_open=True, hi_open=True))
        if (
            not isinstance(pair, list)
            or len(pair) != 2
            or any(k not in keys for k in pair)
            or pair[0] == pair[1]
        ):
            item.error(
                "keys",
                "expected two different keys of [uncertainty.inputs], got "
                f"{show(pair)}",
            )
            continue
        if rho is None:
            continue
        a, b = keys.index(pair[0]), keys.index(pair[1])
        if matrix[a, b] != 0.0:
            item.error("keys", f"the pair {pair} is correlated twice")
            continue
        matrix[a, b] = matrix[b, a] = rho
    scores = score_correlation(matrix)  # what the reordering imposes
    if min(np.linalg.eigvalsh(matrix).min(), np.linalg.eigvalsh(scores).min()) <= 1e-10:
        table.error(
            "correlation",
            "the correlations together are not a valid correlation matrix "
            "(not positive definite, as rank correlations or as the normal-score "
            "correlations 2 sin(pi rho / 6) that induce them)",
        )
        return None
    return None if np.allclose(matrix, np.eye(len(keys))) else matrix
