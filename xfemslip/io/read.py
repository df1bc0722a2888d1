"""The reader of ``result.h5``: the one place a result file is read back.

``read_result(path)`` returns the :class:`~xfemslip.post.result.Result` that
:func:`xfemslip.run_case` returned for the run that wrote the file, array for
array (``output-format.md``: the element stresses are stored for the final
step only, so the other steps carry None there).  ``read_attrs(path)`` reads
the root attributes alone (whether a sweep member is done, without loading
its fields).  The figures, the sweep summaries, ``dfn --result`` and the tests
go through these two.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import h5py
import numpy as np

from xfemslip.errors import ResultError
from xfemslip.geometry.box import Box
from xfemslip.io.result_check import (
    check_attrs,
    check_final_copy,
    check_layout,
    check_result,
    reading,
)
from xfemslip.post.fields import FractureFields, FractureProperties, StepFields
from xfemslip.post.result import (
    DepletionTable,
    EventTable,
    PermeabilityHistory,
    Result,
)

__all__ = ["FRACTURE_ARRAYS", "read_attrs", "read_result"]

# Datasets of each fracture group read into FractureFields (contact_pressure
# is derived from normal_traction and not kept).
FRACTURE_ARRAYS = (
    "s",
    "points",
    "slip",
    "opening",
    "normal_traction",
    "shear_traction",
    "state",
)
OPTIONAL_FRACTURE_ARRAYS = (
    "plastic_slip",  # not in a result written before it was kept
    "fluid_pressure",
    "effective_normal_traction",
    "aperture",
    "transmissivity",
    "utilisation",
    "accumulated_slip",
    "friction_coefficient",
)
BULK_ARRAYS = ("stress", "stress_zz", "principal_stress")
OPTIONAL_BULK_ARRAYS = ("effective_stress", "pore_pressure")


def _result_file(path: str | Path) -> Path:
    """``path``, or ``path/result.h5`` for a folder; ResultError when missing."""
    path = Path(path)
    if path.is_dir():
        path = path / "result.h5"
    if not path.is_file():
        raise ResultError(f"{path}: no such file (expected a result.h5)")
    return path


def _open(path: Path) -> h5py.File:
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        reason = " ".join(str(exc).split())
        raise ResultError(f"{path}: not a readable result.h5: {reason}") from None


def _plain(value: Any) -> Any:
    """An attribute as Python: NumPy scalars become bool, int, float; arrays
    stay arrays."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, bytes):
        return value.decode("utf-8")
    return value


def read_attrs(path: str | Path) -> dict[str, Any]:
    """The root attributes of a ``result.h5`` (or of ``path/result.h5``).

    Raises ResultError when the file is missing, not HDF5 or damaged.
    """
    path = _result_file(path)
    with _open(path) as h5, reading(path):
        return {key: _plain(value) for key, value in h5.attrs.items()}


def _fractures(group: h5py.Group | None) -> list[FractureFields]:
    """``<group>/fractures/<i>/*`` in the order of ``i`` (case-file index)."""
    if group is None or "fractures" not in group:
        return []
    parent = group["fractures"]
    out = []
    for name in sorted(parent, key=int):
        g = parent[name]
        arrays = {key: g[key][()] for key in FRACTURE_ARRAYS}
        arrays |= {key: g[key][()] for key in OPTIONAL_FRACTURE_ARRAYS if key in g}
        out.append(FractureFields(**arrays))
    return out


def _text(value) -> str:
    """An HDF5 string attribute item as str."""
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


def _properties(h5: h5py.File) -> list[FractureProperties] | None:
    """``/fractures/<i>`` shear_modulus, poisson_ratio and attribute ends of
    every fracture; None when a fracture lacks one (a result written before
    they were kept) or when the file has no fracture."""
    if "fractures" not in h5:
        return None
    parent = h5["fractures"]
    out = []
    for name in sorted(parent, key=int):
        g = parent[name]
        if not {"shear_modulus", "poisson_ratio"} <= set(g) or "ends" not in g.attrs:
            return None
        lo, hi = (float(v) for v in g.attrs["ends"])
        optional = {
            key: g[key][()]
            for key in (
                "in_situ_normal_traction",
                "in_situ_shear_traction",
                "in_situ_utilisation",
            )
            if key in g
        }
        if "breaks" in g.attrs:
            optional["breaks"] = np.asarray(g.attrs["breaks"], float)
            for key in ("units_plus", "units_minus"):
                optional[key] = tuple(_text(v) for v in g.attrs.get(key, ()))
        out.append(
            FractureProperties(
                ends=(lo, hi),
                shear_modulus=g["shear_modulus"][()],
                poisson_ratio=g["poisson_ratio"][()],
                **optional,
            )
        )
    return out


def _bulk(h5: h5py.File) -> dict[str, np.ndarray]:
    fields = h5["fields"]
    arrays = {key: fields[key][()] for key in BULK_ARRAYS}
    arrays |= {key: fields[key][()] for key in OPTIONAL_BULK_ARRAYS if key in fields}
    return arrays


