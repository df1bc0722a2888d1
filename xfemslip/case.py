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
"""

from __future__ import annotations

import difflib
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, NamedTuple

import numpy as np

from xfemslip.errors import CaseError

EDGES = ("bottom", "top", "left", "right")


@dataclass(frozen=True, kw_only=True)
class MeshSpec:
    """Rectilinear structured Q4 mesh: node coordinates along x and y."""

    x: np.ndarray  # (nx+1,) float64, strictly increasing [m]
    y: np.ndarray  # (ny+1,) float64, strictly increasing [m]
    UNITS: ClassVar[dict[str, str]] = {"x": "m", "y": "m"}


@dataclass(frozen=True, kw_only=True)
class MaterialSpec:
    E: float  # Young's modulus [Pa]
    nu: float  # Poisson's ratio [-]
    model: str  # "plane_strain" | "plane_stress"
    UNITS: ClassVar[dict[str, str]] = {"E": "Pa", "nu": "-", "model": ""}


@dataclass(frozen=True, kw_only=True)
class FractureSpec:
    index: int  # position in the case file's [[fractures]] array
    points: np.ndarray  # (k, 2) float64 polyline vertices, k >= 2 [m]
    friction: float  # Coulomb coefficient f [-]
    cohesion: float  # c_f [Pa]
    kn: float  # normal penalty [Pa/m]
    kt: float  # tangential penalty [Pa/m]
    tip: str = "branch"  # crack-tip treatment: "branch" | "ramp"
    tip_radius: float | None = None  # branch enrichment radius [m]; None = automatic
    UNITS: ClassVar[dict[str, str]] = {
        "points": "m",
        "tip_radius": "m",
        "friction": "-",
        "cohesion": "Pa",
        "kn": "Pa/m",
        "kt": "Pa/m",
    }


@dataclass(frozen=True, kw_only=True)
class LoadingSpec:
    stress: tuple[float, float, float] | None  # final far-field (xx, yy, xy) [Pa]
    initial_stress: tuple[float, float, float] | None  # in-situ (xx, yy, xy) [Pa]
    steps: int
    UNITS: ClassVar[dict[str, str]] = {
        "stress": "Pa",
        "initial_stress": "Pa",
        "steps": "-",
    }


@dataclass(frozen=True, kw_only=True)
class EdgeSpec:
    """One edge's boundary condition.

    kind: "traction" (traction = loading.stress . n), "free" (no traction), or
    "displacement".  For "displacement": ``values`` holds the prescribed final
    displacement at every node of the edge, ordered by increasing coordinate
    along the edge (shape (n_edge_nodes, 2), NaN where a component is free);
    ``traction`` says whether the free component carries loading.stress . n.
    ``source`` is "table" or the CSV file's path; for an edge left out of
    ``[boundary]`` (hence "free") it is "default".
    """

    kind: str
    values: np.ndarray | None = None  # (n_edge_nodes, 2) float64 [m], NaN = free
    traction: bool = False
    source: str = ""
    UNITS: ClassVar[dict[str, str]] = {"values": "m"}


@dataclass(frozen=True, kw_only=True)
class BoundarySpec:
    bottom: EdgeSpec
    top: EdgeSpec
    left: EdgeSpec
    right: EdgeSpec


@dataclass(frozen=True, kw_only=True)
class SolverSpec:
    tolerance: float = 1.0e-8  # eta_0 on ||residual|| / ||F_ext||
    max_iterations: int = 30  # Newton iterations per load step
    tangent: str = "consistent"  # "consistent" | "secant" (paper eq. 28)
    UNITS: ClassVar[dict[str, str]] = {
        "tolerance": "-",
        "max_iterations": "-",
        "tangent": "",
    }


@dataclass(frozen=True, kw_only=True)
class OutputSpec:
    directory: Path  # resolved: output.directory, else out/<name> (relative to cwd)
    formats: tuple[str, ...] = ("h5", "vtu")


@dataclass(frozen=True, kw_only=True)
class CaseSpec:
    path: Path  # the case file
    text: str  # the case file's text as read
    name: str
    origin: tuple[float, float]  # lower-left corner [m]
    size: tuple[float, float]  # width, height [m]
    mesh: MeshSpec
    material: MaterialSpec
    fractures: tuple[FractureSpec, ...] = field(default_factory=tuple)
    loading: LoadingSpec
    boundary: BoundarySpec
    solver: SolverSpec
    output: OutputSpec


# --------------------------------------------------------------------------- #
# Constants and option tables
# --------------------------------------------------------------------------- #

TOP_KEYS = (
    "name",
    "domain",
    "mesh",
    "material",
    "fractures",
    "loading",
    "boundary",
    "solver",
    "output",
)
FRACTURE_KEYS = (
    "center",
    "length",
    "angle",
    "points",
    "friction",
    "cohesion",
    "kn",
    "kt",
    "tip",
)
TIP_KINDS = ("branch", "ramp")
TIP_KEYS = ("kind", "radius")
STRESS_KEYS = ("xx", "yy", "xy")
EDGE_KEYS = ("ux", "uy", "traction", "file")
EDGE_WORDS = ("traction", "free")
MATERIAL_MODELS = ("plane_strain", "plane_stress")
OUTPUT_FORMATS = ("h5", "vtu")
CSV_HEADER = ("x", "y", "ux", "uy")

# Memory guard: a Q4 element adds 64 stiffness triplets (8 B value + 2 x 8 B
# indices = 1.5 kB) before CSR conversion and factorisation; 2 kB per element
# is a lower bound, so 25 million elements already mean > 50 GB.
MAX_ELEMENTS = 25_000_000
BYTES_PER_ELEMENT = 2048
MAX_STEPS = 100_000
# Relative agreement of [domain] with mesh.x / mesh.y (rounding of typed values).
DOMAIN_RTOL = 1e-12
# CSV points count as on an edge / at its ends within this fraction of the
# largest domain size (rounding of coordinates printed by another program).
CSV_TOLERANCE = 1e-9
# At most this many row problems are listed per CSV file (then a count).
MAX_CSV_PROBLEMS = 10


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
)

_REQUIRED = object()  # sentinel default: the key must be given
_POSITIVE = Range(0.0, lo_open=True)
_NON_NEGATIVE = Range(0.0)


# --------------------------------------------------------------------------- #
# Value checks: each returns the clean value, or None after recording a problem
# --------------------------------------------------------------------------- #


def _show(value: Any) -> str:
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


def _exact(value: float) -> str:
    """Shortest text that reads back to the same float (numpy scalars too)."""
    return repr(float(value))


def _fmt(value: float) -> str:
    """Short form of a number for messages and summaries."""
    return str(value) if isinstance(value, int) else f"{value:.6g}"


def _range_problem(value: float, rule: Range | None, label: str) -> str | None:
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
    if rule.hi is None:
        text = f"must be {'>' if rule.lo_open else '>='} {_fmt(rule.lo)}"
    elif rule.lo is None:
        text = f"must be {hi_op} {_fmt(rule.hi)}"
    else:
        text = f"must satisfy {_fmt(rule.lo)} {lo_op} {label} {hi_op} {_fmt(rule.hi)}"
    return f"{text}, got {value!r}"


def _check_number(
    value: Any, key: str, problems: list, rule: Range | None = None, label: str = ""
) -> float | None:
    """A finite float (TOML integers accepted, booleans not) within ``rule``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        problems.append((key, f"expected a number, got {_show(value)}"))
        return None
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        problems.append((key, f"must be finite, got {number!r}"))
        return None
    message = _range_problem(number, rule, label or key.rsplit(".", 1)[-1])
    if message:
        problems.append((key, message))
        return None
    return number


