"""``[permeability]`` and the ``hydraulic`` table of a fracture: the aperture
law of each fracture and the block whose permeability tensor is reported.

``[permeability]`` holds the defaults of every fracture's law (``aperture``,
``dilation_angle``, ``dilation_slip``, ``max_closure``, ``normal_stiffness``;
:mod:`xfemslip.post.permeability`), the ``matrix`` permeability and the
``block`` = [x0, y0, x1, y1] the tensor is upscaled over (default the
domain).  ``[[fractures]] hydraulic = { ... }`` and ``[network] hydraulic =
{ ... }`` override the defaults key by key.  A fracture's law must end up
complete and consistent: an aperture, ``max_closure <= aperture`` (so the
aperture stays positive) and a ``normal_stiffness`` when ``max_closure > 0``.
Without the table nothing hydraulic is computed, and a ``hydraulic`` table is
refused (it would be silently ignored).
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.case.specs import HydraulicSpec, PermeabilitySpec
from xfemslip.case.tables import NON_NEGATIVE, POSITIVE, Range, Table, complete, fmt
from xfemslip.geometry.box import Box

__all__ = [
    "HYDRAULIC_KEYS",
    "LAW_RULES",
    "MATRIX",
    "PERMEABILITY_KEYS",
    "read_hydraulic",
    "read_permeability",
]

HYDRAULIC_KEYS = (
    "aperture",
    "dilation_angle",
    "dilation_slip",
    "max_closure",
    "normal_stiffness",
)
PERMEABILITY_KEYS = (*HYDRAULIC_KEYS, "matrix", "block")
# Physical bounds (docs/case-format.md): an aperture from a nanometre (below
# it water does not flow as a continuum) to a metre (a void, not a fracture
# the cubic law describes), so a0^3 / 12 is a normal number; a normal
# stiffness far beyond measured rock joints on either side, within which the
# closure law neither underflows (0 / 0 at zero stress) nor overflows; a
# matrix permeability up to above that of gravel.
MIN_APERTURE, MAX_APERTURE = 1e-9, 1.0  # [m]
MIN_NORMAL_STIFFNESS, MAX_NORMAL_STIFFNESS = 1e3, 1e16  # [Pa/m]
MAX_MATRIX = 1e-6  # [m^2]
LAW_RULES = {
    "aperture": Range(MIN_APERTURE, MAX_APERTURE),
    "dilation_angle": Range(0.0, 90.0, hi_open=True),
    "dilation_slip": POSITIVE,
    "max_closure": NON_NEGATIVE,
    "normal_stiffness": Range(MIN_NORMAL_STIFFNESS, MAX_NORMAL_STIFFNESS),
}
MATRIX = Range(0.0, MAX_MATRIX)


def _law(table: Table) -> HydraulicSpec:
    """The keys of a law that ``table`` gives (None for the others)."""
    return HydraulicSpec(
        **{name: table.number(name, None, rule) for name, rule in LAW_RULES.items()}
    )


def read_hydraulic(parent: Table) -> HydraulicSpec | None:
    """``hydraulic = { ... }`` of a fracture or of ``[network]``: the keys it
    overrides (None without the key; problems are recorded in ``parent``)."""
    if not parent.has("hydraulic"):
        return None
    table = parent.table("hydraulic", HYDRAULIC_KEYS)
    if table is None:
        return None
    return _law(table)


def _where(fracture) -> str:
    """Key path of a fracture's ``hydraulic`` table."""
    return (
        "network.hydraulic"
        if fracture.source
        else f"fractures[{fracture.index}].hydraulic"
    )