def _steps(h5: h5py.File, attrs: dict) -> list[StepFields]:
    """Every converged step: /steps/<k> with the final one's bulk fields from
    /fields; a one-step run has the root only."""
    if "fields" not in h5:
        return []  # the first load step did not converge
    bulk = _bulk(h5)
    if "steps" not in h5:
        return [
            StepFields(
                step=1,
                load_factor=1.0,
                newton_iterations=int(attrs["newton_iterations"]),
                displacement=h5["fields/displacement"][()],
                fractures=_fractures(h5),
                **bulk,
            )
        ]
    names = sorted(h5["steps"], key=int)
    steps = []
    for name in names:
        group = h5["steps"][name]
        last = name == names[-1]
        empty = dict.fromkeys(BULK_ARRAYS)
        steps.append(
            StepFields(
                step=int(name),
                load_factor=float(group.attrs["load_factor"]),
                newton_iterations=int(group.attrs["newton_iterations"]),
                displacement=group["fields/displacement"][()],
                fractures=_fractures(group),
                **(bulk if last else empty),
            )
        )
    return steps


EVENT_ARRAYS = (
    "slipped",
    "max_slip",
    "slipping_length",
    "moment_per_length",
    "stress_drop",
    "extent",
    "max_slip_increment",
    "moment_per_length_increment",
)


def _events(h5: h5py.File) -> EventTable | None:
    """``/events`` (None in a file written without it, or without one of its
    datasets: the event sizes are then computed from the steps)."""
    if "events" not in h5:
        return None
    g = h5["events"]
    if any(name not in g for name in EVENT_ARRAYS) or "extent_given" not in g.attrs:
        return None
    length = g["slipping_length"][()]
    moment = g["moment_per_length"][()]
    drop = g["stress_drop"][()]
    return EventTable(
        slipped=g["slipped"][()].astype(bool),
        max_slip=g["max_slip"][()],
        slipping_length=length,
        moment_per_length=moment,
        # NaN where the crack model has no slipping length or moment (stored
        # so; a file of an older version holds 0 there)
        stress_drop=np.where((length > 0.0) & (moment > 0.0), drop, np.nan),
        extent=g["extent"][()],
        extent_given=bool(g.attrs["extent_given"]),
        max_slip_increment=g["max_slip_increment"][()],
        moment_per_length_increment=g["moment_per_length_increment"][()],
    )


def _permeability(h5: h5py.File) -> PermeabilityHistory | None:
    """``/permeability`` (None without [permeability])."""
    if "permeability" not in h5:
        return None
    g = h5["permeability"]
    return PermeabilityHistory(
        block=Box.from_corners(*g.attrs["block"]).corners,
        matrix=float(g.attrs["matrix"]),
        in_situ=g["in_situ"][()],
        tensors=g["tensor"][()],
        initial_aperture=g["initial_aperture"][()],
    )


def _depletion(h5: h5py.File) -> DepletionTable | None:
    """``/depletion`` (None unless ``deplete`` wrote the file)."""
    if "depletion" not in h5:
        return None
    g = h5["depletion"]
    return DepletionTable(
        dp_lower=g["dp_lower"][()],
        dp_upper=g["dp_upper"][()],
        x=g["x"][()],
        y=g["y"][()],
        at_singularity=g["first_slip_at_singularity"][()].astype(bool),
        singularity=tuple(_text(v) for v in g.attrs.get("singularity", ())),
        dp_patch=g["dp_patch"][()],
        **{
            name: g[name][()] if name in g else np.full(len(g["dp_patch"]), np.nan)
            for name in (
                "dp_seismic",
                "nucleation_length",
                "x_nucleation",
                "y_nucleation",
            )
        },
        patch_length=float(g.attrs["patch_length"]),
        tolerance=float(g.attrs["tolerance"]),
    )


def read_result(path: str | Path) -> Result:
    """Read a ``result.h5`` (or ``path/result.h5``) into a Result.

    A file whose first load step did not converge gives a Result without
    steps.  Raises ResultError (an OutputError) when the file is missing,
    not HDF5, damaged, or not what the output format says
    (:mod:`xfemslip.io.result_check`).
    """
    path = _result_file(path)
    with _open(path) as h5, reading(path):
        check_layout(h5, path)
        attrs = {key: _plain(value) for key, value in h5.attrs.items()}
        check_attrs(attrs, path)
        for name in ("mesh/points", "mesh/cells"):
            if name not in h5:
                raise ResultError(f"{path}: not a result.h5 of xfemslip (no /{name})")
        try:
            result = Result(
                attrs=attrs,
                points=h5["mesh/points"][()],
                cells=h5["mesh/cells"][()],
                steps=_steps(h5, attrs),
                out_dir=path.parent,
                fracture_properties=_properties(h5),
                events=_events(h5),
                permeability=_permeability(h5),
                depletion=_depletion(h5),
            )
            check_final_copy(h5, path)
        except KeyError:  # a dataset or attribute of the format is missing
            raise ResultError(
                f"{path}: not a result.h5 of xfemslip (a dataset of "
                "output-format.md is missing)"
            ) from None
    check_result(result, path)
    return result
