"""``[domain]`` and ``[mesh]`` -> origin, size and node coordinates (``Grid``).

``[mesh]`` takes one of three forms: ``elements = [nx, ny]`` (uniform),
``x`` and ``y`` (the node coordinates), or ``size`` with optional
``growth``, ``max_size`` and ``refine`` (a graded mesh).  A graded mesh
needs the fractures and the region edges it is refined around, so
``read_grid`` leaves its ``mesh`` None and ``xfemslip.case.grading``
builds it once those are read.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from xfemslip.case.specs import GradingSpec, MeshSpec
from xfemslip.case.tables import (
    COORDINATE,
    MAX_COORDINATE,
    POSITIVE,
    REQUIRED,
    Range,
    Table,
    check_integer,
    check_number,
    check_vector,
    exact,
    frozen,
    show,
)
from xfemslip.geometry.box import Box

# Memory guard: a Q4 element adds 64 stiffness triplets (8 B value + 2 x 8 B
# indices = 1.5 kB) before CSR conversion and factorisation; 2 kB per element
# is a lower bound, so 25 million elements already mean > 50 GB.
MAX_ELEMENTS = 25_000_000
BYTES_PER_ELEMENT = 2048
# Relative agreement of [domain] with mesh.x / mesh.y (rounding of typed values).
DOMAIN_RTOL = 1e-12
MESH_KEYS = ("elements", "x", "y", "size", "growth", "max_size", "refine")
GRADED_KEYS = ("size", "growth", "max_size", "refine")
# Neighbouring cells of a graded mesh differ by at most this ratio unless
# mesh.growth says otherwise (1.2: the usual choice of mesh generators; the
# stress error of a smoothly graded mesh is that of its finest cells).
DEFAULT_GROWTH = 1.2
GROWTH_RANGE = Range(1.0, 2.0, lo_open=True)


class Grid(NamedTuple):
    """Resolved domain and mesh, shared by the checks that need geometry.

    ``mesh`` is None while a graded mesh (``grading``) waits for its
    refinement features (xfemslip.case.grading.graded_grid).
    """

    origin: tuple[float, float]
    size: tuple[float, float]
    mesh: MeshSpec | None
    grading: GradingSpec | None = None

    @property
    def box(self) -> Box:
        """The domain [m]."""
        return Box.from_origin_size(self.origin, self.size)


def _int_text(n: int) -> str:
    """An integer of any size (TOML integers are unbounded, floats are not):
    exact up to 15 digits, else like 1.23e+400."""
    digits = str(n)
    if len(digits) <= 15:
        return digits
    return f"{digits[0]}.{digits[1:3]}e+{len(digits) - 1}"


def check_element_count(nx: int, ny: int, key: str, problems: list) -> bool:
    """Memory guard on nx * ny (see MAX_ELEMENTS)."""
    count = nx * ny
    if count <= MAX_ELEMENTS:
        return True
    gigabytes = count * BYTES_PER_ELEMENT // 10**9
    message = (
        f"{_int_text(nx)} x {_int_text(ny)} = {_int_text(count)} elements exceeds "
        f"the limit of {MAX_ELEMENTS} (would need at least ~{_int_text(gigabytes)} "
        f"GB of memory, ~{BYTES_PER_ELEMENT // 1024} kB per element)"
    )
    problems.append((key, message))
    return False


# The narrowest cell of an explicit axis, as a share of the mesh's extent:
# the geometry's tolerances scale with the cell sizes, and below this the
# ratio of extent to tolerance leaves float64.
MIN_CELL_SHARE = 1.0e-9


def _read_axis(mesh: Table, name: str) -> np.ndarray | None:
    """``mesh.x`` or ``mesh.y``: >= 2 strictly increasing finite numbers."""
    found, value = mesh._get(
        name, REQUIRED, f" (mesh.{'y' if name == 'x' else 'x'} is given; give both)"
    )
    if not found:
        return None
    key = mesh.key(name)
    if not isinstance(value, list) or len(value) < 2:
        mesh.error(
            name, f"expected an array of >= 2 increasing numbers, got {show(value)}"
        )
        return None
    items = [check_number(v, f"{key}[{i}]", mesh.problems) for i, v in enumerate(value)]
    if any(v is None for v in items):
        return None
    coords = np.array(items, dtype=np.float64)
    with np.errstate(over="ignore"):
        bad = np.flatnonzero(np.diff(coords) <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        mesh.error(
            f"{name}[{i}]",
            f"must be > {name}[{i - 1}] = {exact(coords[i - 1])} "
            f"(strictly increasing), got {exact(coords[i])}",
        )
        return None
    span = float(coords[-1] - coords[0])
    with np.errstate(over="ignore"):
        thin = np.flatnonzero(np.diff(coords) < MIN_CELL_SHARE * span)
    if thin.size:
        i = int(thin[0]) + 1
        mesh.error(
            f"{name}[{i}]",
            f"the cell from {name}[{i - 1}] = {exact(coords[i - 1])} to "
            f"{exact(coords[i])} is narrower than {MIN_CELL_SHARE:g} of the "
            f"mesh's extent ({span:g} m): the geometry's tolerances cannot "
            "resolve it",
        )
        return None
    return coords


@np.errstate(over="ignore")
def axis_resolves(coords: np.ndarray, key: str, problems: list) -> bool:
    """Resolved node coordinates must stay finite, strictly increasing and
    within MAX_COORDINATE."""
    if (
        np.isfinite(coords).all()
        and np.isfinite(coords[-1] - coords[0])
        and (np.diff(coords) > 0.0).all()
    ):
        if np.abs(coords).max() <= MAX_COORDINATE:
            return True
        problems.append(
            (
                key,
                f"node coordinates from {exact(coords[0])} to {exact(coords[-1])} "
                f"reach beyond +-{MAX_COORDINATE:g} m (squared distances in the "
                "geometry would overflow)",
            )
        )
        return False
    message = (
        f"node coordinates from {exact(coords[0])} to {exact(coords[-1])} are not "
        "finite and strictly increasing in float64 (sizes too small relative to the "
        "origin, or too large)"
    )
    problems.append((key, message))
    return False


def _domain_agrees(domain: Table, name: str, given, expected, scale: float) -> None:
    """Record a problem if ``domain.<name>`` differs from the mesh's value."""
    if given is None or all(
        abs(g - e) <= DOMAIN_RTOL * scale for g, e in zip(given, expected, strict=True)
    ):
        return
    domain.error(
        name,
        f"disagrees with mesh.x / mesh.y: expected "
        f"[{exact(expected[0])}, {exact(expected[1])}], got "
        f"[{exact(given[0])}, {exact(given[1])}] (or leave [domain] out)",
    )


