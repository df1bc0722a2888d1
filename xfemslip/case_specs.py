"""Spec dataclasses of a resolved case: ``CaseSpec`` and its parts.

Private helper of :mod:`xfemslip.case`, which stays the ONLY entry point for
validating user input (house style: case.py is the only place user input is
validated); import the public names from ``xfemslip.case``, not from here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

EDGES = ("bottom", "top", "left", "right")


@dataclass(frozen=True, kw_only=True)
class MeshSpec:
    """Rectilinear structured Q4 mesh: node coordinates along x and y."""

    x: np.ndarray  # (nx+1,) float64, strictly increasing [m]
    y: np.ndarray  # (ny+1,) float64, strictly increasing [m]
    UNITS: ClassVar[dict[str, str]] = {"x": "m", "y": "m"}


@dataclass(frozen=True, kw_only=True)
class MaterialSpec:
    E: float  # Young's modulus [Pa]
    nu: float  # Poisson's ratio [-]
    model: str  # "plane_strain" | "plane_stress"
    UNITS: ClassVar[dict[str, str]] = {"E": "Pa", "nu": "-", "model": ""}


@dataclass(frozen=True, kw_only=True)
class FractureSpec:
    index: int  # position in the case file's [[fractures]] array
    points: np.ndarray  # (k, 2) float64 polyline vertices, k >= 2 [m]
    friction: float  # Coulomb coefficient f [-]
    cohesion: float  # c_f [Pa]
    kn: float  # normal penalty [Pa/m]
    kt: float  # tangential penalty [Pa/m]
    tip: str = "branch"  # crack-tip treatment: "branch" | "ramp"
    tip_radius: float | None = None  # branch enrichment radius [m]; None = automatic
    UNITS: ClassVar[dict[str, str]] = {
        "points": "m",
        "tip_radius": "m",
        "friction": "-",
        "cohesion": "Pa",
        "kn": "Pa/m",
        "kt": "Pa/m",
    }


@dataclass(frozen=True, kw_only=True)
class LoadingSpec:
    stress: tuple[float, float, float] | None  # final far-field (xx, yy, xy) [Pa]
    initial_stress: tuple[float, float, float] | None  # in-situ (xx, yy, xy) [Pa]
    steps: int
    UNITS: ClassVar[dict[str, str]] = {
        "stress": "Pa",
        "initial_stress": "Pa",
        "steps": "-",
    }


@dataclass(frozen=True, kw_only=True)
class EdgeSpec:
    """One edge's boundary condition.

    kind: "traction" (traction = loading.stress . n), "free" (no traction), or
    "displacement".  For "displacement": ``values`` holds the prescribed final
    displacement at every node of the edge, ordered by increasing coordinate
    along the edge (shape (n_edge_nodes, 2), NaN where a component is free);
    ``traction`` says whether the free component carries loading.stress . n.
    ``source`` is "table" or the CSV file's path; for an edge left out of
    ``[boundary]`` (hence "free") it is "default".
    """

    kind: str
    values: np.ndarray | None = None  # (n_edge_nodes, 2) float64 [m], NaN = free
    traction: bool = False
    source: str = ""
    UNITS: ClassVar[dict[str, str]] = {"values": "m"}


@dataclass(frozen=True, kw_only=True)
class BoundarySpec:
    bottom: EdgeSpec
    top: EdgeSpec
    left: EdgeSpec
    right: EdgeSpec


@dataclass(frozen=True, kw_only=True)
class SolverSpec:
    tolerance: float = 1.0e-8  # eta_0 on ||residual|| / ||F_ext||
    max_iterations: int = 30  # Newton iterations per load step
    tangent: str = "consistent"  # "consistent" | "secant" (paper eq. 28)
    linear_solver: str = "auto"  # "auto" | "superlu" | "amg" (xfemslip.linsolve)
    UNITS: ClassVar[dict[str, str]] = {
        "tolerance": "-",
        "max_iterations": "-",
        "tangent": "",
        "linear_solver": "",
    }


@dataclass(frozen=True, kw_only=True)
class OutputSpec:
    directory: Path  # resolved: output.directory, else out/<name> (relative to cwd)
    formats: tuple[str, ...] = ("h5", "vtu")


@dataclass(frozen=True, kw_only=True)
class CaseSpec:
    path: Path  # the case file
    text: str  # the case file's text as read
    name: str
    origin: tuple[float, float]  # lower-left corner [m]
    size: tuple[float, float]  # width, height [m]
    mesh: MeshSpec
    material: MaterialSpec
    fractures: tuple[FractureSpec, ...] = field(default_factory=tuple)
    loading: LoadingSpec
    boundary: BoundarySpec
    solver: SolverSpec
    output: OutputSpec
