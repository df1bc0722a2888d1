"""``Result``: what a run gives back, in memory or read back from ``result.h5``.

:func:`xfemslip.run_case` returns one without reading a file, and
:func:`xfemslip.read_result` reads one from ``result.h5``; both hold the same
arrays (``output-format.md``):

- ``attrs``: the root attributes of ``result.h5`` (``format_version``,
  ``xfemslip_version``, ``case_toml``, ``converged``, ``load_steps``,
  ``newton_iterations``, ``newton_iterations_per_step``,
  ``load_step_cuts_per_step``, ``wall_time_s``, ``tangent``,
  ``contact_patch_cells``, ``n_dofs``, ``kernels``, ``status_codes``,
  ``run_id``) as Python scalars, strings and NumPy arrays;
- ``points`` (N, 2) [m] and ``cells`` (M, 4) of the mesh;
- ``steps``: a :class:`~xfemslip.post.fields.StepFields` per converged load
  step, in order: displacement (N, 2) [m], the fields of every fracture
  (``s``, ``points``, ``slip``, ``opening``, ``normal_traction``,
  ``shear_traction``, ``state``, ``plastic_slip``), and the element stresses;
- ``fracture_properties``: per fracture its ends and the shear modulus and
  Poisson's ratio at its contact points
  (:class:`~xfemslip.post.fields.FractureProperties`).  ``result.h5``
  keeps the element stresses of the final step only, so in a result read
  back they are None for the other steps.

``run_id`` is the digest every file of one output set carries.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from xfemslip.post.fields import FractureFields, FractureProperties, StepFields

__all__ = [
    "TIMED_ATTRS",
    "DepletionTable",
    "EventTable",
    "PermeabilityHistory",
    "Result",
    "run_id",
]


@dataclass
class EventTable:
    """The event size of every fracture at every converged step
    (:mod:`xfemslip.post.events`): arrays (S, F), S steps by F fractures."""

    slipped: np.ndarray  # bool: a contact point in state slip
    max_slip: np.ndarray  # max |slip| that slid (plastic_slip) [m]
    slipping_length: np.ndarray  # [m]
    moment_per_length: np.ndarray  # M0' [N m / m]
    stress_drop: np.ndarray  # moment-equivalent crack drop [Pa]; NaN: undefined
    extent: np.ndarray  # the W of the magnitude [m]
    extent_given: bool  # W is events.extent (else each slipping length)
    # of each step alone (its slip minus the step before's; in situ: 0)
    max_slip_increment: np.ndarray  # [m]
    moment_per_length_increment: np.ndarray  # [N m / m]


@dataclass
class PermeabilityHistory:
    """The equivalent permeability tensor of the block
    (:mod:`xfemslip.post.hydraulics`): in situ and after each converged step."""

    block: tuple[float, float, float, float]  # x0, y0, x1, y1 [m]
    matrix: float  # k_m [m^2]
    in_situ: np.ndarray  # (2, 2) [m^2]
    tensors: np.ndarray  # (S, 2, 2) [m^2]
    initial_aperture: np.ndarray  # (F,) a0 of each fracture [m]

    def ratio(self, step: int = -1) -> np.ndarray:
        """(k_xx, k_yy) after ``step`` over their in-situ values."""
        k = np.array([self.tensors[step][0, 0], self.tensors[step][1, 1]])
        k0 = np.diag(self.in_situ)
        # NaN where the in-situ value is 0 (no matrix, no fracture along x)
        return np.divide(k, k0, out=np.full(2, np.nan), where=k0 > 0.0)


@dataclass
class DepletionTable:
    """What ``xfemslip deplete`` found per fracture (:mod:`xfemslip.studies.
    depletion`): arrays (F,) in case order, NaN where it did not happen."""

    dp_lower: np.ndarray  # last stuck pore-pressure change [Pa]
    dp_upper: np.ndarray  # first slipping one [Pa]
    x: np.ndarray  # first slipping patch [m]
    y: np.ndarray
    at_singularity: np.ndarray  # bool: first slip at or next to a singular point
    singularity: tuple[str, ...]  # what it is ("" when not)
    dp_patch: np.ndarray  # the slipping length first reaches patch_length [Pa]
    # slip-weakening friction: equilibrium lost (a seismic event nucleates)
    dp_seismic: np.ndarray  # [Pa]
    nucleation_length: np.ndarray  # [m]
    x_nucleation: np.ndarray  # [m]
    y_nucleation: np.ndarray
    patch_length: float  # [m]; NaN when not asked for
    tolerance: float  # of the bisections [Pa]

    @property
    def dp_critical(self) -> np.ndarray:
        return 0.5 * (self.dp_lower + self.dp_upper)


@dataclass
class Result:
    """A run's mesh, the fields of its converged load steps and its attributes.

    The properties give the attributes a run summary reports (``converged``,
    ``load_steps``, ``newton_iterations`` ...) and the fields of the final
    step (``displacement``, ``stress``, ``fractures`` ...).
    """

    attrs: dict[str, Any]
    points: np.ndarray  # (N, 2) [m]
    cells: np.ndarray  # (M, 4) int64
    steps: list[StepFields] = field(default_factory=list)
    # the folder the output set was written to (None: nothing written)
    out_dir: Path | None = None
    # of the case (not in run_id: the case text is): per fracture its ends and
    # elastic constants at its contact points (None: written without them)
    fracture_properties: list[FractureProperties] | None = None
    # derived from the steps and the case (not in run_id): the event sizes,
    # and the block's permeability with [permeability]
    events: EventTable | None = None
    permeability: PermeabilityHistory | None = None
    depletion: DepletionTable | None = None  # written by deplete

    @property
    def converged(self) -> bool:
        return bool(self.attrs["converged"])

    @property
    def load_steps(self) -> int:
        return int(self.attrs["load_steps"])

    @property
    def newton_iterations(self) -> int:
        return int(self.attrs["newton_iterations"])

    @property
    def iterations_per_step(self) -> list[int]:
        """Newton iterations of each converged step."""
        return [int(n) for n in self.attrs["newton_iterations_per_step"]]

    @property
    def wall_time_s(self) -> float:
        return float(self.attrs["wall_time_s"])

    @property
    def n_dofs(self) -> int:
        return int(self.attrs["n_dofs"])

    @property
    def run_id(self) -> int:
        return int(self.attrs["run_id"])

    @property
    def final(self) -> StepFields | None:
        """The last converged step (None when no step converged)."""
        return self.steps[-1] if self.steps else None

    @property
    def displacement(self) -> np.ndarray:
        """(N, 2) [m] nodal displacement of the final step."""
        return self._final().displacement

    @property
    def stress(self) -> np.ndarray:
        """(M, 3) [Pa] element-average sxx, syy, sxy of the final step."""
        stress = self._final().stress
        assert stress is not None  # the final step keeps its stresses
        return stress

    @property
    def principal_stress(self) -> np.ndarray:
        """(M, 2) [Pa] s_max, s_min of the final step."""
        principal = self._final().principal_stress
        assert principal is not None  # the final step keeps its stresses
        return principal

    @property
    def fractures(self) -> list[FractureFields]:
        """The fracture fields of the final step, by case-file index."""
        return self._final().fractures

    def _final(self) -> StepFields:
        if not self.steps:
            raise ValueError("the result holds no converged load step")
        return self.steps[-1]


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