def _mesh_from_axes(mesh: Table, domain: Table | None, size, origin) -> Grid | None:
    """Explicit rectilinear mesh; a given [domain] must agree with it."""
    x, y = _read_axis(mesh, "x"), _read_axis(mesh, "y")
    if x is None or y is None:
        return None
    if not check_element_count(x.size - 1, y.size - 1, mesh.key("x"), mesh.problems):
        return None
    x_ok = axis_resolves(x, mesh.key("x"), mesh.problems)
    y_ok = axis_resolves(y, mesh.key("y"), mesh.problems)
    if not (x_ok and y_ok):
        return None
    mesh_origin = (float(x[0]), float(y[0]))
    mesh_size = (float(x[-1] - x[0]), float(y[-1] - y[0]))
    if domain is not None:
        scale = float(max(np.abs(x).max(), np.abs(y).max(), *mesh_size))
        _domain_agrees(domain, "size", size, mesh_size, scale)
        if domain.has("origin"):
            _domain_agrees(domain, "origin", origin, mesh_origin, scale)
    return Grid(mesh_origin, mesh_size, MeshSpec(x=frozen(x), y=frozen(y)))


def _mesh_uniform(mesh: Table, domain: Table | None, size, origin) -> Grid | None:
    """``elements = [nx, ny]`` over ``domain.size``: uniform node coordinates."""
    counts = check_vector(
        mesh.data["elements"],
        mesh.key("elements"),
        mesh.problems,
        2,
        lambda v, k: check_integer(v, k, mesh.problems, Range(1)),
    )
    if domain is not None and not domain.has("size"):
        domain.error("size", "required key missing (mesh.elements needs domain.size)")
    if counts is None or size is None or origin is None:
        return None
    nx, ny = counts
    if not check_element_count(nx, ny, mesh.key("elements"), mesh.problems):
        return None
    with np.errstate(over="ignore"):
        x = origin[0] + size[0] * np.linspace(0.0, 1.0, counts[0] + 1)
        y = origin[1] + size[1] * np.linspace(0.0, 1.0, counts[1] + 1)
    key = domain.key("size") if domain is not None else "domain.size"
    x_ok = axis_resolves(x, key, mesh.problems)
    y_ok = axis_resolves(y, key, mesh.problems)
    if not (x_ok and y_ok):
        return None
    return Grid(origin, size, MeshSpec(x=frozen(x), y=frozen(y)))


