"""``load_case`` / ``loads_case``: a case file -> a validated ``CaseSpec``.

The readers of ``name``, ``[material]``, ``[loading]``, ``[solver]`` and
``[output]`` are here; the other tables have their own modules in this
package, which this one calls in document order.  Every problem is collected
(each with its key path) and raised as one ``CaseError``; otherwise the
returned ``CaseSpec`` holds SI values and read-only NumPy arrays, so that the
numerical modules never look at the TOML again.

Resolution rules beyond ``case-format.md`` (see ``describe`` for the printout):

- an edge left out of ``[boundary]`` is ``"free"`` (no traction); its
  ``EdgeSpec.source`` is ``"default"`` so that ``describe`` can say so;
- ``center``/``length``/``angle`` use cosines and sines that are exact at
  multiples of 45 degrees, so axis-aligned and diagonal fractures land exactly
  on the lines they are meant to follow;
- ``name`` becomes a directory name (``out/<name>``), so it may not contain a
  path separator or a control character;
- boundary CSV files: problems name the file and its line (the header is line
  1); a point beyond either end of its edge is an error like a point off the
  edge, and points closer than the tolerance along the edge must carry the
  same values (one of them is then kept).
"""

from __future__ import annotations

import re
from pathlib import Path

from xfemslip.case import options
from xfemslip.case.boundary import read_boundary
from xfemslip.case.events import EXTENT, read_events
from xfemslip.case.files import (
    MAX_NAME_BYTES,
    STDIN,
    input_folder,
    parse_toml,
    path_problem,
    read_text,
)
from xfemslip.case.fractures import read_fractures
from xfemslip.case.grid import read_grid
from xfemslip.case.hydraulics import LAW_RULES, MATRIX, read_permeability
from xfemslip.case.network import read_network
from xfemslip.case.options import (
    MATERIAL_MODELS,
    MAX_STEPS,
    OUTPUT_FORMATS,
    SOLVER_OPTIONS,
    STRESS_KEYS,
    TOP_KEYS,
)
from xfemslip.case.pore import read_pore_pressure, read_reservoir
from xfemslip.case.segments import PROPERTY_RULES
from xfemslip.case.specs import (
    CaseSpec,
    LoadingSpec,
    MaterialSpec,
    OutputSpec,
    SolverSpec,
)
from xfemslip.case.tables import (
    BIOT,
    FINITE,
    POISSON,
    POSITIVE,
    Range,
    Table,
    check_choice,
    show,
)
from xfemslip.errors import CaseError

__all__ = ["load_case", "loads_case", "value_rule"]


# --------------------------------------------------------------------------- #
# name, [material]
# --------------------------------------------------------------------------- #


def _read_name(root: Table, path: Path) -> str | None:
    """``name``, default the file's stem (``stdin`` for standard input); it
    becomes a directory name."""
    name = root.string("name", "stdin" if str(path) == STDIN else path.stem)
    if name is None or not root.has("name"):
        return name
    if any(c in "/\\" or ord(c) < 32 for c in name) or name in (".", ".."):
        message = (
            "must not be . or .."
            if name in (".", "..")
            else "must not contain a path separator or a control character"
        )
        root.error("name", f"{message}, got {name!r} (it names the output directory)")
        return None
    size = len(name.encode("utf-8", "surrogatepass"))
    if size > MAX_NAME_BYTES:
        root.error(
            "name",
            f"is {size} bytes long, more than the {MAX_NAME_BYTES} of a folder name "
            "(it names the output directory)",
        )
        return None
    return name


def _read_material(root: Table) -> MaterialSpec | None:
    """[material]: E > 0, 0 <= nu < 0.5, model."""
    table = root.table("material", ("E", "nu", "model"), required=True)
    if table is None:
        return None
    E = table.number("E", rule=POSITIVE)
    nu = table.number("nu", rule=POISSON)
    model = table.choice("model", MATERIAL_MODELS, "plane_strain")
    if E is None or nu is None or model is None:
        return None
    return MaterialSpec(E=E, nu=nu, model=model)


