"""Quantities with units in a case file: ``"25 MPa"``, ``"3 km"``, ``"23 MPa/km"``.

``KEY_DIMENSIONS`` is the one table of what each numeric key of a case file
measures (its key path with the array indices left out); ``convert_units``
replaces every string that starts with a number at such a key by its value in
the key's unit (SI; degrees for angles) before the tables are read, so the
readers see numbers only.  A plain number in the file is left as it is, and a
string at a key that does not measure anything (``"mean"``, ``"traction"``)
is left to its reader.

The number and the unit are converted in decimal arithmetic and rounded once
(``"-25 MPa"`` is the double ``-25e6``, ``"5 mm"`` the double ``0.005``), so a
case written with units gives bitwise the values of the same case written in
SI.  Units are parsed by pint, imported only when a file holds a unit string
(its import and registry take about half a second).
"""

from __future__ import annotations

import re
from decimal import Decimal, InvalidOperation, localcontext
from functools import cache
from typing import Any, NamedTuple

from xfemslip.case.tables import show

__all__ = [
    "DIMENSIONS",
    "KEY_DIMENSIONS",
    "Dimension",
    "convert_units",
    "first_problems",
    "key_value",
    "quantity",
]


class Dimension(NamedTuple):
    """What a key measures: its name in messages, the unit its number is in
    (pint's spelling), and an example of a value with units."""

    name: str
    unit: str
    example: str


DIMENSIONS = {
    "pressure": Dimension("pressure", "Pa", '"25 MPa"'),
    "modulus": Dimension("modulus", "Pa", '"20 GPa"'),
    "length": Dimension("length", "m", '"3 km"'),
    "pressure gradient": Dimension("pressure gradient", "Pa/m", '"23 MPa/km"'),
    "stiffness": Dimension("stiffness per area", "Pa/m", '"5e12 Pa/m"'),
    "density": Dimension("density", "kg/m^3", '"2500 kg/m^3"'),
    "acceleration": Dimension("acceleration", "m/s^2", '"9.81 m/s^2"'),
    "angle": Dimension("angle", "deg", '"30 deg"'),
    "area": Dimension("area (permeability)", "m^2", '"1e-15 m^2"'),
    "per area": Dimension("number per area", "1/m^2", '"0.01 1/m^2"'),
    "per length": Dimension("length per area", "1/m", '"0.1 1/m"'),
    "dimensionless": Dimension("dimensionless number", "", '"60 %"'),
}

_HYDRAULIC = {
    "aperture": "length",
    "dilation_angle": "angle",
    "dilation_slip": "length",
    "max_closure": "length",
    "normal_stiffness": "stiffness",
}
_FRACTURE_PROPERTIES = {
    "friction": "dimensionless",
    "friction.static": "dimensionless",
    "friction.dynamic": "dimensionless",
    "friction.slip_distance": "length",
    "cohesion": "pressure",
    "cohesion.static": "pressure",
    "cohesion.dynamic": "pressure",
    "kn": "stiffness",
    "kt": "stiffness",
    "tip.radius": "length",
    **{f"hydraulic.{k}": v for k, v in _HYDRAULIC.items()},
}
_REGION = {
    "top": "length",
    "base": "length",
    "box": "length",
    "boxes": "length",
    "polygon": "length",
}
_GENERATE = {
    "p20": "per area",
    "p21": "per length",
    "region": "length",
    "min_spacing": "length",
    "min_length": "length",
    "orientation.mean": "angle",
    "orientation.std": "angle",
    "orientation.kappa": "dimensionless",
    "length.value": "length",
    "length.min": "length",
    "length.max": "length",
    "length.median": "length",
    "length.exponent": "dimensionless",
    "length.sigma": "dimensionless",
}
_GENERATE = {
    **_GENERATE,
    "sets.weight": "dimensionless",
    **{f"sets.{k}": v for k, v in _GENERATE.items() if k.startswith(("orie", "len"))},
}

