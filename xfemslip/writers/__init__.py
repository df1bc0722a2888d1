"""Output writers: HDF5 (``hdf5.py``) and VTU/PVD (``vtu.py``).

The containers below are what the simulation hands to the writers; they hold
plain arrays in the output sign convention (``output-format.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

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
