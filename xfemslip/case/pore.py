"""``[pore_pressure]`` -> ``PorePressureSpec``.

The table is optional; a case without it runs exactly as before.  The rock
units (``[[units]]``, ``[reservoir]``) are read in :mod:`xfemslip.case.units`.
"""

from __future__ import annotations

from pathlib import Path

from xfemslip.case.pressure_field import read_field_table
from xfemslip.case.specs import PorePressureSpec
from xfemslip.case.tables import BIOT, Table

PORE_PRESSURE_KEYS = (
    "initial",
    "change",
    "biot",
    "region",
    "gradient",
    "datum",
    "field",
)
PORE_PRESSURE_REGIONS = ("all", "reservoir")


def read_pore_pressure(
    root: Table, in_situ_datum=None, folder: Path = Path()
) -> PorePressureSpec | None:
    """[pore_pressure]: initial [Pa] (at the datum), its ``gradient`` with
    depth [Pa/m] and ``datum`` [m], change [Pa] or a field from a file
    (``[pore_pressure.field]``, its path relative to ``folder``), biot in
    (0, 1], region ("all", "reservoir" or the name of a unit: checked with
    the units)."""
    table = root.table("pore_pressure", PORE_PRESSURE_KEYS)
    if table is None or not table.present:
        return None
    start = len(table.problems)
    initial = table.number("initial")
    field = None
    if table.has("field") and table.has("change"):
        table.error(
            None,
            "give either change (one value) or a field table (values from a "
            "file), not both",
        )
        change = None
    elif table.has("field"):
        change = None
        field = read_field_table(table, folder)
    else:
        change = table.number(
            "change", hint=" (or a field table: [pore_pressure.field] file = ...)"
        )
    biot = table.number("biot", 1.0, BIOT)
    region = table.string("region", "all")
    gradient = table.number("gradient", 0.0)
    datum = table.number("datum", in_situ_datum)
    loading = root.data.get("loading")
    stress = loading.get("initial_stress") if isinstance(loading, dict) else None
    stress_datum = isinstance(stress, dict) and "datum" in stress
    if gradient not in (None, 0.0) and datum is None and not stress_datum:
        table.error(
            "datum",
            "required key missing: a gradient needs the datum, the y [m] of "
            "zero depth (or loading.initial_stress.datum)",
        )
    has_initial = isinstance(loading, dict) and "initial_stress" in loading
    for key, value in (("initial", initial), ("gradient", gradient)):
        if value not in (None, 0.0) and not has_initial:
            table.error(
                key,
                f"= {value!r} needs loading.initial_stress (the in-situ total "
                "stress the initial pore pressure is in equilibrium with)",
            )
    if len(table.problems) > start:
        return None
    return PorePressureSpec(
        initial=initial,
        change=change,
        biot=biot,
        region=region,
        gradient=gradient,
        datum=0.0 if datum is None else datum,
        field=field,
    )


def check_region(root: Table, pore: PorePressureSpec | None, units) -> None:
    """``region`` names "all", "reservoir" (with a [reservoir] or a unit of
    that name) or a unit; with a field from a file, the file gives the
    change everywhere (no region, no unit's own change)."""
    if pore is None:
        return
    if pore.field is not None:
        if pore.region != "all":
            root.problems.append(
                (
                    "pore_pressure.region",
                    "is not used with [pore_pressure.field]: the file gives the "
                    "change everywhere (its outside rule beyond its data)",
                )
            )
        for i, unit in enumerate(units or ()):
            if unit.change is not None or unit.change_sides is not None:
                root.problems.append(
                    (
                        f"units[{i}].change",
                        "the pore-pressure change comes from [pore_pressure.field]; "
                        "leave a unit's change out",
                    )
                )
        return
    names = [u.name for u in units or ()]
    if pore.region == "all" or pore.region in names:
        return
    key = "pore_pressure.region"
    if pore.region == "reservoir":
        root.problems.append(
            (
                key,
                'is "reservoir" but the case has no [reservoir] table (give '
                '[reservoir] box = [x0, y0, x1, y1], or region = "all")',
            )
        )
        return
    choices = ", ".join(repr(n) for n in ["all", *names])
    root.problems.append(
        (key, f"expected one of {choices} (all, or a unit's name), got {pore.region!r}")
    )