# Key path (array indices left out; an array's items take its key) -> what
# its numbers measure.  Keys of numbers only; integers (counts, steps, seeds)
# and words are not here.
KEY_DIMENSIONS: dict[str, str] = {
    "domain.size": "length",
    "domain.origin": "length",
    "mesh.x": "length",
    "mesh.y": "length",
    "mesh.size": "length",
    "mesh.max_size": "length",
    "mesh.growth": "dimensionless",
    "mesh.refine": "length",
    "material.E": "modulus",
    "material.nu": "dimensionless",
    "material.density": "density",
    "fractures.center": "length",
    "fractures.length": "length",
    "fractures.angle": "angle",
    "fractures.points": "length",
    "fractures.point": "length",
    "fractures.dip": "angle",
    "fractures.top": "length",
    "fractures.base": "length",
    "fractures.fluid_pressure": "pressure",
    **{f"fractures.{k}": v for k, v in _FRACTURE_PROPERTIES.items()},
    **{f"network.{k}": v for k, v in _FRACTURE_PROPERTIES.items()},
    **{f"network.generate.{k}": v for k, v in _GENERATE.items()},
    "loading.stress.xx": "pressure",
    "loading.stress.yy": "pressure",
    "loading.stress.xy": "pressure",
    "loading.initial_stress.xx": "pressure",
    "loading.initial_stress.yy": "pressure",
    "loading.initial_stress.xy": "pressure",
    "loading.initial_stress.datum": "length",
    "loading.initial_stress.gradient_xx": "pressure gradient",
    "loading.initial_stress.gradient_yy": "pressure gradient",
    "loading.initial_stress.ratio_xx": "dimensionless",
    "loading.initial_stress.gravity": "acceleration",
    **{
        f"boundary.{edge}.{c}": "length"
        for edge in ("bottom", "top", "left", "right")
        for c in ("ux", "uy")
    },
    "pore_pressure.initial": "pressure",
    "pore_pressure.change": "pressure",
    "pore_pressure.biot": "dimensionless",
    "pore_pressure.gradient": "pressure gradient",
    "pore_pressure.datum": "length",
    "pore_pressure.field.outside": "pressure",
    "reservoir.E": "modulus",
    "reservoir.nu": "dimensionless",
    **{f"reservoir.{k}": v for k, v in _REGION.items() if k not in ("top", "base")},
    **{f"units.{k}": v for k, v in _REGION.items()},
    "units.offset.throw": "length",
    "units.E": "modulus",
    "units.nu": "dimensionless",
    "units.biot": "dimensionless",
    "units.density": "density",
    "units.change": "pressure",
    "units.change.left": "pressure",
    "units.change.right": "pressure",
    "units.overpressure": "pressure",
    "events.extent": "length",
    "permeability.matrix": "area",
    "permeability.block": "length",
    **{f"permeability.{k}": v for k, v in _HYDRAULIC.items()},
}

# A number at the start of a string marks it as a quantity: "25 MPa", "-3e3 m".
_QUANTITY = re.compile(
    r"\s*(?P<number>[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(?P<unit>.*?)\s*\Z",
    re.DOTALL,
)


@cache
def _registry():
    """pint's unit registry, computing in decimals (imported on first use)."""
    import pint

    return pint.UnitRegistry(non_int_type=Decimal)


def _describe(units) -> str:
    """A name for what ``units`` (pint units) measure, for messages."""
    registry = _registry()
    for dim in DIMENSIONS.values():
        if dim.name in ("modulus", "stiffness per area") or not dim.unit:
            continue
        target = registry.parse_units(dim.unit)
        if units.dimensionality == target.dimensionality:
            if dim.name == "angle" or not _is_angle(units):
                return dim.name
    if _is_angle(units):
        return "angle"
    return f"quantity of dimension {units.dimensionality}"


def _a(name: str) -> str:
    return f"{'an' if name[0] in 'aeiou' else 'a'} {name}"


def _is_angle(units) -> bool:
    registry = _registry()
    return bool(
        units.dimensionless
        and registry.Quantity(Decimal(1), units).to_base_units().units
        == registry.radian
    )


