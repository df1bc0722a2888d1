"""Spec dataclasses of a resolved case: ``CaseSpec`` and its parts."""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field
from pathlib import Path, PurePath
from typing import Any, ClassVar

import numpy as np

from xfemslip.contact.defaults import CONTACT_PATCH_CELLS
from xfemslip.geometry.box import Box

EDGES = ("bottom", "top", "left", "right")


@dataclass(frozen=True, kw_only=True)
class GradingSpec:
    """``[mesh]`` size, growth, max_size, refine: a graded mesh
    (xfemslip.geometry.grading) refined to ``size`` around the fractures, the
    region edges and the ``refine`` boxes."""

    size: float  # h, the largest cell near a refinement feature [m]
    growth: float  # g, largest ratio of neighbouring cell sizes, 1 < g <= 2 [-]
    max_size: float  # H >= h, the largest cell [m]; inf: no cap
    refine: np.ndarray  # (k, 4) float64 boxes [x0, y0, x1, y1] [m]
    UNITS: ClassVar[dict[str, str]] = {
        "size": "m",
        "growth": "-",
        "max_size": "m",
        "refine": "m",
    }


@dataclass(frozen=True, kw_only=True)
class MeshSpec:
    """Rectilinear structured Q4 mesh: node coordinates along x and y."""

    x: np.ndarray  # (nx+1,) float64, strictly increasing [m]
    y: np.ndarray  # (ny+1,) float64, strictly increasing [m]
    grading: GradingSpec | None = None  # the keys x and y were built from
    UNITS: ClassVar[dict[str, str]] = {"x": "m", "y": "m"}


@dataclass(frozen=True, kw_only=True)
class MaterialSpec:
    E: float  # Young's modulus [Pa]
    nu: float  # Poisson's ratio [-]
    model: str  # "plane_strain" | "plane_stress"
    density: float | None = None  # bulk density [kg/m^3] (with gravity only)
    UNITS: ClassVar[dict[str, str]] = {
        "E": "Pa",
        "nu": "-",
        "model": "",
        "density": "kg/m^3",
    }


@dataclass(frozen=True, kw_only=True)
class HydraulicSpec:
    """The aperture law of a fracture (xfemslip.post.permeability.ApertureLaw).

    In ``[permeability]`` (the defaults) and in a fracture's ``hydraulic``
    table (its overrides) a key may be left out (None); the laws that
    ``PermeabilitySpec.laws`` holds per fracture are complete: ``aperture``
    given, ``dilation_slip`` inf without a cap, ``normal_stiffness`` inf
    without closure.
    """

    aperture: float | None = None  # a0 [m] > 0
    dilation_angle: float | None = None  # psi [deg], 0 <= psi < 90
    dilation_slip: float | None = None  # slip at which dilation stops [m]
    max_closure: float | None = None  # V_m [m], 0 <= V_m <= a0
    normal_stiffness: float | None = None  # K_ni [Pa/m] > 0
    UNITS: ClassVar[dict[str, str]] = {
        "aperture": "m",
        "dilation_angle": "deg",
        "dilation_slip": "m",
        "max_closure": "m",
        "normal_stiffness": "Pa/m",
    }


@dataclass(frozen=True, kw_only=True)
class PermeabilitySpec:
    """[permeability]: the aperture law of every fracture and the block whose
    equivalent permeability tensor is reported (xfemslip.post.hydraulics)."""

    laws: tuple[HydraulicSpec, ...]  # complete, one per fracture (case order)
    matrix: float  # matrix permeability k_m [m^2] >= 0
    block: tuple[float, float, float, float]  # x0, y0, x1, y1 [m]
    block_given: bool = False  # False: the block is the domain
    UNITS: ClassVar[dict[str, str]] = {"matrix": "m^2", "block": "m"}


@dataclass(frozen=True, kw_only=True)
class SlipWeakeningSpec:
    """Linear slip weakening of a fracture's friction and cohesion
    (``friction = { law = "slip_weakening", ... }``; kernels.contact): from
    the static values of ``FractureSpec.friction`` and ``cohesion`` at zero
    accumulated slip to these dynamic ones at ``slip_distance`` of it and
    beyond."""

    dynamic_friction: float  # f_d [-], 0 <= f_d <= f_s
    dynamic_cohesion: float  # c_d [Pa], 0 <= c_d <= c_s (= c_s: no weakening)
    slip_distance: float  # D_c [m] > 0
    UNITS: ClassVar[dict[str, str]] = {
        "dynamic_friction": "-",
        "dynamic_cohesion": "Pa",
        "slip_distance": "m",
    }


