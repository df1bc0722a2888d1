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
from dataclasses import replace
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
from xfemslip.case.grading import (
    case_refinement,
    combine,
    graded_grid,
    unit_refinement,
)
from xfemslip.case.grid import read_grid
from xfemslip.case.hydraulics import LAW_RULES, MATRIX, read_permeability
from xfemslip.case.network import read_network
from xfemslip.case.options import (
    IN_SITU_KEYS,
    MATERIAL_MODELS,
    MAX_STEPS,
    OUTPUT_FORMATS,
    SOLVER_OPTIONS,
    STRESS_KEYS,
    TOP_KEYS,
)
from xfemslip.case.pore import check_region, read_pore_pressure
from xfemslip.case.quantities import convert_units, first_problems
from xfemslip.case.segments import PROPERTY_RULES
from xfemslip.case.specs import (
    CaseSpec,
    InSituSpec,
    LoadingSpec,
    MaterialSpec,
    OutputSpec,
    SolverSpec,
    digest,
)
from xfemslip.case.tables import (
    BIOT,
    FINITE,
    POISSON,
    POSITIVE,
    Range,
    Table,
    check_choice,
    complete,
    show,
)
from xfemslip.case.units import (
    read_reservoir,
    read_units,
    reservoir_unit,
    settle_units,
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
    """[material]: E > 0, 0 <= nu < 0.5, model, density > 0 [kg/m^3]."""
    table = root.table("material", ("E", "nu", "model", "density"), required=True)
    if table is None:
        return None
    E = table.number("E", rule=POSITIVE)
    nu = table.number("nu", rule=POISSON)
    model = table.choice("model", MATERIAL_MODELS, "plane_strain")
    density = table.number("density", None, POSITIVE)
    if E is None or nu is None or model is None:
        return None
    return MaterialSpec(E=E, nu=nu, model=model, density=density)


def value_rule(key: str) -> Range | None:
    """The interval the case format allows for the number at ``key`` (a key
    path such as ``fractures[0].friction``): the rule its reader checks, for
    the keys a study may vary by a distribution; None for other keys (their
    values are checked when a case is loaded).  Every number of a case is
    finite besides."""
    parts = re.sub(r"\[\d+\]", "", key).split(".")
    table, name = ".".join(parts[:-1]), parts[-1]
    rules: dict[str, Range] = {}
    if table in ("material", "reservoir", "units"):
        rules = {"E": POSITIVE, "nu": POISSON}
        if table == "units":
            rules |= {"biot": BIOT, "density": POSITIVE, "overpressure": FINITE}
            rules |= {"change": FINITE}
    elif table in ("loading.stress", "loading.initial_stress"):
        rules = dict.fromkeys(STRESS_KEYS, FINITE)
    elif table == "pore_pressure":
        rules = {
            "initial": FINITE,
            "change": FINITE,
            "biot": BIOT,
            "gradient": FINITE,
            "datum": FINITE,
        }
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


def _depth_dependent(loading: Table) -> bool:
    """Whether ``loading.initial_stress`` varies with depth (a datum key)."""
    value = loading.data.get("initial_stress")
    return isinstance(value, dict) and any(k in value for k in IN_SITU_KEYS)


def _gradient(table: Table, key: str, default):
    """A stress gradient with depth [Pa/m]: <= 0, compression growing downward."""
    value = table.number(key, default)
    if value is not None and value > 0.0:
        table.error(
            key,
            f"must be <= 0, got {value!r}: tension is positive, so a stress that "
            "grows more compressive with depth has a negative gradient (e.g. "
            "-23e3 Pa/m)",
        )
        return None
    return value


def _read_in_situ(loading: Table) -> InSituSpec | None:
    """``initial_stress`` with a ``datum``: values at the datum and how they
    grow with depth (``InSituSpec``; xfemslip.fem.zones.in_situ_stress)."""
    table = loading.table("initial_stress", STRESS_KEYS + IN_SITU_KEYS)
    if table is None:
        return None
    start = len(table.problems)
    datum = table.number(
        "datum", hint=" (the y [m] of zero depth, where xx and yy are given)"
    )
    yy = table.number("yy", 0.0)
    xy = table.number("xy", 0.0)
    if table.has("gradient_yy") == table.has("gravity"):
        table.error(
            None,
            "give exactly one of gradient_yy (d sigma_yy / d depth [Pa/m], "
            "e.g. -23e3) or gravity (g [m/s^2], with the densities)",
        )
    gradient_yy = _gradient(table, "gradient_yy", None)
    gravity = table.number("gravity", None, POSITIVE)
    xx = gradient_xx = ratio = None
    if table.has("ratio_xx"):
        for key in ("xx", "gradient_xx"):
            if table.has(key):
                table.error(key, "give either ratio_xx or xx and gradient_xx")
        value = table.data["ratio_xx"]
        if value == "uniaxial_strain":
            ratio = "uniaxial_strain"
        elif isinstance(value, str):
            table.error(
                "ratio_xx",
                f'expected a number or "uniaxial_strain", got {show(value)}',
            )
        else:
            ratio = table.number(
                "ratio_xx",
                rule=Range(0.0, 100.0),
                hint=' (a ratio of effective stresses, or "uniaxial_strain")',
            )
    else:
        xx = table.number(
            "xx", hint=" (or ratio_xx = sigma'_xx / sigma'_yy, with a datum)"
        )
        gradient_xx = _gradient(table, "gradient_xx", 0.0)
    if len(table.problems) > start or datum is None:
        return None
    return InSituSpec(
        datum=datum,
        yy=yy,
        gradient_yy=gradient_yy,
        gravity=gravity,
        xx=xx,
        gradient_xx=gradient_xx,
        ratio_xx=ratio,
        xy=xy,
    )


def _read_loading(root: Table, needs_stress: list[str]) -> LoadingSpec | None:
    """[loading]; ``stress`` is required when an edge carries a traction,
    unless the in-situ stress varies with depth (its edges keep it)."""
    table = root.table("loading", ("stress", "initial_stress", "steps"))
    if table is None:
        return None
    start = len(table.problems)
    stress = _read_stress(table, "stress")
    in_situ = None
    if _depth_dependent(table):
        in_situ = _read_in_situ(table)
        initial_stress = None
        if table.has("stress"):
            table.error(
                "stress",
                "is a uniform far-field stress, and loading.initial_stress "
                "varies with depth: leave loading.stress out (traction edges "
                "keep their in-situ traction)",
            )
    else:
        initial_stress = _read_stress(table, "initial_stress")
        if needs_stress and not table.has("stress"):
            edges = ", ".join(f"boundary.{e}" for e in needs_stress)
            table.error(
                "stress",
                f"required key missing: {edges} carries a traction = "
                "loading.stress . n",
            )
    steps = table.integer("steps", 1, Range(1, MAX_STEPS))
    if len(table.problems) > start:
        return None
    return LoadingSpec(
        stress=stress, initial_stress=initial_stress, steps=steps, in_situ=in_situ
    )


def _check_densities(root: Table, loading, material, units) -> None:
    """``gravity`` needs a density everywhere: [material] and every unit."""
    if loading is None or loading.in_situ is None or loading.in_situ.gravity is None:
        return
    if material is not None and material.density is None:
        root.problems.append(
            (
                "material.density",
                "required key missing: loading.initial_stress.gravity integrates "
                "the densities [kg/m^3] of the rock above each point",
            )
        )


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
            f'expected a non-empty array of formats ("h5", "vtu", "csv"), got '
            f"{show(value)}",
        )
        return None
    key = table.key("formats")
    formats = complete(
        [
            check_choice(v, f"{key}[{i}]", table.problems, OUTPUT_FORMATS)
            for i, v in enumerate(value)
        ]
    )
    if formats is None:
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


