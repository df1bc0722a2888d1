"""The case text of what runs: a spec changed in Python records its own text.

``loads_case`` stamps every ``CaseSpec`` with a digest of its values
(``CaseSpec.loaded``).  A spec changed afterwards with
``dataclasses.replace`` keeps the stamp and the text of the file it came
from, so its digest no longer matches; :func:`case_of_record` then writes
the changed values into the file's tables (``build.with_keys``), reads the
new text back and checks that it gives exactly the spec that runs.  That
text (and the ``run_id`` made from it) is what ``result.h5`` records.

Values that a few keys cannot say (a changed mesh, boundary, rock unit,
fracture geometry from ``[network]``...) are refused with a message naming
them: change the case's tables with ``with_keys`` and load them instead.
"""

from __future__ import annotations

import dataclasses
import tomllib
from typing import Any

import numpy as np

from xfemslip.case.build import case_text, stress_table, with_keys
from xfemslip.case.load import loads_case
from xfemslip.case.specs import NOT_VALUES, CaseSpec, digest, digest_of
from xfemslip.errors import CaseError, UsageError

__all__ = ["case_of_record"]


def _fracture_keys(i: int, new, old) -> dict[str, Any]:
    """Dotted keys of fractures[i] that say what changed in it."""
    keys: dict[str, Any] = {}
    for name in ("friction", "cohesion", "kn", "kt", "fluid_pressure"):
        if getattr(new, name) != getattr(old, name):
            keys[f"fractures.{i}.{name}"] = getattr(new, name)
    if not np.array_equal(new.points, old.points):
        keys[f"fractures.{i}.points"] = new.points
        for name in ("center", "length", "angle", "point", "dip", "dip_direction"):
            keys[f"fractures.{i}.{name}"] = None
        keys[f"fractures.{i}.top"] = keys[f"fractures.{i}.base"] = None
    return keys


def _keys(field: str, new, old) -> dict[str, Any] | None:
    """Dotted keys that set ``field`` of a CaseSpec from ``old`` to ``new``,
    or None when a few keys cannot say it."""
    if field == "name":
        return {"name": new}
    if field == "material":
        return {
            f"material.{k}": getattr(new, k) for k in ("E", "nu", "model", "density")
        }
    if field == "solver":
        return {
            f"solver.{f.name}": getattr(new, f.name) for f in dataclasses.fields(new)
        }
    if field == "output":
        return {"output.directory": str(new.directory), "output.formats": new.formats}
    if field == "events" and new is not None:
        return {"events.extent": new.extent}
    if field == "loading":
        keys: dict[str, Any] = {
            "loading.stress": stress_table(new.stress),
            "loading.steps": new.steps,
        }
        if new.in_situ is None:
            keys["loading.initial_stress"] = stress_table(new.initial_stress)
        elif new.in_situ != old.in_situ or new.initial_stress != old.initial_stress:
            return None
        return keys
    if field == "pore_pressure" and new is not None and old is not None:
        if new.field is not None or old.field is not None:
            return None
        names = ("initial", "change", "biot", "gradient", "datum", "region")
        return {f"pore_pressure.{k}": getattr(new, k) for k in names}
    if field == "fractures" and len(new) == len(old):
        keys = {}
        for i, (a, b) in enumerate(zip(new, old, strict=True)):
            if digest_of(a) == digest_of(b):
                continue
            if a.source or b.source:  # from [network]: no table of its own
                return None
            keys.update(_fracture_keys(i, a, b))
        return keys
    return None


def case_of_record(spec: CaseSpec) -> CaseSpec:
    """``spec`` with the text of what it holds: itself when its values are
    those its text was loaded into; else the text rewritten with its changed
    values, checked to load back into exactly ``spec``.

    Raises UsageError naming the values no key rewrite reproduces.
    """
    if spec.loaded and spec.loaded == digest(spec):
        return spec
    try:
        base = loads_case(spec.text, spec.path)
    except CaseError as err:
        raise UsageError(f"{spec.path}: the case text no longer loads: {err}") from None
    fields = [
        f.name
        for f in dataclasses.fields(CaseSpec)
        if f.name not in NOT_VALUES
        and digest_of(getattr(spec, f.name)) != digest_of(getattr(base, f.name))
    ]
    if not fields:
        return dataclasses.replace(spec, loaded=digest(spec))
    keys: dict[str, Any] = {}
    refused = []
    for name in fields:
        found = _keys(name, getattr(spec, name), getattr(base, name))
        if found is None:
            refused.append(name)
        else:
            keys.update(found)
    if not refused:
        text = case_text(with_keys(tomllib.loads(spec.text), **keys))
        again = loads_case(text, spec.path)
        if digest(again) == digest(spec):
            return dataclasses.replace(spec, text=text, loaded=digest(spec))
        refused = [
            name
            for name in fields
            if digest_of(getattr(again, name)) != digest_of(getattr(spec, name))
        ] or fields
    raise UsageError(
        f"{spec.path}: the CaseSpec was changed in Python in "
        f"{', '.join(refused)}, which no case text of it says; change the case's "
        "tables with xfemslip.case.build.with_keys and load them with loads_case"
    )
