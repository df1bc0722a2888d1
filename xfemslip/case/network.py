"""``[network]``: many fractures from a CSV file of segments and/or a random
network (``[network.generate]``) -> more ``FractureSpec`` entries.

Numbering (``FractureSpec.index``, ``/fractures/<i>`` of result.h5): the
inline ``[[fractures]]`` first, in file order; then the fractures of
``network.file`` in the order of their first row; then the generated ones in
placement order.  ``FractureSpec.source`` says where each came from, and
``xfemslip check`` prints it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from xfemslip.case.fractures import read_tip
from xfemslip.case.friction import read_strength
from xfemslip.case.generate import GENERATE_KEYS, read_generate, realize
from xfemslip.case.grid import Grid
from xfemslip.case.hydraulics import read_hydraulic
from xfemslip.case.segments import PROPERTY_RULES, read_segments_file
from xfemslip.case.specs import FractureSpec
from xfemslip.case.tables import Table, frozen

# the network's own keys, then the properties its fractures take
NETWORK_KEYS = ("file", "generate", *PROPERTY_RULES, "tip", "hydraulic")


def network_table(root: Table) -> Table | None:
    """The [network] table reader (None if not a table)."""
    return root.table("network", NETWORK_KEYS)


def _segments_of(polylines) -> np.ndarray:
    """(m, 2, 2) segments of a list of (k, 2) polylines."""
    parts = [np.stack([p[:-1], p[1:]], axis=1) for p in polylines]
    return np.concatenate(parts) if parts else np.zeros((0, 2, 2))


def read_network(
    root: Table, grid: Grid | None, folder: Path, inline: tuple
) -> tuple[FractureSpec, ...] | None:
    """``[network]``: the CSV file's fractures, then the generated ones,
    numbered after the ``inline`` [[fractures]] (which, with the file's,
    the generated ones keep away from under intersections = "avoid")."""
    first_index = len(inline)
    table = network_table(root)
    if table is None:
        return None
    if not table.present:
        return ()
    start = len(table.problems)
    strength = read_strength(table, friction_default=None, cohesion_default=None)
    defaults = {"friction": strength.friction, "cohesion": strength.cohesion}
    defaults |= {
        name: table.number(name, None, rule)
        for name, rule in PROPERTY_RULES.items()
        if name not in defaults
    }
    tip, radius = read_tip(table)
    hydraulic = read_hydraulic(table)
    if not table.has("file") and not table.has("generate"):
        table.error(None, 'expected file = "segments.csv" and/or a generate table')
    found: list[tuple[np.ndarray, dict, str]] = []
    if table.has("file"):
        found += read_segments_file(table, grid, folder, defaults) or []
    if table.has("generate"):
        gen = table.table("generate", GENERATE_KEYS)
        params = read_generate(gen) if gen is not None else None
        if (
            params is not None
            and defaults["friction"] is None
            and not table.has("friction")
        ):
            table.error(
                "friction",
                "required key missing: the generated fractures take it from here",
            )
        if params is not None and grid is not None and len(table.problems) == start:
            others = [f.points for f in inline] + [p for p, _, _ in found]
            assert gen is not None  # params were read from it
            network = realize(gen, params, grid, _segments_of(others))
            if network is not None:
                found += [
                    (
                        seg,
                        defaults,
                        f"network.generate #{k} (set {network.set_index[k]})",
                    )
                    for k, seg in enumerate(network.segments)
                ]
    if len(table.problems) > start:
        return None
    return tuple(
        FractureSpec(
            index=first_index + k,
            points=frozen(points),
            friction=props["friction"],
            cohesion=props["cohesion"] if props["cohesion"] is not None else 0.0,
            kn=props["kn"],
            kt=props["kt"],
            tip=tip,
            tip_radius=radius,
            source=source,
            hydraulic=hydraulic,
            weakening=_weakening(strength, props),
        )
        for k, (points, props, source) in enumerate(found)
    )


def _weakening(strength, props):
    """The [network] friction law of one of its fractures: a friction or
    cohesion that its CSV rows give replaces the law's values of it."""
    given = props.get("given", ())
    return strength.weakening(
        friction=props["friction"] if "friction" in given else None,
        cohesion=props["cohesion"] if "cohesion" in given else None,
    )