def _graded(root: Table, grid, fractures, reservoir, units):
    """The grid, with a graded mesh built around the fractures and the rock
    units once they are read (xfemslip.case.grading: each fracture's extents,
    the units' horizons on mesh rows, their edges); anything else unchanged."""
    if grid is None or grid.mesh is not None:
        return grid
    failed = (reservoir is None and root.has("reservoir")) or (
        units is None and root.has("units")
    )
    if fractures is None or failed:
        return None  # their problems are recorded; nothing to refine
    if reservoir is not None:
        units = (reservoir_unit(reservoir),)
    features = combine(
        case_refinement(grid, fractures, None),
        unit_refinement(units or (), grid.origin, grid.size),
    )
    return graded_grid(grid, features, root.problems, root.key("mesh.size"))


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
    if formats is None:
        return None
    if directory is not None:
        path = Path(directory)
    elif table.has("directory") or name is None:
        return None
    else:
        path = Path("out") / name
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
    problems: list[tuple[str, str]] = []
    document = convert_units(parse_toml(text, path), problems)
    refused = len(problems)
    root = Table(document, "", problems, TOP_KEYS)
    name = _read_name(root, path)
    grid = read_grid(root)
    material = _read_material(root)
    fractures = read_fractures(root, grid)
    fractures = _with_network(root, grid, folder, fractures)
    reservoir = read_reservoir(root)
    units = read_units(root, fractures, material)
    grid = _graded(root, grid, fractures, reservoir, units)
    units, reservoir = settle_units(root, units, reservoir, fractures, grid)
    boundary, needs_stress = read_boundary(root, grid, folder)
    loading = _read_loading(root, needs_stress)
    solver = _read_solver(root)
    output = _read_output(root, name)
    datum = loading.in_situ.datum if loading and loading.in_situ else None
    pore_pressure = read_pore_pressure(root, datum, folder)
    if reservoir is not None:
        units = (reservoir_unit(reservoir),)
    check_region(root, pore_pressure, units)
    _check_densities(root, loading, material, units)
    events = read_events(root)
    permeability = read_permeability(root, grid, fractures)
    if problems:
        raise CaseError(path, first_problems(problems) if refused else problems)
    # each reader returns None only after recording a problem
    assert (
        name is not None
        and material is not None
        and loading is not None
        and boundary is not None
        and solver is not None
        and output is not None
    )
    spec = CaseSpec(
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
        units=units or (),
        events=events,
        permeability=permeability,
    )
    return replace(spec, loaded=digest(spec))