def _check_integer(
    value: Any, key: str, problems: list, rule: Range | None = None, label: str = ""
) -> int | None:
    """A TOML integer (not a float, not a boolean) within ``rule``."""
    if isinstance(value, bool) or not isinstance(value, int):
        problems.append((key, f"expected an integer, got {_show(value)}"))
        return None
    message = _range_problem(value, rule, label or key.rsplit(".", 1)[-1])
    if message:
        problems.append((key, message))
        return None
    return value


def _suggest(word: str, allowed: tuple[str, ...]) -> str:
    """'; did you mean ...?' or the list of allowed words (pypa/build _find_typo)."""
    close = difflib.get_close_matches(word, allowed, n=1)
    if close:
        return f"; did you mean {close[0]!r}?"
    return "; allowed: " + ", ".join(allowed)


def _check_choice(
    value: Any, key: str, problems: list, choices: tuple[str, ...]
) -> str | None:
    """One of the strings ``choices``."""
    if not isinstance(value, str):
        allowed = ", ".join(f'"{c}"' for c in choices)
        problems.append((key, f"expected one of {allowed}, got {_show(value)}"))
        return None
    if value not in choices:
        allowed = ", ".join(f'"{c}"' for c in choices)
        close = difflib.get_close_matches(value, choices, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        problems.append((key, f"must be one of {allowed}, got {value!r}{hint}"))
        return None
    return value


def _check_vector(value: Any, key: str, problems: list, n: int, check) -> tuple | None:
    """An array of exactly ``n`` items, each passed through ``check(item, key)``."""
    if not isinstance(value, list) or len(value) != n:
        problems.append((key, f"expected an array of {n} numbers, got {_show(value)}"))
        return None
    items = [check(item, f"{key}[{i}]") for i, item in enumerate(value)]
    return None if any(item is None for item in items) else tuple(items)


def _frozen(values) -> np.ndarray:
    """A read-only float64 copy (specs are immutable, arrays included)."""
    array = np.array(values, dtype=np.float64)
    array.setflags(write=False)
    return array


class _Table:
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
        for name in data if allowed is not None else ():
            if name not in allowed:
                message = f"unknown key {name!r}{where}{_suggest(name, allowed)}"
                self.error(name, message)

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
        if default is _REQUIRED:
            self.error(name, "required key missing" + hint)
            return False, None
        return False, default

    def number(self, name, default=_REQUIRED, rule=None, hint=""):
        """A finite number (float) within ``rule``."""
        found, value = self._get(name, default, hint)
        if not found:
            return value
        return _check_number(value, self.key(name), self.problems, rule)

    def integer(self, name, default=_REQUIRED, rule=None):
        """An integer within ``rule``."""
        found, value = self._get(name, default)
        if not found:
            return value
        return _check_integer(value, self.key(name), self.problems, rule)

    def choice(self, name, choices, default=_REQUIRED):
        """One of the strings ``choices``."""
        found, value = self._get(name, default)
        if not found:
            return value
        return _check_choice(value, self.key(name), self.problems, choices)

    def boolean(self, name, default=_REQUIRED):
        """true or false."""
        found, value = self._get(name, default)
        if found and not isinstance(value, bool):
            self.error(name, f"expected true or false, got {_show(value)}")
            return None
        return value

    def string(self, name, default=_REQUIRED):
        """A non-empty string."""
        found, value = self._get(name, default)
        if found and (not isinstance(value, str) or not value.strip()):
            self.error(name, f"expected a non-empty string, got {_show(value)}")
            return None
        return value

    def numbers(self, name, n, default=_REQUIRED, rule=None, hint=""):
        """A fixed-length array of finite numbers, e.g. ``size = [1.0, 1.0]``."""
        found, value = self._get(name, default, hint)
        if not found:
            return value

        def check(item, key):
            return _check_number(item, key, self.problems, rule)

        return _check_vector(value, self.key(name), self.problems, n, check)

    def table(self, name, allowed, required=False) -> _Table | None:
        """Sub-table reader; an absent optional table reads as empty."""
        if name not in self.data:
            if required:
                self.error(name, "required key missing")
                return None
            return _Table({}, self.key(name), self.problems, present=False)
        value = self.data[name]
        if not isinstance(value, dict):
            self.error(name, f"expected a table, got {_show(value)}")
            return None
        return _Table(value, self.key(name), self.problems, allowed)


# --------------------------------------------------------------------------- #
# name, [domain], [mesh], [material]
# --------------------------------------------------------------------------- #


class _Grid(NamedTuple):
    """Resolved domain and mesh, shared by the checks that need geometry."""

    origin: tuple[float, float]
    size: tuple[float, float]
    mesh: MeshSpec


def _read_name(root: _Table, path: Path) -> str | None:
    """``name``, default the file's stem; it becomes a directory name."""
    name = root.string("name", path.stem)
    if name is None or not root.has("name"):
        return name
    if any(c in "/\\" or ord(c) < 32 for c in name):
        message = "must not contain a path separator or a control character"
        root.error("name", f"{message}, got {name!r} (it names the output directory)")
        return None
    return name


def _check_element_count(nx: int, ny: int, key: str, problems: list) -> bool:
    """Memory guard on nx * ny (see MAX_ELEMENTS)."""
    count = nx * ny
    if count <= MAX_ELEMENTS:
        return True
    gigabytes = count * BYTES_PER_ELEMENT / 1e9
    message = (
        f"{nx} x {ny} = {count} elements exceeds the limit of {MAX_ELEMENTS} "
        f"(would need at least ~{gigabytes:.3g} GB of memory, "
        f"~{BYTES_PER_ELEMENT // 1024} kB per element)"
    )
    problems.append((key, message))
    return False


def _read_axis(mesh: _Table, name: str) -> np.ndarray | None:
    """``mesh.x`` or ``mesh.y``: >= 2 strictly increasing finite numbers."""
    found, value = mesh._get(
        name, _REQUIRED, f" (mesh.{'y' if name == 'x' else 'x'} is given; give both)"
    )
    if not found:
        return None
    key = mesh.key(name)
    if not isinstance(value, list) or len(value) < 2:
        mesh.error(
            name, f"expected an array of >= 2 increasing numbers, got {_show(value)}"
        )
        return None
    items = [
        _check_number(v, f"{key}[{i}]", mesh.problems) for i, v in enumerate(value)
    ]
    if any(v is None for v in items):
        return None
    coords = np.array(items, dtype=np.float64)
    with np.errstate(over="ignore"):
        bad = np.flatnonzero(np.diff(coords) <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        mesh.error(
            f"{name}[{i}]",
            f"must be > {name}[{i - 1}] = {_exact(coords[i - 1])} "
            f"(strictly increasing), got {_exact(coords[i])}",
        )
        return None
    return coords


@np.errstate(over="ignore")
def _axis_resolves(coords: np.ndarray, key: str, problems: list) -> bool:
    """Resolved node coordinates must stay finite and strictly increasing."""
    if (
        np.isfinite(coords).all()
        and np.isfinite(coords[-1] - coords[0])
        and (np.diff(coords) > 0.0).all()
    ):
        return True
    message = (
        f"node coordinates from {_exact(coords[0])} to {_exact(coords[-1])} are not "
        "finite and strictly increasing in float64 (sizes too small relative to the "
        "origin, or too large)"
    )
    problems.append((key, message))
    return False


def _domain_agrees(domain: _Table, name: str, given, expected, scale: float) -> None:
    """Record a problem if ``domain.<name>`` differs from the mesh's value."""
    if given is None or all(
        abs(g - e) <= DOMAIN_RTOL * scale for g, e in zip(given, expected, strict=True)
    ):
        return
    domain.error(
        name,
        f"disagrees with mesh.x / mesh.y: expected "
        f"[{_exact(expected[0])}, {_exact(expected[1])}], got "
        f"[{_exact(given[0])}, {_exact(given[1])}] (or leave [domain] out)",
    )


def _mesh_from_axes(mesh: _Table, domain: _Table | None, size, origin) -> _Grid | None:
    """Explicit rectilinear mesh; a given [domain] must agree with it."""
    x, y = _read_axis(mesh, "x"), _read_axis(mesh, "y")
    if x is None or y is None:
        return None
    if not _check_element_count(x.size - 1, y.size - 1, mesh.key("x"), mesh.problems):
        return None
    x_ok = _axis_resolves(x, mesh.key("x"), mesh.problems)
    y_ok = _axis_resolves(y, mesh.key("y"), mesh.problems)
    if not (x_ok and y_ok):
        return None
    mesh_origin = (float(x[0]), float(y[0]))
    mesh_size = (float(x[-1] - x[0]), float(y[-1] - y[0]))
    if domain is not None:
        scale = float(max(np.abs(x).max(), np.abs(y).max(), *mesh_size))
        _domain_agrees(domain, "size", size, mesh_size, scale)
        if domain.has("origin"):
            _domain_agrees(domain, "origin", origin, mesh_origin, scale)
    return _Grid(mesh_origin, mesh_size, MeshSpec(x=_frozen(x), y=_frozen(y)))


def _mesh_uniform(mesh: _Table, domain: _Table | None, size, origin) -> _Grid | None:
    """``elements = [nx, ny]`` over ``domain.size``: uniform node coordinates."""
    counts = _check_vector(
        mesh.data["elements"],
        mesh.key("elements"),
        mesh.problems,
        2,
        lambda v, k: _check_integer(v, k, mesh.problems, Range(1)),
    )
    if domain is not None and not domain.has("size"):
        domain.error("size", "required key missing (mesh.elements needs domain.size)")
    if counts is None or size is None or origin is None:
        return None
    if not _check_element_count(*counts, mesh.key("elements"), mesh.problems):
        return None
    with np.errstate(over="ignore"):
        x = origin[0] + size[0] * np.linspace(0.0, 1.0, counts[0] + 1)
        y = origin[1] + size[1] * np.linspace(0.0, 1.0, counts[1] + 1)
    key = domain.key("size") if domain is not None else "domain.size"
    x_ok = _axis_resolves(x, key, mesh.problems)
    y_ok = _axis_resolves(y, key, mesh.problems)
    if not (x_ok and y_ok):
        return None
    return _Grid(origin, size, MeshSpec(x=_frozen(x), y=_frozen(y)))


def _read_grid(root: _Table) -> _Grid | None:
    """[domain] and [mesh] -> origin, size and node coordinates."""
    domain = root.table("domain", ("size", "origin"))
    size = origin = None
    if domain is not None:
        size = domain.numbers("size", 2, None, _POSITIVE)
        origin = domain.numbers("origin", 2, (0.0, 0.0))
    mesh = root.table("mesh", ("elements", "x", "y"), required=True)
    if mesh is None:
        return None
    has_axes = mesh.has("x") or mesh.has("y")
    if mesh.has("elements") and has_axes:
        mesh.error(None, "give either elements = [nx, ny] or x and y, not both")
        return None
    if has_axes:
        return _mesh_from_axes(mesh, domain, size, origin)
    if mesh.has("elements"):
        return _mesh_uniform(mesh, domain, size, origin)
    mesh.error(
        None,
        "required key missing: give elements = [nx, ny] (with "
        "domain.size) or node coordinates x and y",
    )
    return None


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
# [[fractures]]
# --------------------------------------------------------------------------- #


def _cos_sin_degrees(angle: float) -> tuple[float, float]:
    """cos and sin of ``angle`` [deg], exact at multiples of 45 degrees.

    math.cos(math.pi / 2) is 6e-17, not 0, and cos/sin(pi/4) differ in the last
    bit: reducing to [0, 45] and rotating by quarter turns keeps vertical,
    horizontal and diagonal fractures exactly on their lines.
    """
    turns, rest = divmod(angle, 90.0)  # rest in [0, 90)
    if rest == 45.0:
        c = s = math.sqrt(0.5)
    elif rest < 45.0:
        c, s = math.cos(math.radians(rest)), math.sin(math.radians(rest))
    else:  # 90 - rest is exact here (Sterbenz)
        s, c = math.cos(math.radians(90.0 - rest)), math.sin(math.radians(90.0 - rest))
    for _ in range(int(turns) % 4):
        c, s = -s, c  # rotate by +90 degrees
    return c + 0.0, s + 0.0  # + 0.0 turns -0.0 into 0.0


def _read_points(table: _Table) -> np.ndarray | None:
    """``points``: an array of >= 2 points, each two finite numbers [m]."""
    value = table.data["points"]
    key = table.key("points")
    if not isinstance(value, list) or len(value) < 2:
        table.error(
            "points", f"expected an array of >= 2 points [x, y], got {_show(value)}"
        )
        return None

    def check(v, k):
        return _check_number(v, k, table.problems)

    points = [
        _check_vector(p, f"{key}[{i}]", table.problems, 2, check)
        for i, p in enumerate(value)
    ]
    return (
        None if any(p is None for p in points) else np.array(points, dtype=np.float64)
    )


def _fracture_points(table: _Table) -> np.ndarray | None:
    """Polyline vertices from ``points`` or from ``center``/``length``/``angle``."""
    given = [k for k in ("center", "length", "angle") if table.has(k)]
    if given and table.has("points"):
        table.error(
            None,
            "give either points or center, length and angle, not both "
            f"(got points and {', '.join(given)})",
        )
        return None
    if table.has("points"):
        return _read_points(table)
    if not given:
        table.error(
            "points",
            "required key missing: give points = [[x0, y0], "
            "[x1, y1], ...] or center, length and angle",
        )
        return None
    hint = f" ({', '.join(given)} given: center, length and angle go together)"
    center = table.numbers("center", 2, hint=hint)
    length = table.number("length", rule=_POSITIVE, hint=hint)
    angle = table.number("angle", hint=hint)
    if center is None or length is None or angle is None:
        return None
    c, s = _cos_sin_degrees(angle)
    with np.errstate(over="ignore", invalid="ignore"):
        half = 0.5 * length * np.array([c, s])
        points = np.array([np.asarray(center) - half, np.asarray(center) + half])
    if not np.isfinite(points).all():
        table.error(
            "length",
            f"center -/+ length/2 (cos angle, sin angle) overflows, "
            f"got length {_exact(length)}",
        )
        return None
    return points


def _orientation(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Sign of the cross product (b - a) x (c - a); arrays (..., 2)."""
    ab, ac = b - a, c - a
    return np.sign(ab[..., 0] * ac[..., 1] - ab[..., 1] * ac[..., 0])


def _in_box(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Whether c lies in the bounding box of segment a-b; arrays (..., 2)."""
    return np.all((np.minimum(a, b) <= c) & (c <= np.maximum(a, b)), axis=-1)


@np.errstate(over="ignore", invalid="ignore")
def _self_intersection(points: np.ndarray) -> tuple[int, int] | None:
    """First pair (i, j) of segments that cross, touch or fold back, else None."""
    a, b = points[:-1], points[1:]
    n = len(a)
    for i in range(n - 1):
        # Adjacent segments share b[i]; they overlap only if the path turns back.
        turn = b[i] - a[i], b[i + 1] - a[i + 1]
        if _orientation(a[i], b[i], b[i + 1]) == 0 and float(np.dot(*turn)) < 0.0:
            return i, i + 1
        p, q, r, s = a[i], b[i], a[i + 2 :], b[i + 2 :]
        if not len(r):
            continue
        o1, o2 = _orientation(p, q, r), _orientation(p, q, s)
        o3, o4 = _orientation(r, s, p), _orientation(r, s, q)
        hit = (
            ((o1 * o2) < 0) & ((o3 * o4) < 0)
            | (o1 == 0) & _in_box(p, q, r)
            | (o2 == 0) & _in_box(p, q, s)
            | (o3 == 0) & _in_box(r, s, p)
            | (o4 == 0) & _in_box(r, s, q)
        )
        if hit.any():
            return i, i + 2 + int(np.flatnonzero(hit)[0])
    return None


def _segment_meets_box(a: np.ndarray, b: np.ndarray, lo, hi) -> bool:
    """Whether segment a-b has a point in the closed box [lo, hi] (Liang-Barsky)."""
    t0, t1 = 0.0, 1.0
    for axis in (0, 1):
        # Python floats: an overflow gives inf, which the min/max below handle.
        d = float(b[axis]) - float(a[axis])
        if d == 0.0:
            if not lo[axis] <= a[axis] <= hi[axis]:
                return False
            continue
        ta = (float(lo[axis]) - float(a[axis])) / d
        tb = (float(hi[axis]) - float(a[axis])) / d
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    return t0 <= t1


@np.errstate(over="ignore")
def _check_polyline(table: _Table, points: np.ndarray, grid: _Grid | None) -> None:
    """Zero-length segments, self-intersection, and a fracture off the domain."""
    name = "points" if table.has("points") else "length"
    lengths = np.hypot(*np.diff(points, axis=0).T)
    if not lengths.any():
        table.error(name, "fracture has zero length (all its points coincide)")
        return
    for j in np.flatnonzero(lengths == 0.0):
        x, y = points[j]
        table.error(
            f"points[{j + 1}]",
            f"repeats the previous point ({_exact(x)}, {_exact(y)}): "
            "zero-length segment",
        )
    if not lengths.all():
        return
    pair = _self_intersection(points)
    if pair is not None:
        table.error(
            "points",
            f"self-intersecting polyline: segments {pair[0]} and "
            f"{pair[1]} touch or cross",
        )
    if grid is None:
        return
    lo = grid.origin
    hi = (lo[0] + grid.size[0], lo[1] + grid.size[1])
    if not any(
        _segment_meets_box(a, b, lo, hi)
        for a, b in zip(points[:-1], points[1:], strict=True)
    ):
        table.error(
            None,
            f"lies outside the domain [{_fmt(lo[0])}, {_fmt(hi[0])}] x "
            f"[{_fmt(lo[1])}, {_fmt(hi[1])}]",
        )


def _read_fracture(
    table: _Table, index: int, grid: _Grid | None
) -> FractureSpec | None:
    """One [[fractures]] entry."""
    start = len(table.problems)
    points = _fracture_points(table)
    friction = table.number("friction", rule=_NON_NEGATIVE)
    cohesion = table.number("cohesion", 0.0, rule=_NON_NEGATIVE)
    kn = table.number("kn", rule=_POSITIVE)
    kt = table.number("kt", rule=_POSITIVE)
    tip, radius = _read_tip(table)
    if points is not None:
        _check_polyline(table, points, grid)
    if len(table.problems) > start:
        return None
    return FractureSpec(
        index=index,
        points=_frozen(points),
        friction=friction,
        cohesion=cohesion,
        kn=kn,
        kt=kt,
        tip=tip,
        tip_radius=radius,
    )


def _read_tip(table: _Table) -> tuple[str, float | None]:
    """``tip = "branch"`` / ``"ramp"``, or ``tip = { kind = .., radius = .. }``.

    branch: near-tip branch functions on the nodes within ``radius`` (m) of each
    tip (default: 4 tip-cell sizes); ramp: the jump falls linearly to zero
    across the tip cell.  Default "branch".
    """
    if not table.has("tip"):
        return "branch", None
    value = table.data["tip"]
    if isinstance(value, dict):
        sub = _Table(value, table.key("tip"), table.problems, TIP_KEYS)
        kind = sub.choice("kind", TIP_KINDS, "branch")
        radius = sub.number("radius", None, rule=_POSITIVE)
        if radius is not None and kind == "ramp":
            sub.error("radius", 'only used with kind = "branch"')
        return kind, radius
    return table.choice("tip", TIP_KINDS), None


def _read_fractures(
    root: _Table, grid: _Grid | None
) -> tuple[FractureSpec, ...] | None:
    """``[[fractures]]``: zero or more fracture tables."""
    value = root.data.get("fractures", [])
    if not isinstance(value, list):
        root.error(
            "fractures",
            f"expected an array of tables [[fractures]], got "
            f"{_show(value)} (write [[fractures]], not [fractures])",
        )
        return None
    specs = []
    for i, item in enumerate(value):
        if not isinstance(item, dict):
            root.error(f"fractures[{i}]", f"expected a table, got {_show(item)}")
            specs.append(None)
            continue
        table = _Table(item, f"fractures[{i}]", root.problems, FRACTURE_KEYS)
        specs.append(_read_fracture(table, i, grid))
    return None if any(s is None for s in specs) else tuple(specs)


# --------------------------------------------------------------------------- #
# [boundary] and boundary CSV files
# --------------------------------------------------------------------------- #


class _EdgeFrame(NamedTuple):
    """Where an edge is: coordinate axis along it, fixed coordinate across it."""

    along: int  # 0: the edge runs along x (bottom, top); 1: along y
    at: float  # the fixed coordinate (y of bottom/top, x of left/right) [m]
    nodes: np.ndarray  # node coordinates along the edge, increasing [m]


def _edge_frame(edge: str, grid: _Grid) -> _EdgeFrame:
    """Geometry of one edge of the rectilinear mesh."""
    x, y = grid.mesh.x, grid.mesh.y
    return {
        "bottom": _EdgeFrame(0, float(y[0]), x),
        "top": _EdgeFrame(0, float(y[-1]), x),
        "left": _EdgeFrame(1, float(x[0]), y),
        "right": _EdgeFrame(1, float(x[-1]), y),
    }[edge]


def _csv_row(line: str) -> list[float] | str:
    """Four finite numbers of one CSV row, or what is wrong with it."""
    fields = line.split(",")
    if len(fields) != 4:
        return f"expected 4 values x,y,ux,uy, got {len(fields)}: {line.strip()!r}"
    row = []
    for name, text in zip(CSV_HEADER, fields, strict=True):
        try:
            value = float(text)
        except ValueError:
            return f"{name} is not a number: {text.strip()!r}"
        if not math.isfinite(value):
            return f"{name} must be finite, got {text.strip()!r}"
        row.append(value)
    return row


def _read_csv(file: Path, key: str, problems: list) -> tuple[np.ndarray, list] | None:
    """Rows (m, 4) ``[x, y, ux, uy]`` of a boundary CSV file and their line numbers."""
    try:
        lines = file.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        problems.append(
            (key, f"cannot read {file}: {getattr(exc, 'strerror', None) or exc}")
        )
        return None
    header = tuple(c.strip().lower() for c in lines[0].split(",")) if lines else ()
    if header != CSV_HEADER:
        got = repr(lines[0].strip()) if lines else "an empty file"
        problems.append((key, f"{file} line 1: header must be x,y,ux,uy, got {got}"))
        return None
    rows, numbers, bad = [], [], []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        row = _csv_row(line)
        if isinstance(row, str):
            bad.append(f"{file} line {number}: {row}")
        else:
            rows.append(row)
            numbers.append(number)
    _add_capped(problems, key, bad)
    if bad:
        return None
    return np.array(rows, dtype=np.float64).reshape(-1, 4), numbers


def _add_capped(problems: list, key: str, messages: list[str]) -> None:
    """Record at most MAX_CSV_PROBLEMS messages, then how many were left out."""
    problems.extend((key, m) for m in messages[:MAX_CSV_PROBLEMS])
    if len(messages) > MAX_CSV_PROBLEMS:
        problems.append((key, f"... and {len(messages) - MAX_CSV_PROBLEMS} more rows"))


def _csv_points_on_edge(rows, numbers, frame, edge, file, tol) -> list[str]:
    """Messages for points off the edge's line or beyond its ends."""
    axis = "xy"[frame.along]
    across = "yx"[frame.along]
    lo, hi = float(frame.nodes[0]), float(frame.nodes[-1])
    bad = []
    for (x, y, _, _), number in zip(rows, numbers, strict=True):
        s, t = (x, y) if frame.along == 0 else (y, x)
        where = f"{file} line {number}: point ({_exact(x)}, {_exact(y)})"
        if abs(t - frame.at) > tol:
            bad.append(
                f"{where} is not on the {edge} edge ({across} = {_exact(frame.at)})"
            )
        elif s < lo - tol or s > hi + tol:
            bad.append(
                f"{where} lies beyond the {edge} edge "
                f"({axis} in [{_exact(lo)}, {_exact(hi)}])"
            )
    return bad


def _csv_edge_values(rows, numbers, frame, edge, file, tol) -> np.ndarray | str:
    """Interpolate the CSV values to the edge's nodes, or say what is wrong."""
    s = rows[:, frame.along]
    order = np.argsort(s, kind="stable")
    s, values, numbers = s[order], rows[order, 2:], [numbers[i] for i in order]
    close = np.flatnonzero(np.diff(s) <= tol)
    for i in close:
        if np.any(values[i] != values[i + 1]):
            first, second = (", ".join(map(_exact, v)) for v in values[i : i + 2])
            return (
                f"{file} lines {numbers[i]} and {numbers[i + 1]}: the same point "
                f"with different values (ux, uy) = ({first}) and ({second})"
            )
    keep = np.ones(s.size, dtype=bool)
    keep[close + 1] = False
    s, values = s[keep], values[keep]
    if s.size < 2:
        return f"{file}: needs at least 2 distinct points along the edge, got {s.size}"
    lo, hi = float(frame.nodes[0]), float(frame.nodes[-1])
    if s[0] > lo + tol or s[-1] < hi - tol:
        axis = "xy"[frame.along]
        return (
            f"{file}: points cover {axis} in [{_exact(s[0])}, {_exact(s[-1])}] but "
            f"the {edge} edge spans [{_exact(lo)}, {_exact(hi)}]; the file must "
            "cover the edge end to end"
        )
    return np.column_stack(
        [
            np.interp(frame.nodes, s, values[:, 0]),
            np.interp(frame.nodes, s, values[:, 1]),
        ]
    )


def _edge_from_csv(table: _Table, edge: str, grid: _Grid | None, folder: Path):
    """``{ file = "edge.csv" }``: both components at every node, from the file."""
    for other in ("ux", "uy", "traction"):
        if table.has(other):
            table.error(
                other,
                "cannot be combined with file (the file prescribes both components)",
            )
    name = table.string("file")
    if name is None:
        return None
    file = folder / name
    key = table.key("file")
    start = len(table.problems)
    parsed = _read_csv(file, key, table.problems)
    if parsed is None or grid is None or len(table.problems) > start:
        return None
    rows, numbers = parsed
    frame = _edge_frame(edge, grid)
    tol = CSV_TOLERANCE * max(grid.size)
    bad = _csv_points_on_edge(rows, numbers, frame, edge, file, tol)
    _add_capped(table.problems, key, bad)
    if bad:
        return None
    values = _csv_edge_values(rows, numbers, frame, edge, file, tol)
    if isinstance(values, str):
        table.error("file", values)
        return None
    return EdgeSpec(kind="displacement", values=_frozen(values), source=str(file))


def _edge_from_table(table: _Table, edge: str, grid: _Grid | None):
    """``{ ux = .., uy = .., traction = .. }``: prescribed components."""
    start = len(table.problems)
    ux, uy = table.number("ux", None), table.number("uy", None)
    traction = table.boolean("traction", False)
    given = [c for c in ("ux", "uy") if table.has(c)]
    if not given:
        table.error(
            None,
            'prescribes nothing: give ux and/or uy, or file = "..."; '
            'for no constraint write "free" or "traction"',
        )
        return None
    if traction and len(given) == 2:
        table.error(
            "traction",
            "traction = true needs a free component, but ux and uy are both prescribed",
        )
        return None
    if len(table.problems) > start or grid is None:
        return None
    values = np.full((_edge_frame(edge, grid).nodes.size, 2), np.nan)  # NaN: free
    for component, value in enumerate((ux, uy)):
        if value is not None:
            values[:, component] = value
    return EdgeSpec(
        kind="displacement", values=_frozen(values), traction=traction, source="table"
    )


def _read_edge(boundary: _Table, edge: str, grid: _Grid | None, folder: Path):
    """One edge entry -> EdgeSpec (None after recording a problem)."""
    if not boundary.has(edge):
        return EdgeSpec(kind="free", source="default")
    value = boundary.data[edge]
    if isinstance(value, str) and value in EDGE_WORDS:
        return EdgeSpec(kind=value)
    if not isinstance(value, dict):
        close = (
            difflib.get_close_matches(value, EDGE_WORDS, n=1)
            if isinstance(value, str)
            else []
        )
        hint = f"; did you mean {close[0]!r}?" if close else ""
        boundary.error(
            edge,
            f'must be "traction", "free", a table such as '
            f'{{ ux = 0.0, uy = 0.0 }} or {{ file = "{edge}.csv" }}, '
            f"got {_show(value)}{hint}",
        )
        return None
    table = boundary.table(edge, EDGE_KEYS)
    if table.has("file"):
        return _edge_from_csv(table, edge, grid, folder)
    return _edge_from_table(table, edge, grid)


def _read_boundary(root: _Table, grid: _Grid | None, folder: Path):
    """[boundary] -> (BoundarySpec or None, edges that need loading.stress)."""
    table = root.table("boundary", EDGES, required=True)
    if table is None:
        return None, []
    edges = {edge: _read_edge(table, edge, grid, folder) for edge in EDGES}
    needs_stress = [
        e
        for e in EDGES
        if edges[e] is not None and (edges[e].kind == "traction" or edges[e].traction)
    ]
    if any(spec is None for spec in edges.values()):
        return None, needs_stress
    if not any(spec.kind == "displacement" for spec in edges.values()):
        table.error(
            None,
            "no displacement is prescribed on any edge: the body can move "
            "freely; prescribe at least one component (e.g. bottom = "
            "{ uy = 0.0 })",
        )
        return None, needs_stress
    return BoundarySpec(**edges), needs_stress


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


def _read_output(root: _Table, name: str | None) -> OutputSpec | None:
    """[output]: directory (default out/<name>, relative to the cwd) and formats."""
    table = root.table("output", ("directory", "formats"))
    if table is None:
        return None
    directory = table.string("directory", None)
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
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise CaseError(
            path, [("", f"cannot read the case file: {exc.strerror or exc}")]
        ) from None
    except UnicodeDecodeError as exc:
        raise CaseError(
            path, [("", f"not a UTF-8 text file: {exc.reason} at byte {exc.start}")]
        ) from None
    return loads_case(text, path)


def loads_case(text: str, path: str | Path = "<string>") -> CaseSpec:
    """Validate and resolve case-file ``text``; ``path`` names it in messages,
    gives the default ``name`` (its stem) and the folder of CSV files."""
    path = Path(path)
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(path, [("", f"TOML syntax error: {exc}")]) from None
    problems: list[tuple[str, str]] = []
    root = _Table(document, "", problems, TOP_KEYS)
    name = _read_name(root, path)
    grid = _read_grid(root)
    material = _read_material(root)
    fractures = _read_fractures(root, grid)
    boundary, needs_stress = _read_boundary(root, grid, path.parent)
    loading = _read_loading(root, needs_stress)
    solver = _read_solver(root)
    output = _read_output(root, name)
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
    )


# --------------------------------------------------------------------------- #
# describe: the resolved SI summary printed by ``xfemslip check``
# --------------------------------------------------------------------------- #


def _with_unit(value: Any, unit: str) -> str:
    """``5e+09 Pa``; no unit for dimensionless ("-") or unitless ("") values."""
    text = _fmt(value) if isinstance(value, int | float) else str(value)
    return f"{text} {unit}" if unit not in ("", "-") else text


def _describe_axis(coords: np.ndarray, label: str) -> str:
    """Element sizes along one axis: uniform or graded (min .. max)."""
    h = np.diff(coords)
    unit = MeshSpec.UNITS[label]
    if np.ptp(h) <= 1e-9 * h.max():
        return f"d{label} = {_with_unit(float(h[0]), unit)} (uniform)"
    return (
        f"d{label} = {_fmt(float(h.min()))} .. {_with_unit(float(h.max()), unit)} "
        "(graded)"
    )


def _describe_fracture(spec: FractureSpec) -> list[str]:
    """Points, length, segment angles and contact parameters of one fracture."""
    p = spec.points
    seg = np.diff(p, axis=0)
    angles = np.degrees(np.arctan2(seg[:, 1], seg[:, 0]))
    units = FractureSpec.UNITS
    points = " -> ".join(f"({_fmt(float(x))}, {_fmt(float(y))})" for x, y in p)
    params = ", ".join(
        f"{k} = {_with_unit(getattr(spec, k), units[k])}"
        for k in ("friction", "cohesion", "kn", "kt")
    )
    tip = spec.tip + (
        f", radius {_with_unit(spec.tip_radius, units['tip_radius'])}"
        if spec.tip_radius is not None
        else (", radius 4 tip-cell sizes (automatic)" if spec.tip == "branch" else "")
    )
    return [
        f"  [{spec.index}] points [{units['points']}]: {points}",
        f"      length {_with_unit(float(np.hypot(*seg.T).sum()), units['points'])}, "
        f"angle {', '.join(_fmt(float(a)) for a in angles)} deg",
        f"      {params}",
        f"      tip: {tip}",
    ]


def _describe_edge(name: str, edge: EdgeSpec) -> str:
    """One edge's boundary condition."""
    if edge.kind == "traction":
        return f"  {name}: traction = loading.stress . n"
    if edge.kind == "free":
        note = " (not given in [boundary])" if edge.source == "default" else ""
        return f"  {name}: free (zero traction){note}"
    parts = []
    for c, label in enumerate(("ux", "uy")):
        column = edge.values[:, c]
        if np.isnan(column).all():
            extra = " (traction = loading.stress . n)" if edge.traction else ""
            parts.append(f"{label} free{extra}")
        elif np.ptp(column) == 0.0:
            parts.append(
                f"{label} = {_with_unit(float(column[0]), EdgeSpec.UNITS['values'])}"
            )
        else:
            parts.append(
                f"{label} = {_fmt(float(column.min()))} .. "
                f"{_with_unit(float(column.max()), EdgeSpec.UNITS['values'])}"
            )
    return (
        f"  {name}: displacement {', '.join(parts)} at {len(edge.values)} nodes "
        f"[{edge.source}]"
    )


def _describe_stress(stress: tuple[float, float, float] | None) -> str:
    """``(xx, yy, xy) = (...) Pa`` or none."""
    if stress is None:
        return "none"
    values = ", ".join(_fmt(v) for v in stress)
    return f"(xx, yy, xy) = ({values}) {LoadingSpec.UNITS['stress']}"


def describe(spec: CaseSpec) -> str:
    """Human-readable summary of a resolved case (SI units, tension positive).

    Printed by ``xfemslip check``: domain, mesh (element sizes, graded or not),
    material, fractures, loading, every edge's condition (edges not given in the
    file are reported as free), solver options (from SOLVER_OPTIONS) and output.
    """
    (x0, y0), (w, h) = spec.origin, spec.size
    nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
    m = spec.material
    lines = [
        f"case {spec.name!r} ({spec.path})",
        f"domain: [{_fmt(x0)}, {_fmt(x0 + w)}] x [{_fmt(y0)}, {_fmt(y0 + h)}] m "
        f"(size {_fmt(w)} x {_fmt(h)} m)",
        f"mesh: {nx} x {ny} Q4 elements, {(nx + 1) * (ny + 1)} nodes; "
        f"{_describe_axis(spec.mesh.x, 'x')}; {_describe_axis(spec.mesh.y, 'y')}",
        f"material: E = {_with_unit(m.E, MaterialSpec.UNITS['E'])}, nu = {_fmt(m.nu)}, "
        f"{m.model}",
        f"fractures: {len(spec.fractures)}",
    ]
    for fracture in spec.fractures:
        lines += _describe_fracture(fracture)
    steps = spec.loading.steps
    lines += [
        f"loading: stress {_describe_stress(spec.loading.stress)}; "
        f"initial_stress {_describe_stress(spec.loading.initial_stress)}; "
        f"{steps} step{'' if steps == 1 else 's'}",
        "boundary:",
    ]
    lines += [_describe_edge(e, getattr(spec.boundary, e)) for e in EDGES]
    lines.append("solver:")
    for option in SOLVER_OPTIONS:
        value = getattr(spec.solver, option.name)
        lines.append(
            f"  {option.name} = {_with_unit(value, SolverSpec.UNITS[option.name])}"
            f"  ({option.doc})"
        )
    lines.append(f"output: {spec.output.directory} ({', '.join(spec.output.formats)})")
    return "\n".join(lines)
