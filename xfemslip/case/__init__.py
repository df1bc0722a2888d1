"""Case files (TOML, ``case-format.md`` version 1) -> validated frozen specs.

This package is the ONLY place where user input is validated.
``load_case(path)`` reads a file, collects every problem it finds (each with
its key path) and raises one ``CaseError``; otherwise it returns a
``CaseSpec`` whose fields are resolved to SI values and read-only NumPy
arrays.  Units: m, Pa, Pa/m for penalty stiffnesses; angles in degrees in the
file, converted here and nowhere else.  Stresses: tension positive.

Modules: ``load`` (entry points; ``name``, ``[material]``, ``[loading]``,
``[solver]``, ``[output]``), ``options`` (key tables, ``SOLVER_OPTIONS``),
``specs`` (the frozen spec dataclasses), ``tables`` (typed TOML-table reader,
value checks, messages), ``files`` (capped reading of input files, TOML
nesting cap, path checks), ``grid`` (``[domain]``, ``[mesh]``), ``grading``
(the graded mesh of ``mesh.size``, built around the fractures and region
edges), ``fractures``
(``[[fractures]]`` and polyline checks), ``boundary`` (``[boundary]`` and its
CSV files), ``network``, ``segments`` and ``generate`` (``[network]``: a CSV
file of segments, random networks), ``pore`` (``[pore_pressure]``,
``[reservoir]``), ``pressure_field`` (``[pore_pressure.field]``: pressure
changes from a CSV or VTK file), ``events`` (``[events]``), ``hydraulics``
(``[permeability]``, a fracture's ``hydraulic`` table), ``describe`` (the ``xfemslip
check`` printout) and ``build`` (case text from Python values, for tests and
benchmarks).
"""

from __future__ import annotations

from xfemslip.case.boundary import CSV_HEADER, EDGE_KEYS, EDGE_WORDS
from xfemslip.case.describe import describe
from xfemslip.case.events import EVENTS_KEYS
from xfemslip.case.files import (
    CSV_TOLERANCE,
    MAX_CSV_BYTES,
    MAX_CSV_PROBLEMS,
    MAX_NAME_BYTES,
    MAX_TOML_BYTES,
    MAX_TOML_DEPTH,
    parse_toml,
    path_problem,
    read_text,
)
from xfemslip.case.fractures import FRACTURE_KEYS, TIP_KEYS, TIP_KINDS
from xfemslip.case.grid import BYTES_PER_ELEMENT, DOMAIN_RTOL, MAX_ELEMENTS
from xfemslip.case.hydraulics import HYDRAULIC_KEYS, PERMEABILITY_KEYS
from xfemslip.case.load import load_case, loads_case
from xfemslip.case.options import (
    MATERIAL_MODELS,
    MAX_STEPS,
    OUTPUT_FORMATS,
    SOLVER_OPTIONS,
    STRESS_KEYS,
    TOP_KEYS,
)
from xfemslip.case.pore import PORE_PRESSURE_KEYS, PORE_PRESSURE_REGIONS
from xfemslip.case.specs import (
    EDGES,
    BoundarySpec,
    CaseSpec,
    EdgeSpec,
    EventsSpec,
    FractureSpec,
    HydraulicSpec,
    InSituSpec,
    LoadingSpec,
    MaterialSpec,
    MeshSpec,
    OutputSpec,
    PermeabilitySpec,
    PorePressureSpec,
    RegionSpec,
    ReservoirSpec,
    SolverSpec,
    UnitSpec,
)
from xfemslip.case.tables import Option, Range
from xfemslip.case.units import RESERVOIR_KEYS, UNIT_KEYS
from xfemslip.contact.defaults import AUTO_PENALTY, CONTACT_PATCH_CELLS

__all__ = [
    "AUTO_PENALTY",
    "BYTES_PER_ELEMENT",
    "CONTACT_PATCH_CELLS",
    "CSV_HEADER",
    "CSV_TOLERANCE",
    "DOMAIN_RTOL",
    "EDGES",
    "EDGE_KEYS",
    "EDGE_WORDS",
    "EVENTS_KEYS",
    "FRACTURE_KEYS",
    "HYDRAULIC_KEYS",
    "MATERIAL_MODELS",
    "MAX_CSV_BYTES",
    "MAX_CSV_PROBLEMS",
    "MAX_ELEMENTS",
    "MAX_NAME_BYTES",
    "MAX_STEPS",
    "MAX_TOML_BYTES",
    "MAX_TOML_DEPTH",
    "OUTPUT_FORMATS",
    "PERMEABILITY_KEYS",
    "PORE_PRESSURE_KEYS",
    "PORE_PRESSURE_REGIONS",
    "RESERVOIR_KEYS",
    "SOLVER_OPTIONS",
    "STRESS_KEYS",
    "TIP_KEYS",
    "TIP_KINDS",
    "TOP_KEYS",
    "UNIT_KEYS",
    "BoundarySpec",
    "CaseSpec",
    "EdgeSpec",
    "EventsSpec",
    "FractureSpec",
    "HydraulicSpec",
    "InSituSpec",
    "LoadingSpec",
    "MaterialSpec",
    "MeshSpec",
    "Option",
    "OutputSpec",
    "PermeabilitySpec",
    "PorePressureSpec",
    "Range",
    "RegionSpec",
    "ReservoirSpec",
    "SolverSpec",
    "UnitSpec",
    "describe",
    "load_case",
    "loads_case",
    "parse_toml",
    "path_problem",
    "read_text",
]
