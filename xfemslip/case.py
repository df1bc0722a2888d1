"""Case files (TOML, ``case-format.md`` version 1) -> validated frozen specs.

This is the ONLY module that validates user input.  ``load_case(path)``
reads a file, collects every problem it finds (each with its key path) and
raises one ``CaseError``; otherwise it returns a ``CaseSpec`` whose fields are
resolved to SI values and plain NumPy arrays, so that the numerical modules
never look at the TOML again.

Units: m, Pa, N/m^3 (= Pa/m) for penalty stiffnesses; angles in degrees in the
file, converted here and nowhere else.  Stresses: tension positive.

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

Public functions: ``load_case``, ``loads_case``, ``describe``; ``SOLVER_OPTIONS``
is the one table of ``[solver]`` options.

The work is split over private helper modules, imported only from here (every
public name is re-exported here): ``case_specs`` (the spec dataclasses),
``case_tables`` (typed TOML-table reader, value checks, message helpers),
``case_grid`` (``[domain]`` and ``[mesh]``), ``case_fractures`` and
``case_polyline`` (``[[fractures]]`` and its polyline checks),
``case_network``, ``case_segments`` and ``case_generate`` (``[network]``: a
CSV file of segments, random networks),
``case_boundary`` and ``case_csv`` (``[boundary]`` and its CSV files) and
``case_describe`` (``describe``).  This module keeps the other constants,
``SOLVER_OPTIONS``, the readers of ``name``, ``[material]``, ``[loading]``,
``[solver]`` and ``[output]``, and the entry points.
"""

from __future__ import annotations

from pathlib import Path

from xfemslip import pardiso
from xfemslip.case_boundary import EDGE_KEYS, EDGE_WORDS, _read_boundary
from xfemslip.case_csv import CSV_HEADER, CSV_TOLERANCE, MAX_CSV_PROBLEMS
from xfemslip.case_describe import describe
from xfemslip.case_files import (
    MAX_CSV_BYTES,
    MAX_NAME_BYTES,
    MAX_TOML_BYTES,
    MAX_TOML_DEPTH,
    parse_toml,
    path_problem,
    read_text,
)
from xfemslip.case_fractures import (
    FRACTURE_KEYS,
    TIP_KEYS,
    TIP_KINDS,
    _read_fractures,
)
from xfemslip.case_grid import (
    BYTES_PER_ELEMENT,
    DOMAIN_RTOL,
    MAX_ELEMENTS,
    _read_grid,
)
from xfemslip.case_network import _read_network
from xfemslip.case_pore import (
    PORE_PRESSURE_KEYS,
    PORE_PRESSURE_REGIONS,
    RESERVOIR_KEYS,
    _read_pore_pressure,
    _read_reservoir,
)
from xfemslip.case_specs import (
    CONTACT_PATCH_CELLS,
    EDGES,
    BoundarySpec,
    CaseSpec,
    EdgeSpec,
    FractureSpec,
    LoadingSpec,
    MaterialSpec,
    MeshSpec,
    OutputSpec,
    PorePressureSpec,
    ReservoirSpec,
    SolverSpec,
)
from xfemslip.case_tables import (
    _POSITIVE,
    Option,
    Range,
    _check_choice,
    _show,
    _Table,
)
from xfemslip.errors import CaseError

__all__ = [
    "BYTES_PER_ELEMENT",
    "CSV_HEADER",
    "CSV_TOLERANCE",
    "DOMAIN_RTOL",
    "EDGES",
    "EDGE_KEYS",
    "EDGE_WORDS",
    "FRACTURE_KEYS",
    "MATERIAL_MODELS",
    "MAX_CSV_BYTES",
    "MAX_NAME_BYTES",
    "MAX_TOML_BYTES",
    "MAX_TOML_DEPTH",
    "MAX_CSV_PROBLEMS",
    "MAX_ELEMENTS",
    "MAX_STEPS",
    "OUTPUT_FORMATS",
    "PORE_PRESSURE_KEYS",
    "PORE_PRESSURE_REGIONS",
    "RESERVOIR_KEYS",
    "SOLVER_OPTIONS",
    "STRESS_KEYS",
    "TIP_KEYS",
    "TIP_KINDS",
    "TOP_KEYS",
    "BoundarySpec",
    "CaseSpec",
    "EdgeSpec",
    "FractureSpec",
    "LoadingSpec",
    "MaterialSpec",
    "MeshSpec",
    "Option",
    "OutputSpec",
    "PorePressureSpec",
    "Range",
    "ReservoirSpec",
    "SolverSpec",
    "describe",
    "load_case",
    "loads_case",
    "parse_toml",
    "path_problem",
    "read_text",
]


# --------------------------------------------------------------------------- #
# Constants and option tables
# --------------------------------------------------------------------------- #

# The constants of [domain]/[mesh], [[fractures]], [boundary] and the CSV files
# live beside their readers (case_grid, case_fractures, case_boundary, case_csv)
# and are re-exported above.
TOP_KEYS = (
    "name",
    "domain",
    "mesh",
    "material",
    "fractures",
    "network",
    "loading",
    "boundary",
    "solver",
    "output",
    "pore_pressure",
    "reservoir",
)
STRESS_KEYS = ("xx", "yy", "xy")
MATERIAL_MODELS = ("plane_strain", "plane_stress")
OUTPUT_FORMATS = ("h5", "vtu")
MAX_STEPS = 100_000


