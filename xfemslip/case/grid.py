"""``[domain]`` and ``[mesh]`` -> origin, size and node coordinates (``Grid``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from xfemslip.case.specs import MeshSpec
from xfemslip.case.tables import (
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

# Memory guard: a Q4 element adds 64 stiffness triplets (8 B value + 2 x 8 B
# indices = 1.5 kB) before CSR conversion and factorisation; 2 kB per element
# is a lower bound, so 25 million elements already mean > 50 GB.
MAX_ELEMENTS = 25_000_000
BYTES_PER_ELEMENT = 2048
# Relative agreement of [domain] with mesh.x / mesh.y (rounding of typed values).
DOMAIN_RTOL = 1e-12


class Grid(NamedTuple):
    """Resolved domain and mesh, shared by the checks that need geometry."""

    origin: tuple[float, float]
    size: tuple[float, float]
    mesh: MeshSpec


def _int_text(n: int) -> str:
    """An integer of any size (TOML integers are unbounded, floats are not):
    exact up to 15 digits, else like 1.23e+400."""
    digits = str(n)
    if len(digits) <= 15:
        return digits
    return f"{digits[0]}.{digits[1:3]}e+{len(digits) - 1}"


def _check_element_count(nx: int, ny: int, key: str, problems: list) -> bool:
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
    return coords


@np.errstate(over="ignore")
def _axis_resolves(coords: np.ndarray, key: str, problems: list) -> bool:
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
    return Grid(origin, size, MeshSpec(x=frozen(x), y=frozen(y)))


def read_grid(root: Table) -> Grid | None:
    """[domain] and [mesh] -> origin, size and node coordinates."""
    domain = root.table("domain", ("size", "origin"))
    size = origin = None
    if domain is not None:
        size = domain.numbers("size", 2, None, POSITIVE)
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