def value_rule(key: str) -> Range | None:
    """The interval the case format allows for the number at ``key`` (a key
    path such as ``fractures[0].friction``): the rule its reader checks, for
    the keys a study may vary by a distribution; None for other keys (their
    values are checked when a case is loaded).  Every number of a case is
    finite besides."""
    parts = re.sub(r"\[\d+\]", "", key).split(".")
    table, name = ".".join(parts[:-1]), parts[-1]
    rules: dict[str, Range] = {}
    if table in ("material", "reservoir"):
        rules = {"E": POSITIVE, "nu": POISSON}
    elif table in ("loading.stress", "loading.initial_stress"):
        rules = dict.fromkeys(STRESS_KEYS, FINITE)
    elif table == "pore_pressure":
        rules = {"initial": FINITE, "change": FINITE, "biot": BIOT}
    elif table in ("fractures", "network"):
        rules = {**PROPERTY_RULES, "length": POSITIVE, "angle": FINITE}
    elif table in ("fractures.hydraulic", "network.hydraulic"):
        rules = LAW_RULES
    elif table == "permeability":
        rules = {**LAW_RULES, "matrix": MATRIX}
    elif table == "events":
        rules = {"extent": EXTENT}
    return rules.get(name)


# --------------------------------------------------------------------------- #
# [loading], [solver], [output]
# --------------------------------------------------------------------------- #


def _read_stress(loading: Table, name: str) -> tuple[float, float, float] | None:
    """``{ xx = .., yy = .., xy = .. }`` [Pa]; xy defaults to 0."""
    table = loading.table(name, STRESS_KEYS)
    if table is None or not table.present:
        return None
    xx, yy = table.number("xx"), table.number("yy")
    xy = table.number("xy", 0.0)
    return None if None in (xx, yy, xy) else (xx, yy, xy)


def _read_loading(root: Table, needs_stress: list[str]) -> LoadingSpec | None:
    """[loading]; ``stress`` is required when an edge carries a traction."""
    table = root.table("loading", ("stress", "initial_stress", "steps"))
    if table is None:
        return None
    start = len(table.problems)
    stress = _read_stress(table, "stress")
    if needs_stress and not table.has("stress"):
        edges = ", ".join(f"boundary.{e}" for e in needs_stress)
        table.error(
            "stress",
            f"required key missing: {edges} carries a traction = loading.stress . n",
        )
    initial_stress = _read_stress(table, "initial_stress")
    steps = table.integer("steps", 1, Range(1, MAX_STEPS))
    if len(table.problems) > start:
        return None
    return LoadingSpec(stress=stress, initial_stress=initial_stress, steps=steps)


def _read_solver(root: Table) -> SolverSpec | None:
    """[solver], validated against SOLVER_OPTIONS."""
    table = root.table("solver", tuple(o.name for o in SOLVER_OPTIONS))
    if table is None:
        return None
    values = {}
    for option in SOLVER_OPTIONS:
        if option.type is str:
            values[option.name] = table.choice(
                option.name, option.allowed, option.default
            )
        elif option.type is int:
            values[option.name] = table.integer(
                option.name, option.default, option.allowed
            )
        else:
            values[option.name] = table.number(
                option.name, option.default, option.allowed
            )
    if values["linear_solver"] == "pardiso" and not options.pardiso_installed():
        table.error(
            "linear_solver",
            "'pardiso' needs MKL PARDISO, which is not installed: "
            "pip install 'xfemslip[mkl]'",
        )
        return None
    if any(v is None for v in values.values()):
        return None
    return SolverSpec(**values)