@dataclass(frozen=True, kw_only=True)
class FractureSpec:
    index: int  # [[fractures]] position; [network] ones follow (network.py)
    points: np.ndarray  # (k, 2) float64 polyline vertices, k >= 2 [m]
    friction: float  # Coulomb coefficient f [-]
    cohesion: float  # c_f [Pa]
    kn: float | None  # normal penalty [Pa/m]; None = AUTO_PENALTY * E / h
    kt: float | None  # tangential penalty [Pa/m]; None = AUTO_PENALTY * E / h
    tip: str = "branch"  # crack-tip treatment: "branch" | "ramp"
    tip_radius: float | None = None  # branch enrichment radius [m]; None = automatic
    source: str = ""  # "" = [[fractures]]; else where [network] took it from
    hydraulic: HydraulicSpec | None = None  # overrides of [permeability]
    # the fluid pressure in the fracture from the pore pressures on its two
    # faces (xfemslip.fem.zones.FLUID_RULES): "mean" | "higher" | "lower",
    # or a number [Pa] (a sealing fracture holding a pressure of its own)
    fluid_pressure: str | float = "mean"
    # slip weakening of friction (and cohesion); None: constant Coulomb with
    # friction and cohesion above (which are then the static values)
    weakening: SlipWeakeningSpec | None = None
    UNITS: ClassVar[dict[str, str]] = {
        "points": "m",
        "tip_radius": "m",
        "friction": "-",
        "cohesion": "Pa",
        "kn": "Pa/m",
        "kt": "Pa/m",
    }


@dataclass(frozen=True, kw_only=True)
class InSituSpec:
    """An in-situ total stress that varies with depth (``loading.initial_stress``
    with a datum): xfemslip.fem.zones.in_situ_stress.

    Depth is ``datum - y``.  sigma_yy = yy + gradient_yy depth, or with
    ``gravity`` yy - g int rho dz over the rock above (the units' densities);
    sigma_xx = xx + gradient_xx depth, or from ``ratio_xx`` of the effective
    vertical stress (a number, or "uniaxial_strain": nu / (1 - nu) of each
    unit); sigma_xy uniform.
    """

    datum: float  # y of zero depth [m]
    yy: float  # sigma_yy at the datum [Pa]
    gradient_yy: float | None  # d sigma_yy / d depth [Pa/m]; None: gravity
    gravity: float | None  # g [m/s^2] with the densities; None: gradient_yy
    xx: float | None  # sigma_xx at the datum [Pa] (with gradient_xx)
    gradient_xx: float | None  # [Pa/m]
    ratio_xx: float | str | None  # sigma'_xx / sigma'_yy, or "uniaxial_strain"
    xy: float = 0.0  # [Pa]
    UNITS: ClassVar[dict[str, str]] = {
        "datum": "m",
        "yy": "Pa",
        "gradient_yy": "Pa/m",
        "gravity": "m/s^2",
        "xx": "Pa",
        "gradient_xx": "Pa/m",
        "ratio_xx": "-",
        "xy": "Pa",
    }


@dataclass(frozen=True, kw_only=True)
class LoadingSpec:
    stress: tuple[float, float, float] | None  # final far-field (xx, yy, xy) [Pa]
    # uniform in-situ (xx, yy, xy) [Pa]; None with a depth-dependent one
    initial_stress: tuple[float, float, float] | None
    steps: int
    in_situ: InSituSpec | None = None  # in-situ stress varying with depth
    UNITS: ClassVar[dict[str, str]] = {
        "stress": "Pa",
        "initial_stress": "Pa",
        "steps": "-",
    }

    @property
    def has_in_situ(self) -> bool:
        """Whether the model starts from an in-situ stress (uniform or not)."""
        return self.initial_stress is not None or self.in_situ is not None


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
    contact_patch: float = CONTACT_PATCH_CELLS  # patch length [cells]; 0 = pointwise
    max_step_cuts: int = 5  # bisections of a failing load step
    linear_solver: str = "auto"  # "auto" | "superlu" | "amg" | "pardiso" (solve.linear)
    kernels: str = "auto"  # "auto" | "numba" | "numpy" (xfemslip.kernels)
    UNITS: ClassVar[dict[str, str]] = {
        "tolerance": "-",
        "max_iterations": "-",
        "tangent": "",
        "contact_patch": "cells",
        "max_step_cuts": "-",
        "linear_solver": "",
        "kernels": "",
    }


@dataclass(frozen=True, kw_only=True)
class OutputSpec:
    directory: Path  # resolved: output.directory, else out/<name> (relative to cwd)
    formats: tuple[str, ...] = ("h5", "vtu", "csv")