def _read_refine(mesh: Table) -> np.ndarray | None:
    """``refine = [[x0, y0, x1, y1], ...]``: boxes with x0 < x1, y0 < y1 [m]."""
    value = mesh.data.get("refine", [])
    if not isinstance(value, list):
        mesh.error(
            "refine", f"expected an array of boxes [x0, y0, x1, y1], got {show(value)}"
        )
        return None
    boxes = []
    for i, box in enumerate(value):
        key = f"{mesh.key('refine')}[{i}]"

        def check(v, k):
            return check_number(v, k, mesh.problems, COORDINATE)

        items = check_vector(box, key, mesh.problems, 4, check)
        if items is not None and not (items[0] < items[2] and items[1] < items[3]):
            mesh.problems.append(
                (key, f"must satisfy x0 < x1 and y0 < y1, got {list(items)}")
            )
            items = None
        boxes.append(items)
    if any(b is None for b in boxes):
        return None
    return frozen(np.array(boxes, dtype=np.float64).reshape(-1, 4))


def _mesh_graded(mesh: Table, domain: Table | None, size, origin) -> Grid | None:
    """``size`` (with growth, max_size, refine): the graded mesh's keys; its
    node coordinates follow once the refinement features are read."""
    start = len(mesh.problems)
    cell = mesh.number("size", REQUIRED, POSITIVE, hint=GRADED_HINT)
    growth = mesh.number("growth", DEFAULT_GROWTH, GROWTH_RANGE)
    largest = mesh.number("max_size", np.inf, POSITIVE)
    refine = _read_refine(mesh)
    if cell is not None and largest is not None and largest < cell:
        mesh.error(
            "max_size", f"must be >= mesh.size = {exact(cell)}, got {exact(largest)}"
        )
    if domain is not None and not domain.has("size"):
        domain.error("size", "required key missing (mesh.size needs domain.size)")
    if len(mesh.problems) > start or size is None or origin is None or refine is None:
        return None
    grading = GradingSpec(size=cell, growth=growth, max_size=largest, refine=refine)
    return Grid(origin, size, None, grading)


GRADED_HINT = " (growth, max_size and refine go with size: a graded mesh)"


def read_grid(root: Table) -> Grid | None:
    """[domain] and [mesh] -> origin, size and node coordinates (the mesh
    None for a graded mesh, see the module docstring)."""
    domain = root.table("domain", ("size", "origin"))
    size = origin = None
    if domain is not None:
        size = domain.numbers("size", 2, None, POSITIVE)
        origin = domain.numbers("origin", 2, (0.0, 0.0))
    mesh = root.table("mesh", MESH_KEYS, required=True)
    if mesh is None:
        return None
    has_axes = mesh.has("x") or mesh.has("y")
    graded = any(mesh.has(k) for k in GRADED_KEYS)
    if mesh.has("elements") and has_axes:
        mesh.error(None, "give either elements = [nx, ny] or x and y, not both")
        return None
    if graded and (mesh.has("elements") or has_axes):
        other = "elements = [nx, ny]" if mesh.has("elements") else "x and y"
        given = ", ".join(k for k in GRADED_KEYS if mesh.has(k))
        mesh.error(
            None,
            f"give either {other} or size (a graded mesh), not both (got {given})",
        )
        return None
    if has_axes:
        return _mesh_from_axes(mesh, domain, size, origin)
    if mesh.has("elements"):
        return _mesh_uniform(mesh, domain, size, origin)
    if graded:
        return _mesh_graded(mesh, domain, size, origin)
    mesh.error(
        None,
        "required key missing: give elements = [nx, ny] (with domain.size), "
        "node coordinates x and y, or size (a graded mesh, with domain.size)",
    )
    return None
