"""The ``[uncertainty]`` table of a sweep file: uncertain inputs -> samples.

A sweep file holds either ``[vary]`` (:mod:`xfemslip.studies.sweep`) or
``[uncertainty]`` (docs/sweep-format.md, *Uncertainty*)::

    name = "slip-probability"
    base = "../depleting_reservoir.toml"

    [uncertainty]
    samples = 2000                 # number of samples
    method = "lhs"                 # or "monte_carlo"
    seed = 1
    evaluate = "screen"            # or "xfem"
    levels = { start = 0.0, stop = -20.0e6, num = 21 }   # dp [Pa], < 0 depletion
    confidence = 0.95              # of the Wilson intervals
    half_width = 0.05              # target half-width: samples needed

    [uncertainty.inputs]
    "fractures[0].friction" = { distribution = "uniform", low = 0.4, high = 0.7 }
    "loading.initial_stress.xx" = { distribution = "normal", mean = -44e6, std = 2e6 }

    [[uncertainty.correlation]]
    keys = ["fractures[0].friction", "loading.initial_stress.xx"]
    rho = 0.3

Every problem is one ``CaseError`` naming the sweep file and the key (exit 2);
the sample count is bounded before anything is drawn.  The samples are drawn
by :func:`xfemslip.studies.sampling.draw` from ``seed``: the same file gives
the same samples.  Evaluating them is :mod:`xfemslip.studies.reactivation`.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import special

from xfemslip.case import loads_case, parse_toml, path_problem, read_text
from xfemslip.case.specs import CaseSpec
from xfemslip.case.tables import Range, Table, show
from xfemslip.errors import CaseError
from xfemslip.studies.inputs import read_correlation, read_inputs
from xfemslip.studies.sampling import Distribution, draw
from xfemslip.studies.sweep import read_base
from xfemslip.studies.vary import (
    MAX_CASES,
    expand_range,
    key_parts,
    set_key_path,
)

UNCERTAINTY_FILE_KEYS = ("name", "base", "uncertainty", "output")
UNCERTAINTY_KEYS = (
    "samples",
    "method",
    "seed",
    "evaluate",
    "levels",
    "confidence",
    "half_width",
    "inputs",
    "correlation",
)
METHODS = ("lhs", "monte_carlo")
EVALUATE = ("screen", "xfem")
# The closed form costs a few hundred ns per sample and fracture segment; a
# million samples is ~1 GB of intermediate arrays at most.
MAX_SCREEN_SAMPLES = 1_000_000
# Every xfem sample is a case folder, as in a sweep.
MAX_XFEM_SAMPLES = MAX_CASES
MAX_SCREEN_CELLS = 50_000_000  # samples x fracture segments
MAX_LEVELS = 1000


@dataclass(frozen=True)
class UncertaintySpec:
    """A validated uncertainty study: the base case, inputs, samples, levels."""

    path: Path  # the sweep file
    name: str
    base: dict  # the base case document (TOML tables)
    base_name: str
    case_path: Path  # the path the cases are loaded as (CSV files relative to it)
    base_spec: CaseSpec  # the base case
    directory: Path
    samples: int
    method: str
    seed: int
    evaluate: str
    levels: np.ndarray  # (n_levels,) pore-pressure changes [Pa], ordered from 0
    confidence: float
    half_width: float
    keys: tuple[str, ...]
    distributions: tuple[Distribution, ...]
    correlation: np.ndarray | None  # (d, d) target rank correlation
    values: np.ndarray  # (samples, d) drawn inputs


def is_uncertainty_document(document: dict) -> bool:
    """Whether a parsed sweep file holds an ``[uncertainty]`` table."""
    return isinstance(document, dict) and "uncertainty" in document


# --------------------------------------------------------------------------- #
# The table
# --------------------------------------------------------------------------- #


def _read_levels(table: Table) -> np.ndarray | None:
    """``levels``: an array or a range table of pore-pressure changes [Pa]."""
    value = table.data.get("levels")
    where = table.key("levels")
    if value is None:
        table.error("levels", "required key missing (pore-pressure changes in Pa)")
        return None
    if isinstance(value, dict):
        levels = expand_range(value, where, table.problems)
    elif isinstance(value, list) and value:
        levels = value
    else:
        table.error("levels", f"expected an array or a range table, got {show(value)}")
        return None
    if levels is None:
        return None
    if len(levels) > MAX_LEVELS:
        table.error("levels", f"at most {MAX_LEVELS} levels, got {len(levels)}")
        return None
    if not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
        for v in levels
    ):
        table.error("levels", "expected finite numbers [Pa]")
        return None
    return np.array(sorted({float(v) for v in levels}, key=abs))


def _check_levels(table: Table, levels: np.ndarray, base_spec) -> None:
    """Levels between 0 and the base case's pore_pressure.change."""
    pore = base_spec.pore_pressure
    if pore is None or pore.change in (None, 0.0):
        table.error(
            "levels",
            "the base case needs a [pore_pressure] table with a non-zero change "
            "(the levels are pore-pressure changes along it)",
        )
        return
    change = pore.change
    outside = [v for v in levels if v * change < 0.0 or abs(v) > abs(change)]
    if outside:
        table.error(
            "levels",
            f"must lie between 0 and pore_pressure.change = {change:g} Pa of the "
            f"base case, got {outside[0]:g}",
        )