def _resolve(defaults: HydraulicSpec, fracture, root: Table) -> HydraulicSpec | None:
    """The complete law of ``fracture``: its overrides, then the defaults."""
    own = fracture.hydraulic or HydraulicSpec()
    values, keys = {}, {}
    for name in HYDRAULIC_KEYS:
        value = getattr(own, name)
        keys[name] = f"{_where(fracture)}.{name}"
        if value is None:
            value = getattr(defaults, name)
            keys[name] = f"permeability.{name}"
        values[name] = value
    start = len(root.problems)
    if values["aperture"] is None:
        root.error(
            "permeability.aperture",
            f"required key missing: fracture {fracture.index} has no aperture "
            f"(give it here or in {_where(fracture)})",
        )
    vm = values["max_closure"] or 0.0
    if values["aperture"] is not None and vm > values["aperture"]:
        root.error(
            keys["max_closure"],
            f"must be <= the aperture {fmt(values['aperture'])} m of fracture "
            f"{fracture.index} (the closure would close it), got {vm!r}",
        )
    if vm > 0.0 and values["normal_stiffness"] is None:
        root.error(
            keys["max_closure"],
            f"needs normal_stiffness (Pa/m) for fracture {fracture.index}: the "
            "hyperbolic closure law takes both",
        )
    if len(root.problems) > start:
        return None
    return HydraulicSpec(
        aperture=values["aperture"],
        dilation_angle=values["dilation_angle"] or 0.0,
        dilation_slip=values["dilation_slip"] or math.inf,
        max_closure=vm,
        normal_stiffness=values["normal_stiffness"] or math.inf,
    )


def _read_block(table: Table, grid) -> tuple[float, float, float, float] | None:
    """``block`` = [x0, y0, x1, y1] inside the domain, x0 < x1, y0 < y1."""
    block = table.numbers("block", 4)
    if block is None or grid is None:
        return None
    x0, y0, x1, y1 = block
    lo, hi, size = grid.box.lo, grid.box.hi, grid.size
    if not (x0 < x1 and y0 < y1):
        table.error(
            "block",
            f"expected [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got {list(block)}",
        )
        return None
    tol = 1e-9 * max(size)
    if x0 < lo[0] - tol or y0 < lo[1] - tol or x1 > hi[0] + tol or y1 > hi[1] + tol:
        table.error(
            "block",
            f"must lie inside the domain [{fmt(lo[0])}, {fmt(hi[0])}] x "
            f"[{fmt(lo[1])}, {fmt(hi[1])}], got {list(block)}",
        )
        return None
    # the fractures are resolved cell by cell: a block is upscaled over at
    # least one cell each way (and its area is a normal number)
    dx, dy = float(min(np.diff(grid.mesh.x))), float(min(np.diff(grid.mesh.y)))
    if x1 - x0 < (1.0 - 1e-9) * dx or y1 - y0 < (1.0 - 1e-9) * dy:
        table.error(
            "block",
            f"must be at least one cell of the mesh wide and high ({fmt(dx)} x "
            f"{fmt(dy)} m), got {fmt(x1 - x0)} x {fmt(y1 - y0)} m",
        )
        return None
    return block


def read_permeability(root: Table, grid, fractures) -> PermeabilitySpec | None:
    """[permeability] (None without it; ``fractures`` None when they had
    problems of their own, then only the table's keys are checked)."""
    table = root.table("permeability", PERMEABILITY_KEYS)
    if table is None:
        return None
    if not table.present:
        for fracture in fractures or ():
            if fracture.hydraulic is not None:
                root.error(
                    _where(fracture),
                    "needs a [permeability] table (at least its aperture): "
                    "permeability is computed only when the case has one",
                )
                break
        return None
    start = len(root.problems)
    defaults = _law(table)
    matrix = table.number("matrix", 0.0, MATRIX)
    if table.has("block"):
        block = _read_block(table, grid)
    elif grid is not None:
        block = grid.box.corners
    else:
        block = None
    if len(root.problems) > start or fractures is None or block is None:
        return None
    laws = complete([_resolve(defaults, f, root) for f in fractures])
    if laws is None:
        return None
    return PermeabilitySpec(
        laws=tuple(laws),
        matrix=matrix,
        block=Box.from_corners(*block).corners,
        block_given=table.has("block"),
    )
