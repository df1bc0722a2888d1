"""Sweep files: a base case plus the parameters to vary -> validated cases.

A sweep file is TOML (docs/sweep-format.md)::

    name = "young-modulus"                # optional; default: the file's stem
    base = "../reservoir_depletion.toml"  # the base case, relative to this file,
    # [base] ...                          #   OR the whole case inline as a table
    combine = "product"                   # or "zip"; default "product"

    [vary]                                # key path in the case = values
    "material.E" = [5.0e9, 20.0e9, 80.0e9]
    "fractures[0].angle" = { start = 0.0, stop = 90.0, step = 22.5 }
    # { start = .., stop = .., num = n }: n evenly spaced values, both ends in

    [output]
    directory = "out/sweeps/young-modulus"  # default: out/sweeps/<name>

Key paths are dotted case keys; ``name[i]`` picks item i of an array
(``fractures[0].angle``, ``loading.stress.xx``, ``mesh.elements[0]``).  An
unquoted ``material.E = [...]`` in ``[vary]`` is the same key (TOML reads it as
a nested table, flattened here).  A range with ``step`` includes ``stop`` when
it falls on the grid (within 1e-9 step).  ``product`` runs every combination,
the first key varying slowest; ``zip`` pairs the i-th values of every key.

Every generated case is validated by the normal case loader
(:func:`xfemslip.case.loads_case`) and checked against its mesh before
anything runs.  A problem of the sweep file itself (its keys, the ``[vary]``
table, a key path the base case does not have) is ONE ``CaseError`` naming
the sweep file, the key and what was expected (exit 2), as is a sweep none of
whose cases can be built.  A generated case that cannot be built while
others can is *refused*: it stays in ``SweepSpec.cases`` with the reason in
``SweepCase.refused`` (and no spec), and :mod:`xfemslip.studies.run` reports
it and runs the others.

Public: ``load_sweep(path) -> SweepSpec``, ``loads_sweep(text, path)``.
The ``[vary]`` table (key paths, ranges) is read by :mod:`xfemslip.studies.vary`;
the running of a sweep is :mod:`xfemslip.studies.run`.
"""

from __future__ import annotations

import copy
import itertools
import logging
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import tomli_w

from xfemslip.case import loads_case, parse_toml, path_problem, read_text
from xfemslip.case.files import MAX_TOML_BYTES, UnreadableInput, read_input
from xfemslip.case.tables import Table, show
from xfemslip.errors import CaseError, GeometryError, MeshError
from xfemslip.studies.vary import (
    MAX_CASES,
    RANGE_KEYS,
    case_count,
    expand_range,
    key_parts,
    parse_key_path,
    read_vary,
    set_key_path,
)

__all__ = [
    "MAX_CASES",
    "RANGE_KEYS",
    "SweepCase",
    "SweepSpec",
    "case_id",
    "expand_range",
    "load_sweep",
    "loads_sweep",
    "parse_key_path",
    "set_key_path",
]

SWEEP_KEYS = ("name", "base", "combine", "vary", "output")
COMBINE = ("product", "zip")
MAX_PROBLEMS = 20  # invalid generated cases listed in one message
# Bytes of a case id (ASCII) and of the base name in a case's name: together
# below the 255 bytes of a folder name.
MAX_CASE_ID = 100
# A generous bound on cases x base-case size: a 2 kB base allows far more
# than MAX_CASES cases; a 1 MB base (thousands of inline fractures) 256.
MAX_SWEEP_TEXT_BYTES = 256e6