def _sample_bound(table: Table, evaluate: str | None) -> int | None:
    """``samples``, bounded before anything is drawn."""
    bound = MAX_XFEM_SAMPLES if evaluate == "xfem" else MAX_SCREEN_SAMPLES
    n = table.integer("samples", rule=Range(1, None))
    if n is not None and n > bound:
        table.error(
            "samples",
            f"must be <= {bound} with evaluate = {evaluate!r}, got {n}",
        )
        return None
    return n


def _check_keys(table: Table, keys: list[str], base: dict | None) -> None:
    """Each input key can be set in the base case; the depletion itself
    (pore_pressure.change) is the axis of the curve, not an input."""
    for key in keys:
        where = f'uncertainty.inputs."{key}"'
        if key == "pore_pressure.change":
            table.problems.append(
                (
                    where,
                    "the pore-pressure change is the axis of the probability "
                    "curve (levels), not an input",
                )
            )
            continue
        trial = copy.deepcopy(base) if base is not None else {}
        message = set_key_path(trial, key_parts(key), 0.0)
        if message:
            table.problems.append((where, message))
    for a, key in enumerate(keys):
        parts = key_parts(key)
        for other in keys[a + 1 :]:
            o = key_parts(other)
            n = min(len(parts), len(o))
            if parts[:n] == o[:n]:
                table.problems.append(
                    (f'uncertainty.inputs."{key}"', f'overlaps "{other}"')
                )


def loads_uncertainty(text: str, path: str | Path = "<string>") -> UncertaintySpec:
    """Validate a sweep file with an ``[uncertainty]`` table and draw its
    samples; ``CaseError`` listing the problems (exit 2)."""
    path = Path(path)
    document = parse_toml(text, path)
    problems: list[tuple[str, str]] = []
    root = Table(document, "", problems, UNCERTAINTY_FILE_KEYS)
    if "vary" in document:
        problems.append(
            ("vary", "a sweep file holds [vary] or [uncertainty], not both")
        )
    name = root.string("name", path.stem)
    if isinstance(name, str) and (
        any(c in "/\\" or ord(c) < 32 for c in name) or path_problem(name)
    ):
        root.error("name", f"must be usable as a folder name, got {name!r}")
    base, case_path, base_name = read_base(root, path)
    output = root.table("output", ("directory",))
    directory = output.string("directory", None) if output is not None else None
    problem = path_problem(directory) if directory is not None else None
    if output is not None and problem:
        output.error("directory", problem)
    table = root.table("uncertainty", UNCERTAINTY_KEYS, required=True)
    if table is None or problems:
        raise CaseError(path, problems or [("uncertainty", "expected a table")])
    evaluate = table.choice("evaluate", EVALUATE)
    samples = _sample_bound(table, evaluate)
    method = table.choice("method", METHODS, "lhs")
    seed = table.integer("seed", 0, Range(0, 2**63 - 1))
    confidence = table.number("confidence", 0.95, Range(0.0, 1.0, True, True))
    half_width = table.number("half_width", 0.05, Range(0.0, 0.5, True))
    levels = _read_levels(table)
    keys, dists = read_inputs(table)
    correlation = read_correlation(table, keys) if keys else None
    if correlation is not None and samples is not None and samples <= len(keys):
        # the normal scores of n samples span n - 1 dimensions: their
        # correlation matrix over the inputs is singular
        table.error(
            "samples",
            f"[[uncertainty.correlation]] needs more samples than inputs "
            f"({len(keys)}), got {samples}",
        )
    _check_keys(table, keys, base)
    if problems:
        raise CaseError(path, problems)
    # each reader returns None only after recording a problem
    assert base is not None and levels is not None and samples is not None
    base_spec = _base_spec(base, case_path, path)
    if not base_spec.fractures:
        raise CaseError(
            path,
            [("base", "the base case has no fracture: nothing could slip")],
        )
    _check_levels(table, levels, base_spec)
    _check_half_width(table, half_width, confidence)
    if evaluate == "screen":
        _check_screen(table, keys, base, base_spec)
    if problems:
        raise CaseError(path, problems)
    values = draw(dists, samples, method=method, seed=seed, correlation=correlation)
    return UncertaintySpec(
        path=path,
        name=name,
        base=base,
        base_name=str(base_name),
        case_path=case_path,
        base_spec=base_spec,
        directory=Path(directory) if directory else Path("out") / "sweeps" / name,
        samples=samples,
        method=method,
        seed=seed,
        evaluate=evaluate,
        levels=levels,
        confidence=confidence,
        half_width=half_width,
        keys=tuple(keys),
        distributions=tuple(dists),
        correlation=correlation,
        values=values,
    )