SOLVER_OPTIONS: tuple[Option, ...] = (
    Option(
        "tolerance",
        float,
        1.0e-8,
        "Newton stops when ||residual|| / ||F_ext|| <= tolerance (eta_0)",
        Range(0.0, 1.0, lo_open=True, hi_open=True),
    ),
    Option(
        "max_iterations", int, 30, "Newton iterations per load step", Range(1, 10_000)
    ),
    Option(
        "tangent",
        str,
        "consistent",
        "contact tangent: 'consistent' (Newton) or 'secant' (paper eq. 28)",
        ("consistent", "secant"),
    ),
    Option(
        "contact_patch",
        float,
        CONTACT_PATCH_CELLS,
        "length of a contact patch in cell sizes: the contact law acts on the jump "
        "averaged over each patch, which removes the traction oscillation of "
        "pointwise penalty XFEM; 0 = pointwise (every Gauss point on its own)",
        Range(0.0, 100.0),
    ),
    Option(
        "max_step_cuts",
        int,
        5,
        "bisections of a load step that does not converge (0: none); the "
        "smallest sub-step is 1/2**max_step_cuts of the step",
        Range(0, 30),
    ),
    Option(
        "linear_solver",
        str,
        "auto",
        "linear solver of the Newton systems: 'superlu' (sparse LU, factorization "
        "kept), 'amg' (pyamg-preconditioned GMRES), 'pardiso' (MKL PARDISO, "
        "pip install 'xfemslip[mkl]') or 'auto' (pardiso from 50,000 free dofs "
        "when installed, else amg from 50,000 free dofs on cells up to 4:1)",
        ("auto", "superlu", "amg", "pardiso"),
    ),
    Option(
        "kernels",
        str,
        "auto",
        "how the cell and contact loops run: 'numpy' (whole-array NumPy, no "
        "Numba start-up), 'numba' (compiled, cached once per install) or 'auto' "
        "(numpy unless the enriched cells are many; the answer is the same to "
        "round-off)",
        ("auto", "numba", "numpy"),
    ),
)


# --------------------------------------------------------------------------- #
# name, [material]
# --------------------------------------------------------------------------- #


def _read_name(root: _Table, path: Path) -> str | None:
    """``name``, default the file's stem; it becomes a directory name."""
    name = root.string("name", path.stem)
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


def _read_material(root: _Table) -> MaterialSpec | None:
    """[material]: E > 0, 0 <= nu < 0.5, model."""
    table = root.table("material", ("E", "nu", "model"), required=True)
    if table is None:
        return None
    E = table.number("E", rule=_POSITIVE)
    nu = table.number("nu", rule=Range(0.0, 0.5, hi_open=True))
    model = table.choice("model", MATERIAL_MODELS, "plane_strain")
    if E is None or nu is None or model is None:
        return None
    return MaterialSpec(E=E, nu=nu, model=model)


# --------------------------------------------------------------------------- #
# [loading], [solver], [output]
# --------------------------------------------------------------------------- #


def _read_stress(loading: _Table, name: str) -> tuple[float, float, float] | None:
    """``{ xx = .., yy = .., xy = .. }`` [Pa]; xy defaults to 0."""
    table = loading.table(name, STRESS_KEYS)
    if table is None or not table.present:
        return None
    xx, yy = table.number("xx"), table.number("yy")
    xy = table.number("xy", 0.0)
    return None if None in (xx, yy, xy) else (xx, yy, xy)


def _read_loading(root: _Table, needs_stress: list[str]) -> LoadingSpec | None:
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


def _read_solver(root: _Table) -> SolverSpec | None:
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
    if values["linear_solver"] == "pardiso" and not pardiso.available():
        table.error(
            "linear_solver",
            "'pardiso' needs MKL PARDISO, which is not installed: "
            "pip install 'xfemslip[mkl]'",
        )
        return None
    if any(v is None for v in values.values()):
        return None
    return SolverSpec(**values)


def _read_formats(table: _Table) -> tuple[str, ...] | None:
    """``output.formats``: a non-empty list of distinct formats including "h5"."""
    value = table.data.get("formats", list(OUTPUT_FORMATS))
    if not isinstance(value, list) or not value:
        table.error(
            "formats",
            f'expected a non-empty array of formats ("h5", "vtu"), got {_show(value)}',
        )
        return None
    key = table.key("formats")
    formats = [
        _check_choice(v, f"{key}[{i}]", table.problems, OUTPUT_FORMATS)
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


def _with_network(root: _Table, grid, folder: Path, fractures):
    """The inline [[fractures]] followed by those of [network] (case_network)."""
    network = _read_network(root, grid, folder, fractures or ())
    if fractures is None or network is None:
        return None
    return fractures + network


def _read_output(root: _Table, name: str | None) -> OutputSpec | None:
    """[output]: directory (default out/<name>, relative to the cwd) and formats."""
    table = root.table("output", ("directory", "formats"))
    if table is None:
        return None
    directory = table.string("directory", None)
    problem = path_problem(directory) if directory is not None else None
    if problem:
        table.error("directory", f"{problem}, got {_show(directory)}")
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
    path : the TOML case file; CSV files it names are relative to its folder.

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
    return loads_case(read_text(path, "case file"), path)


def loads_case(text: str, path: str | Path = "<string>") -> CaseSpec:
    """Validate and resolve case-file ``text``; ``path`` names it in messages,
    gives the default ``name`` (its stem) and the folder of CSV files."""
    path = Path(path)
    document = parse_toml(text, path)
    problems: list[tuple[str, str]] = []
    root = _Table(document, "", problems, TOP_KEYS)
    name = _read_name(root, path)
    grid = _read_grid(root)
    material = _read_material(root)
    fractures = _read_fractures(root, grid)
    fractures = _with_network(root, grid, path.parent, fractures)
    boundary, needs_stress = _read_boundary(root, grid, path.parent)
    loading = _read_loading(root, needs_stress)
    solver = _read_solver(root)
    output = _read_output(root, name)
    pore_pressure = _read_pore_pressure(root)
    reservoir = _read_reservoir(root, grid)
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
    )