@dataclass(frozen=True, kw_only=True)
class PressureFieldSpec:
    """[pore_pressure.field]: pressure changes dp(x, y) read from a file,
    one field per column (or VTK array), in order (xfemslip.case.pressure_field).

    ``field.values(xy)`` (n, 2) [m] -> (n_fields, n) [Pa] interpolates them
    (xfemslip.geometry.sampled: bilinear on a regular grid, linear on
    triangles, constant per cell for cell data) with the ``outside`` rule.
    """

    file: Path  # resolved against the case file's folder
    columns: tuple[str, ...]  # CSV columns or VTK array names, one per field
    outside: str | float  # "error" | "nearest" | a value [Pa]
    kind: str  # "grid" | "points" | "mesh points" | "mesh cells"
    field: object  # GridField | TriangleField (xfemslip.geometry.sampled)
    UNITS: ClassVar[dict[str, str]] = {"outside": "Pa"}


@dataclass(frozen=True, kw_only=True)
class PorePressureSpec:
    """[pore_pressure]: initial pore pressure and its change (depletion < 0).

    The change ``change`` [Pa] is applied proportionally over the load steps
    (``loading.steps``), in the whole model (``region = "all"``) or inside the
    ``[reservoir]`` only (``region = "reservoir"``).  With ``field`` the
    change is read from a file instead (``change`` is then None).
    """

    initial: float  # p0 [Pa] (at the datum with a gradient)
    change: float | None  # final dp [Pa]; < 0 = depletion; None with field
    biot: float  # alpha, 0 < alpha <= 1 [-]
    region: str  # "all" | "reservoir" | the name of a unit
    gradient: float = 0.0  # d p0 / d depth [Pa/m] (hydrostatic: about 1e4)
    datum: float = 0.0  # y of zero depth [m] (with a gradient)
    field: PressureFieldSpec | None = None  # dp(x, y) from a file
    UNITS: ClassVar[dict[str, str]] = {
        "initial": "Pa",
        "change": "Pa",
        "biot": "-",
        "region": "",
        "gradient": "Pa/m",
        "datum": "m",
    }


@dataclass(frozen=True, kw_only=True)
class ReservoirSpec:
    """[reservoir]: a region of boxes, or one polygon, with its own elastic
    constants.

    ``boxes`` (k, 4) float64 [x0, y0, x1, y1] [m] ((0, 4) with a polygon);
    ``polygon`` (k, 2) float64 vertices [m] or None.  An intact cell belongs
    to the reservoir when its centre lies in the region (xfemslip.fem.poro).
    """

    boxes: np.ndarray  # (k, 4) float64 [m]
    E: float  # [Pa]
    nu: float  # [-]
    polygon: np.ndarray | None = None  # (k, 2) float64 [m]
    # edges moved onto a fracture: (edge name, fracture index, distance [m])
    snapped: tuple[tuple[str, int, float], ...] = ()
    UNITS: ClassVar[dict[str, str]] = {
        "boxes": "m",
        "polygon": "m",
        "E": "Pa",
        "nu": "-",
    }


@dataclass(frozen=True, kw_only=True)
class RegionSpec:
    """Where a rock unit lies (xfemslip.geometry.regions.in_region).

    kind "boxes": ``boxes`` (k, 4) [x0, y0, x1, y1]; "polygon": ``polygon``
    (k, 2); "layer": between the horizons ``base`` < y < ``top``; "offset":
    a layer displaced across a fault: ``top``/``base`` on the side that is
    not lowered, ``top - throw``/``base - throw`` on the ``lowered`` side
    ("left" or "right" of the fault line ``fault`` (k, 2), a copy of the
    points of fracture ``fracture``, extended straight beyond its ends).
    """

    kind: str
    boxes: np.ndarray | None = None  # (k, 4) [m]
    polygon: np.ndarray | None = None  # (k, 2) [m]
    top: float | None = None  # [m]
    base: float | None = None  # [m]
    fault: np.ndarray | None = None  # (k, 2) [m]
    fracture: int | None = None
    throw: float = 0.0  # [m] >= 0
    lowered: str = ""  # "left" | "right"
    UNITS: ClassVar[dict[str, str]] = {
        "boxes": "m",
        "polygon": "m",
        "top": "m",
        "base": "m",
        "throw": "m",
    }

    @property
    def horizons(self) -> tuple[float, float]:
        """(base, top) [m] of a layer, or of a displaced layer on the side that
        is not lowered."""
        if self.base is None or self.top is None:
            raise ValueError(f"a {self.kind!r} region has no horizons")
        return self.base, self.top

    @property
    def vertices(self) -> np.ndarray:
        """(k, 2) vertices [m] of a polygon region."""
        if self.polygon is None:
            raise ValueError(f"a {self.kind!r} region has no polygon")
        return self.polygon

    @property
    def box_array(self) -> np.ndarray:
        """(k, 4) boxes [x0, y0, x1, y1] [m] of a boxes region."""
        if self.boxes is None:
            raise ValueError(f"a {self.kind!r} region has no boxes")
        return self.boxes