def _check_half_width(table: Table, half_width: float, confidence: float) -> None:
    """The samples ``half_width`` asks for (at P = 0.5, the most: about
    (z / 2 half_width)^2) must be samples a study can draw: a target beyond
    them only means a search over numbers too large to count exactly."""
    if half_width is None or confidence is None:
        return
    z = float(special.ndtri(0.5 + confidence / 2.0))
    with np.errstate(over="ignore"):
        needed = (z / (2.0 * half_width)) ** 2
    if needed > MAX_SCREEN_SAMPLES:
        smallest = z / (2.0 * math.sqrt(MAX_SCREEN_SAMPLES))
        table.error(
            "half_width",
            f"{half_width!r} at confidence {confidence:g} needs about {needed:.3g} "
            f"samples at P = 0.5, more than the {MAX_SCREEN_SAMPLES} a study may "
            f"draw; give at least {smallest:.2g}",
        )


def _check_screen(table: Table, keys: list[str], base: dict, base_spec) -> None:
    """The closed form follows the base case's stress path and reads the keys."""
    from xfemslip.studies.slip_screen import screen_key_problem, stress_path

    segments = sum(len(f.points) - 1 for f in base_spec.fractures)
    if table.data.get("samples", 0) * segments > MAX_SCREEN_CELLS:
        table.error(
            "samples",
            f"{table.data['samples']} samples x {segments} fracture segments is "
            f"more than the screen's {MAX_SCREEN_CELLS} (memory); draw fewer",
        )
    _, why = stress_path(base_spec)
    if why:
        table.error(
            "evaluate",
            f'"screen" cannot follow the base case: {why}; use evaluate = "xfem"',
        )
    for key in keys:
        why = screen_key_problem(base_spec, key)
        parts = key_parts(key)
        index = parts[1] if len(parts) > 1 else None
        if (
            not why
            and parts[0] == "fractures"
            and parts[-1] in ("angle", "length")
            and isinstance(index, int)
        ):
            items = base.get("fractures", [])
            if index >= len(items) or "center" not in items[index]:
                why = (
                    "the screen varies angle and length of a center-form fracture only"
                )
        if why:
            table.problems.append((f'uncertainty.inputs."{key}"', why))


def _base_spec(base: dict, case_path: Path, path: Path):
    """The base case, validated as a case (its problems name the base)."""
    import tomli_w

    try:
        return loads_case(tomli_w.dumps(base), case_path)
    except CaseError as err:
        reasons = "; ".join(f"{k}: {m}" if k else m for k, m in err.problems)
        raise CaseError(
            path, [("base", f"the base case is not valid: {reasons}")]
        ) from None
    except (TypeError, ValueError) as exc:
        raise CaseError(path, [("base", f"cannot be written as TOML: {exc}")]) from None


def load_uncertainty(path: str | Path) -> UncertaintySpec:
    """Read, validate and sample an uncertainty sweep file."""
    path = Path(path)
    return loads_uncertainty(read_text(path, "sweep file"), path)


def sample_document(spec: UncertaintySpec, index: int) -> dict:
    """The case document of sample ``index``: the base with its input values."""
    document = copy.deepcopy(spec.base)
    for key, value in zip(spec.keys, spec.values[index], strict=True):
        set_key_path(document, key_parts(key), _toml_value(value))
    return document


def _toml_value(value) -> float | int:
    """A drawn value as a TOML number (an integer stays an integer)."""
    value = float(value)
    return int(value) if value.is_integer() and abs(value) < 2**53 else value


def is_uncertainty_file(path: str | Path) -> bool:
    """Whether the sweep file at ``path`` holds an ``[uncertainty]`` table
    (False when it cannot be read: the sweep loader then says why)."""
    try:
        return is_uncertainty_document(
            parse_toml(read_text(Path(path), "sweep file"), path)
        )
    except CaseError:
        return False
