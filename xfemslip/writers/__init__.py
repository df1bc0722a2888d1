"""Output writers: HDF5 (``hdf5.py``) and VTU/PVD (``vtu.py``).

The containers below are what the simulation hands to the writers; they hold
plain arrays in the output sign convention (``output-format.md``).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields

import numpy as np


@dataclass
class FractureFields:
    """Contact fields of one fracture at its K integration points, sorted by s."""

    s: np.ndarray  # (K,) arc length from the first point [m]
    points: np.ndarray  # (K, 2) [m]
    slip: np.ndarray  # (K,) [[u]].t [m]
    opening: np.ndarray  # (K,) [[u]].n [m]
    normal_traction: np.ndarray  # (K,) p_N [Pa], compression negative
    shear_traction: np.ndarray  # (K,) p_T along t [Pa]
    state: np.ndarray  # (K,) int8: 0 open, 1 stick, 2 slip
    # with [pore_pressure] only (xfemslip.poro); normal_traction is then total
    fluid_pressure: np.ndarray | None = None  # (K,) p_f [Pa]
    effective_normal_traction: np.ndarray | None = None  # (K,) p_N + p_f [Pa]


@dataclass
class StepFields:
    """Fields of one converged load step."""

    step: int  # 1-based
    load_factor: float  # lambda in (0, 1]
    newton_iterations: int
    displacement: np.ndarray  # (N, 2) [m]
    stress: np.ndarray  # (M, 3) [Pa] element average sxx, syy, sxy
    stress_zz: np.ndarray  # (M,) [Pa]
    principal_stress: np.ndarray  # (M, 2) [Pa] s_max, s_min
    fractures: list[FractureFields] = field(default_factory=list)
    # with [pore_pressure] only (xfemslip.poro)
    effective_stress: np.ndarray | None = None  # (M, 3) sigma + alpha p I [Pa]
    pore_pressure: np.ndarray | None = None  # (M,) [Pa]


@dataclass
class VisMesh:
    """Bulk mesh for ParaView with cut elements split along the fractures.

    Uncut elements are quads on shared points; each cut element is replaced by
    triangles on points of its own, so the displacement can jump across the
    fracture.  ``*_cell`` maps every vis cell to its bulk element (for cell data).
    """

    points: np.ndarray  # (P, 2) [m]
    displacement: np.ndarray  # (P, 2) [m]
    quads: np.ndarray  # (Q, 4) int64
    quad_cell: np.ndarray  # (Q,) int64
    triangles: np.ndarray  # (T, 3) int64
    triangle_cell: np.ndarray  # (T,) int64


# Root attributes that hold a time, so differ between runs of the same case.
TIMED_ATTRS = ("wall_time_s",)


def run_id(
    attrs: Mapping[str, object],
    points: np.ndarray,
    cells: np.ndarray,
    steps: Sequence[StepFields],
) -> int:
    """The ``run_id`` every file of one output set carries (output-format.md).

    A digest (SHA-256, first 63 bits as a non-negative int64) of the root
    attributes except the timed ones (the case text among them), the mesh and
    every array of every step.  Files of one run share it; two runs share it
    only when they wrote the same numbers, so files stamped alike never show
    different results, and the same input gives the same bytes.
    """
    digest = hashlib.sha256()

    def add(name: str, value) -> None:
        array = np.ascontiguousarray(value)
        digest.update(f"{name}:{array.dtype.str}:{array.shape};".encode())
        digest.update(array.tobytes())

    for key in sorted(attrs):
        if key not in TIMED_ATTRS and key != "run_id":
            add(f"attr {key}", attrs[key])
    add("points", points)
    add("cells", cells)
    for step in steps:
        for item in fields(step):
            value = getattr(step, item.name)
            if item.name == "fractures":
                for index, fracture in enumerate(value):
                    for part in fields(fracture):
                        data = getattr(fracture, part.name)
                        if data is not None:
                            add(f"{step.step} {index} {part.name}", data)
            elif value is not None:
                add(f"{step.step} {item.name}", value)
    return int.from_bytes(digest.digest()[:8], "big") >> 1