@dataclass(frozen=True)
class SweepCase:
    """One generated case: its id (folder name), parameters, TOML text, spec;
    a case that cannot be built has no spec and says why in ``refused``."""

    index: int
    case_id: str
    params: tuple[tuple[str, object], ...]  # (key path, value) in vary order
    text: str  # the case file's text (TOML); "" if it cannot be written
    path: Path  # the path the case is loaded as (CSV files relative to it)
    spec: object  # CaseSpec, or None when refused
    refused: str = ""  # one line: why the case cannot be built

    @property
    def label(self) -> str:
        """``case 003_seed=4 (network.generate.seed = 4)``."""
        values = ", ".join(f"{k} = {v!r}" for k, v in self.params)
        return f"case {self.case_id} ({values})"


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: its file, output folder, vary keys and cases."""

    path: Path
    name: str
    base_path: Path
    combine: str
    keys: tuple[str, ...]
    directory: Path
    cases: tuple[SweepCase, ...]


# --------------------------------------------------------------------------- #
# Cases
# --------------------------------------------------------------------------- #


def _slug(value) -> str:
    """Short file-name-safe text of a parameter value."""
    if isinstance(value, float):
        text = re.sub(r"e([+-])0*(\d)", r"e\1\2", f"{value:g}").replace("e+", "e")
    else:
        text = str(value)
    text = re.sub(r"[^A-Za-z0-9.+-]+", "_", text).strip("_")
    return text[:24] or "x"


def case_id(index: int, n_cases: int, params) -> str:
    """Folder name of a case: ``002_angle=45``: index, then each key's last
    name, cut to MAX_CASE_ID characters (the index first keeps it unique)."""
    width = max(3, len(str(n_cases - 1)))
    parts = [f"{index:0{width}d}"]
    for key, value in params:
        name = re.sub(r"\[\d+\]", "", key.rsplit(".", 1)[-1])
        parts.append(f"{name}={_slug(value)}")
    return "_".join(parts)[:MAX_CASE_ID].rstrip("_")


def _combinations(vary: list, combine: str) -> list[tuple[tuple[str, object], ...]]:
    """The parameter sets, in run order."""
    keys = [k for k, _ in vary]
    rows: Iterable[tuple]
    if combine == "zip":
        rows = zip(*(v for _, v in vary), strict=True)
    else:
        rows = itertools.product(*(v for _, v in vary))
    return [tuple(zip(keys, row, strict=True)) for row in rows]


def build_case(base: dict, base_name: str, index: int, n: int, params, path: Path):
    """(case_id, TOML text, why it cannot be written, problems of the sweep
    file: vary keys the base case cannot take)."""
    cid = case_id(index, n, params)
    document = copy.deepcopy(base)
    problems = []
    for key, value in params:
        message = set_key_path(document, key_parts(key), value)
        if message:
            problems.append((f'vary."{key}"', message))
    short = str(base_name).encode("utf-8")[:MAX_CASE_ID].decode("utf-8", "ignore")
    document["name"] = f"{short}-{cid}"
    output = document.get("output")
    if isinstance(output, dict):
        output.pop("directory", None)  # the sweep chooses the folder
    if problems:
        return cid, "", "", problems
    try:
        return cid, tomli_w.dumps(document), "", []
    except (TypeError, ValueError) as exc:  # e.g. mixed-type arrays
        return cid, "", f"cannot be written as TOML: {exc}", []


def validate_case(text: str, path: Path):
    """(spec, "") or (None, one-line reason): the case loader, then the
    geometry check."""
    from xfemslip.simulation import check_geometry

    try:
        spec = loads_case(text, path)
        logging.disable(logging.WARNING)  # the run logs its warnings once
        try:
            check_geometry(spec)
        finally:
            logging.disable(logging.NOTSET)
    except CaseError as err:
        return None, "; ".join(f"{k}: {m}" if k else m for k, m in err.problems)
    except (GeometryError, MeshError) as err:
        return None, " ".join(str(err).replace(f"{path}: ", "", 1).split())
    return spec, ""


# --------------------------------------------------------------------------- #
# Entry points
# --------------------------------------------------------------------------- #


def read_base(root: Table, path: Path) -> tuple[dict | None, Path, str | None]:
    """``base``: a case file path (relative to the sweep file) or an inline table.

    Returns (document, path to load the cases as, base name)."""
    if not root.has("base"):
        root.error("base", "required key missing (a case file path or a [base] table)")
        return None, path, None
    value = root.data["base"]
    if isinstance(value, dict):
        return value, path, value.get("name", path.stem)
    if not isinstance(value, str) or not value.strip():
        root.error("base", f"expected a case file path or a table, got {show(value)}")
        return None, path, None
    base_path = (path.parent / value) if not Path(value).is_absolute() else Path(value)
    try:
        document = parse_toml(read_input(base_path, MAX_TOML_BYTES), base_path)
    except UnreadableInput as exc:
        root.error("base", f"cannot read the base case {base_path}: {exc}")
        return None, base_path, None
    except CaseError as err:
        reasons = "; ".join(f"{k}: {m}" if k else m for k, m in err.problems)
        root.error("base", f"the base case {base_path} is not valid TOML: {reasons}")
        return None, base_path, None
    return document, base_path, document.get("name", base_path.stem)


def loads_sweep(text: str, path: str | Path = "<string>") -> SweepSpec:
    """Validate sweep ``text`` (``path`` names it and anchors relative paths)
    and every case it generates; ``CaseError`` listing the problems."""
    path = Path(path)
    document = parse_toml(text, path)
    problems: list[tuple[str, str]] = []
    root = Table(document, "", problems, SWEEP_KEYS)
    name = root.string("name", path.stem)
    if isinstance(name, str) and any(c in "/\\" or ord(c) < 32 for c in name):
        root.error("name", f"must not contain a path separator, got {name!r}")
    elif isinstance(name, str) and path_problem(name):
        root.error("name", f"{path_problem(name)} (it names the sweep folder)")
    combine = root.choice("combine", COMBINE, "product")
    base, case_path, base_name = read_base(root, path)
    vary = read_vary(root, combine)
    output = root.table("output", ("directory",))
    directory = output.string("directory", None) if output is not None else None
    problem = path_problem(directory) if directory is not None else None
    if output is not None and problem:
        output.error("directory", problem)
    if problems:
        raise CaseError(path, problems)
    # each reader returns None only after recording a problem
    assert base is not None
    _check_volume(base, vary, combine, path)  # read_vary has bounded the count
    combos = _combinations(vary, combine)
    cases = _generate(base, base_name, case_path, combos, problems)
    if not problems and all(case.refused for case in cases):  # nothing to run
        problems = [(case.label, case.refused) for case in cases]
    if problems:
        shown = problems[:MAX_PROBLEMS]
        if len(problems) > MAX_PROBLEMS:
            shown.append(("", f"and {len(problems) - MAX_PROBLEMS} more"))
        raise CaseError(path, shown)
    return SweepSpec(
        path=path,
        name=name,
        base_path=case_path,
        combine=combine,
        keys=tuple(k for k, _ in vary),
        directory=Path(directory) if directory else Path("out") / "sweeps" / name,
        cases=tuple(cases),
    )


def _check_volume(base: dict, vary: list, combine: str, path: Path) -> None:
    """Refuse a sweep whose cases would hold more than MAX_SWEEP_TEXT_BYTES of
    case text (each case is kept as text and as a spec until it has run)."""
    n_cases = case_count(vary, combine)
    size = len(tomli_w.dumps(base))
    if n_cases * size > MAX_SWEEP_TEXT_BYTES:
        raise CaseError(
            path,
            [
                (
                    "vary",
                    f"gives {n_cases} cases of a {size / 1e6:.3g} MB base case, "
                    f"{n_cases * size / 1e9:.3g} GB of case text, more than the "
                    f"limit of {MAX_SWEEP_TEXT_BYTES / 1e9:.3g} GB; vary fewer "
                    "values or make the base case smaller",
                )
            ],
        )


def _generate(base, base_name, case_path, combos, problems) -> list[SweepCase]:
    """Build and validate every case; problems of the sweep file are appended,
    a case that cannot be built is kept with its reason (``refused``)."""
    cases = []
    for index, params in enumerate(combos):
        cid, text, reason, found = build_case(
            base, base_name, index, len(combos), params, case_path
        )
        problems += found
        if found:
            continue
        spec = None
        if not reason and not problems:  # else the sweep is refused anyway
            spec, reason = validate_case(text, case_path)
        cases.append(SweepCase(index, cid, params, text, case_path, spec, reason))
    return cases


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep file; see the module docstring."""
    path = Path(path)
    return loads_sweep(read_text(path, "sweep file"), path)