@dataclass(frozen=True, kw_only=True)
class UnitSpec:
    """A rock unit ([[units]], or the one [reservoir]): its region and
    constants (resolved: the host's where the case leaves one out).

    Units later in the case override earlier ones where they overlap; the
    host ([material]) is everywhere else.  ``change`` is the unit's
    pore-pressure change at the end of loading [Pa] (None: the rule of
    ``[pore_pressure] region``); an offset unit may give one per side
    (``change_sides`` = (left, right)), its two compartments.
    """

    name: str
    region: RegionSpec
    E: float  # [Pa]
    nu: float  # [-]
    biot: float | None = None  # [-]; None: [pore_pressure] biot
    density: float | None = None  # [kg/m^3]; None: [material] density
    change: float | None = None  # [Pa]
    change_sides: tuple[float, float] | None = None  # (left, right) [Pa]
    overpressure: float = 0.0  # added to the initial pore pressure [Pa]
    # edges moved onto a fracture: (edge name, fracture index, distance [m])
    snapped: tuple[tuple[str, int, float], ...] = ()
    UNITS: ClassVar[dict[str, str]] = {
        "E": "Pa",
        "nu": "-",
        "biot": "-",
        "density": "kg/m^3",
        "change": "Pa",
        "overpressure": "Pa",
    }


@dataclass(frozen=True, kw_only=True)
class EventsSpec:
    """[events]: the out-of-plane extent W of a moment magnitude."""

    extent: float | None = None  # W [m]; None: each fracture's slipping length
    UNITS: ClassVar[dict[str, str]] = {"extent": "m"}


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
    pore_pressure: PorePressureSpec | None = None  # None: no pore pressure
    reservoir: ReservoirSpec | None = None  # None: one material everywhere
    # the rock units: [[units]], or [reservoir] as the unit "reservoir"
    units: tuple[UnitSpec, ...] = ()
    events: EventsSpec | None = None  # None: no [events] table
    permeability: PermeabilitySpec | None = None  # None: no [permeability] table
    # digest of the values as loaded from ``text`` (xfemslip.case.record): a
    # spec changed with dataclasses.replace no longer matches it
    loaded: str = field(default="", compare=False, repr=False)

    @property
    def box(self) -> Box:
        """The domain ([domain] origin and size) [m]."""
        return Box.from_origin_size(self.origin, self.size)


# CaseSpec fields that are not values of the case
NOT_VALUES = ("path", "text", "loaded")


def _feed(h, value: Any) -> None:
    """Hash ``value`` into ``h`` by type and content."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        h.update(type(value).__name__.encode())
        for f in dataclasses.fields(value):
            if f.name not in NOT_VALUES:
                h.update(f.name.encode())
                _feed(h, getattr(value, f.name))
    elif isinstance(value, np.ndarray):
        h.update(f"array{value.dtype.str}{value.shape}".encode())
        h.update(np.ascontiguousarray(value).tobytes())
    elif isinstance(value, list | tuple):
        h.update(f"seq{len(value)}".encode())
        for item in value:
            _feed(h, item)
    elif isinstance(value, dict):
        h.update(f"map{len(value)}".encode())
        for key in sorted(value, key=str):
            _feed(h, key)
            _feed(h, value[key])
    elif value is None or isinstance(value, bool | int | float | str | PurePath):
        h.update(f"{type(value).__name__}:{value!r}".encode())
    elif hasattr(value, "__dict__"):  # a sampled pressure field
        h.update(type(value).__name__.encode())
        _feed(h, vars(value))
    else:
        h.update(repr(value).encode())


def digest(spec: CaseSpec) -> str:
    """A digest of every value of ``spec`` (not its path, text or stamp)."""
    h = hashlib.blake2b(digest_size=16)
    _feed(h, spec)
    return h.hexdigest()


def digest_of(value: Any) -> str:
    """A digest of ``value`` (a spec, a field of one) by type and content."""
    h = hashlib.blake2b(digest_size=16)
    _feed(h, value)
    return h.hexdigest()