def _read_formats(table: Table) -> tuple[str, ...] | None:
    """``output.formats``: a non-empty list of distinct formats including "h5"."""
    value = table.data.get("formats", list(OUTPUT_FORMATS))
    if not isinstance(value, list) or not value:
        table.error(
            "formats",
            f'expected a non-empty array of formats ("h5", "vtu"), got {show(value)}',
        )
        return None
    key = table.key("formats")
    formats = [
        check_choice(v, f"{key}[{i}]", table.problems, OUTPUT_FORMATS)
        for i, v in enumerate(value)
    ]
    if any(f is None for f in formats):
        return None
    if len(set(formats)) != len(formats):
        table.error("formats", f"lists a format twice: {formats}")
        return None
    if "h5" not in formats:
        table.error(
            "formats", f'must include "h5" (result.h5 is always written), got {formats}'
        )
        return None
    return tuple(formats)


def _with_network(root: Table, grid, folder: Path, fractures):
    """The inline [[fractures]] followed by those of [network] (network.py)."""
    network = read_network(root, grid, folder, fractures or ())
    if fractures is None or network is None:
        return None
    return fractures + network


def _read_output(root: Table, name: str | None) -> OutputSpec | None:
    """[output]: directory (default out/<name>, relative to the cwd) and formats."""
    table = root.table("output", ("directory", "formats"))
    if table is None:
        return None
    directory = table.string("directory", None)
    problem = path_problem(directory) if directory is not None else None
    if problem:
        table.error("directory", f"{problem}, got {show(directory)}")
        directory = None
    formats = _read_formats(table)
    if formats is None or (
        directory is None and (table.has("directory") or name is None)
    ):
        return None
    path = Path(directory) if directory is not None else Path("out") / name
    return OutputSpec(directory=path, formats=formats)


# --------------------------------------------------------------------------- #
# Public entry points
# --------------------------------------------------------------------------- #


def load_case(path: str | Path) -> CaseSpec:
    """Read, validate and resolve a case file.

    Parameters
    ----------
    path : the TOML case file, a pipe, or ``-`` for standard input; CSV files
        it names are relative to its folder (to the working directory for a
        pipe and standard input).

    Returns
    -------
    CaseSpec with SI values and read-only float64 arrays.

    Raises
    ------
    CaseError listing every problem of the file (unreadable file, TOML syntax,
    unknown keys, missing keys, wrong types, out-of-range values, bad CSV files),
    each with its key path.
    """
    path = Path(path)
    return loads_case(read_text(path, "case file"), path, folder=input_folder(path))


def loads_case(
    text: str, path: str | Path = "<string>", *, folder: Path | None = None
) -> CaseSpec:
    """Validate and resolve case-file ``text``; ``path`` names it in messages
    and gives the default ``name`` (its stem; ``stdin`` for ``-``), ``folder``
    (default: the folder of ``path``) the folder of CSV files."""
    path = Path(path)
    folder = path.parent if folder is None else Path(folder)
    document = parse_toml(text, path)
    problems: list[tuple[str, str]] = []
    root = Table(document, "", problems, TOP_KEYS)
    name = _read_name(root, path)
    grid = read_grid(root)
    material = _read_material(root)
    fractures = read_fractures(root, grid)
    fractures = _with_network(root, grid, folder, fractures)
    boundary, needs_stress = read_boundary(root, grid, folder)
    loading = _read_loading(root, needs_stress)
    solver = _read_solver(root)
    output = _read_output(root, name)
    pore_pressure = read_pore_pressure(root)
    reservoir = read_reservoir(root, grid)
    events = read_events(root)
    permeability = read_permeability(root, grid, fractures)
    if problems:
        raise CaseError(path, problems)
    return CaseSpec(
        path=path,
        text=text,
        name=name,
        origin=grid.origin,
        size=grid.size,
        mesh=grid.mesh,
        material=material,
        fractures=fractures,
        loading=loading,
        boundary=boundary,
        solver=solver,
        output=output,
        pore_pressure=pore_pressure,
        reservoir=reservoir,
        events=events,
        permeability=permeability,
    )