def quantity(text: str, dimension: str) -> tuple[float | None, str | None]:
    """(value, None): ``text`` ("25 MPa") in the unit of ``dimension`` (a key
    of DIMENSIONS), rounded once to the nearest double; or (None, why)."""
    dim = DIMENSIONS[dimension]
    expected = f"expected {_a(dim.name)} such as {dim.example}"
    match = _QUANTITY.fullmatch(text)
    if match is None:
        return None, f"{expected}, got {show(text)}"
    number = Decimal(match["number"])
    unit = match["unit"]
    if not unit:  # a number in quotes is a typing slip, as it always was
        return (
            None,
            f"expected a number, or a string with a unit such as {dim.example}, "
            f"got {show(text)}",
        )
    try:
        registry = _registry()
        units = registry.parse_units(unit)
    except Exception as err:  # pint's and its tokenizer's errors alike
        why = str(err).split("\n", 1)[0] or type(err).__name__
        return None, f"{expected}, got {show(text)} ({why})"
    angle = _is_angle(units)
    target = registry.parse_units(dim.unit) if dim.unit else registry.dimensionless
    if units.dimensionality != target.dimensionality or angle != (dimension == "angle"):
        return None, f"{expected}, got {show(text)} ({_a(_describe(units))})"
    try:
        with localcontext() as context:
            context.prec = 40
            value = registry.Quantity(number, units).to(target).magnitude
        return float(value), None
    except (ArithmeticError, InvalidOperation, OverflowError) as err:
        return None, f"{expected}, got {show(text)} ({type(err).__name__})"


def _pattern(path: str) -> str:
    """The key path with its array indices left out: ``fractures[0].kn`` ->
    ``fractures.kn``."""
    return re.sub(r"\[\d+\]", "", path)


def convert_units(document: dict, problems: list) -> dict:
    """A copy of the parsed case ``document`` with every quantity string at a
    key of KEY_DIMENSIONS replaced by its number; a string of the wrong
    dimension or an unknown unit is recorded in ``problems`` (key path,
    message) and left as it is (its reader's own complaint about the string
    is then dropped by ``first_problems``)."""

    def walk(value: Any, path: str) -> Any:
        if isinstance(value, dict):
            return {
                k: walk(v, f"{path}.{k}" if path else str(k)) for k, v in value.items()
            }
        if isinstance(value, list):
            return [walk(v, f"{path}[{i}]") for i, v in enumerate(value)]
        if not isinstance(value, str) or not _is_quantity(value):
            return value  # a number in quotes is left to its reader's message
        dimension = KEY_DIMENSIONS.get(_pattern(path))
        if dimension is None:
            return value
        number, why = quantity(value, dimension)
        if number is None:
            problems.append((path, why))
            return value
        return number

    if not _has_quantity(document):
        return document
    return walk(document, "")


def _has_quantity(value: Any) -> bool:
    """Whether any string of ``value`` is a number with a unit (only then is
    a copy made and pint imported)."""
    if isinstance(value, dict):
        return any(_has_quantity(v) for v in value.values())
    if isinstance(value, list):
        return any(_has_quantity(v) for v in value)
    return isinstance(value, str) and _is_quantity(value)


def _is_quantity(text: str) -> bool:
    """A number followed by a unit."""
    match = _QUANTITY.fullmatch(text)
    return match is not None and bool(match["unit"])


def key_value(path: str, value: Any) -> tuple[Any, str | None]:
    """(value, None) with a quantity string at the case key ``path``
    (``fractures[0].angle``) converted as a case file's would be, anything
    else unchanged; or (None, why) for a quantity the key refuses."""
    dimension = KEY_DIMENSIONS.get(_pattern(path))
    if dimension is None or not isinstance(value, str) or not _is_quantity(value):
        return value, None
    return quantity(value, dimension)


def first_problems(problems: list) -> list:
    """``problems`` with only the first one of each key path: a unit string
    refused here is also refused by its reader (not a number), and the user
    is told once, why."""
    seen: set = set()
    out = []
    for key, message in problems:
        if key not in seen:
            out.append((key, message))
        seen.add(key)
    return out
